//! `lbvh.*`: a linear BVH built on the GPU from Morton codes (Lauterbach et al. 2009;
//! Karras 2012; Apetrei 2014). Kernels, each under its timer scope:
//! `lbvh.bounds` → `lbvh.morton` → `lbvh.sort` → `lbvh.fit` (the tree and its boxes
//! in one bottom-up pass), or `lbvh.refit` alone when vertices moved but the triangles
//! stayed the same. One layout, the one the traversal reads (`glsl/shared/bvh.glsl`):
//! N-1 internal nodes of 64 bytes holding both children's boxes (`TraversalNode`, root
//! in slot 0) and the triangles in leaf order (`TraversalTri`), each with a link to its
//! box's half of the parent, which the refit climbs. `lbvh.compact` then writes the
//! 32-byte nodes the walk of the static BVH reads (boxes rounded outward to 16 bits).
//! CPU reference: `cpu_ref::lbvh` (every stage exactly; tests/suite/lbvh.rs).

mod bvh;
pub mod dynamic;
mod layout;
pub mod order;
pub mod ploc;
pub mod rigid;
pub mod sort;
mod triangles;

use crate::error::Result;
use crate::gpu_types::TraversalNode;
use crate::shader_defines::{BVH_INVALID, LBVH_BOUNDS_ITEMS, LBVH_WG};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Groups, Pipeline, Resource};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use sort::RadixSort;
use std::sync::atomic::Ordering;
use std::sync::Arc;

pub use bvh::{refit_order, stack_need, wide8_stack_need, wide_stack_need, Bvh, CompactNodes, RefitSchedule};
pub use layout::StaticLayout;
pub use triangles::{index_buffer, Geometry, TriangleTexels, UploadedTriangles, VERTEX_USAGE};

pub const BOUNDS: &str = "lbvh.bounds";
pub const MORTON: &str = "lbvh.morton";
pub const SORT: &str = "lbvh.sort";
pub const FIT: &str = "lbvh.fit";
pub const REFIT: &str = "lbvh.refit";
pub const COMPACT: &str = "lbvh.compact";

/// Most triangles in one BVH: 1D dispatches of LBVH_WG invocations, at most 65535
/// workgroups.
pub const MAX_TRIANGLES: u32 = 65535 * LBVH_WG;
// A leaf's first triangle fits below its count in the child link.
const _: () = assert!(MAX_TRIANGLES <= 1 << crate::shader_defines::BVH_LEAF_COUNT_SHIFT);

// A tree over one-word keys (32 bits) and MAX_TRIANGLES leaves is at most 32 +
// ceil(log2 MAX_TRIANGLES) deep; the binary walk holds at most one pending child per
// level, the wide walk WIDE - 1 per two levels, the compressed one WIDE8 - 1 per
// three: their stack can never overflow in the
// frame (see TRACE_STACK).
const MAX_DEPTH: u32 = 32 + (MAX_TRIANGLES - 1).ilog2() + 1;
const _: () = assert!(MAX_DEPTH <= crate::shader_defines::TRACE_STACK);
const _: () = assert!((crate::shader_defines::WIDE - 1) * MAX_DEPTH.div_ceil(2) <= crate::shader_defines::TRACE_STACK);
const _: () = assert!((crate::shader_defines::WIDE8 - 1) * MAX_DEPTH.div_ceil(3) <= crate::shader_defines::TRACE_STACK);

/// Morton code width: 30 bits (10 per axis, one word) or 63 bits (21 per axis, two
/// words). 63-bit codes separate close centroids in large scenes at twice the sort time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MortonBits {
    #[serde(rename = "30")]
    Bits30,
    #[serde(rename = "63")]
    Bits63,
}

impl MortonBits {
    pub const ALL: [MortonBits; 2] = [MortonBits::Bits30, MortonBits::Bits63];

    /// Bits per code, as the CLI and reports name the width.
    pub fn bits(self) -> u32 {
        match self {
            MortonBits::Bits30 => 30,
            MortonBits::Bits63 => 63,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            MortonBits::Bits30 => "30",
            MortonBits::Bits63 => "63",
        }
    }

    pub fn about(self) -> &'static str {
        match self {
            MortonBits::Bits30 => "10 bits per axis, one key word",
            MortonBits::Bits63 => "21 bits per axis, two key words: close centroids apart, twice the sort time",
        }
    }

    pub fn key_words(self) -> u32 {
        match self {
            MortonBits::Bits30 => 1,
            MortonBits::Bits63 => 2,
        }
    }
}

/// How a BVH's tree is made from the sorted keys: the LBVH's radix tree (`lbvh.fit`:
/// the fastest build, a looser tree) or PLOC's clustering (`lbvh.ploc`: a tree close to
/// binned SAH, a slower build), for geometry built once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BvhKind {
    Lbvh,
    Ploc,
}

impl BvhKind {
    pub const ALL: [BvhKind; 2] = [BvhKind::Lbvh, BvhKind::Ploc];

    pub fn name(self) -> &'static str {
        match self {
            BvhKind::Lbvh => "lbvh",
            BvhKind::Ploc => "ploc",
        }
    }

    pub fn about(self) -> &'static str {
        match self {
            BvhKind::Lbvh => "the LBVH's radix tree with SAH-chosen leaves: the fastest build, a looser tree",
            BvhKind::Ploc => "PLOC's clustering after the same sort: a tree close to binned SAH, a slower build",
        }
    }

    /// The timer scope of the stage that makes the tree.
    pub const fn tree_scope(self) -> &'static str {
        match self {
            BvhKind::Lbvh => FIT,
            BvhKind::Ploc => ploc::PLOC,
        }
    }

    /// The timer scopes of a build, in build order.
    pub const fn stages(self) -> [&'static str; 4] {
        [BOUNDS, MORTON, SORT, self.tree_scope()]
    }
}

/// Whether `lbvh.fit` must climb in workgroup lockstep: on lavapipe before Mesa 25
/// (Mesa 22.3 treats a memory barrier in divergent control flow like a workgroup
/// barrier and loses invocations; the free climb is tested on Mesa 25 only). Every
/// other driver climbs freely.
pub fn lockstep_fit(driver_name: &str, driver_info: &str) -> bool {
    if driver_name != "llvmpipe" {
        return false;
    }
    let major = driver_info
        .strip_prefix("Mesa ")
        .and_then(|v| v.split('.').next())
        .and_then(|m| m.parse::<u32>().ok());
    major.is_none_or(|m| m < 25)
}

/// Push constants of `lbvh_compact.comp`: the binary nodes, and the layout's children
/// a node (`StaticLayout::slots`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CompactPush {
    node_count: u32,
    slots: u32,
}

/// Push constants of `lbvh_morton.comp` (`lbvh.bounds` and the refit push the triangle
/// count alone, as a `u32`; the fit `FitPush`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct KeyPush {
    tri_count: u32,
    /// 1: 30-bit Morton codes, 2: 63-bit.
    key_words: u32,
}

/// Push constants of `lbvh_fit.comp`: `KeyPush`'s, and whether it writes the order
/// counts (`Bvh::counts`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FitPush {
    tri_count: u32,
    key_words: u32,
    order: u32,
}

/// The LBVH kernels.
pub struct LbvhBuilder {
    ctx: Arc<Context>,
    bounds: Pipeline,
    morton: Pipeline,
    pub sort: RadixSort,
    /// The sort's steps each timed under its scope (`sort::STEPS`, `bench lbvh`): a
    /// timestamp and its barrier between each of a build's dispatches of the sort.
    pub time_sort_steps: bool,
    fit: Pipeline,
    refit_leaves: Pipeline,
    refit_level: Pipeline,
    refit_top: Pipeline,
    compact: Pipeline,
    order: order::OrderKernels,
    pub ploc: ploc::PlocBuilder,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RangePush {
    first: u32,
    count: u32,
    tri_count: u32,
}

impl LbvhBuilder {
    /// The kernels, the fit's climb chosen for the driver (`lockstep_fit`).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let lockstep = ctx
            .lockstep_fit
            .unwrap_or_else(|| lockstep_fit(&ctx.driver_name, &ctx.driver_info));
        Self::with_fit(ctx, lockstep)
    }

    /// The kernels with the fit climbing in lockstep or freely, whatever the driver
    /// (tests check both give the same tree).
    pub fn with_fit(ctx: &Arc<Context>, lockstep: bool) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            bounds: Pipeline::compute::<u32>(ctx, BOUNDS, shaders::LBVH_BOUNDS_COMP)?,
            morton: Pipeline::compute::<KeyPush>(ctx, MORTON, shaders::LBVH_MORTON_COMP)?,
            sort: RadixSort::new(ctx)?,
            time_sort_steps: false,
            fit: Pipeline::compute_specialized::<FitPush>(ctx, FIT, shaders::LBVH_FIT_COMP, &[lockstep as u32])?,
            refit_leaves: Pipeline::compute::<u32>(ctx, REFIT, shaders::LBVH_REFIT_LEAVES_COMP)?,
            refit_level: Pipeline::compute::<RangePush>(ctx, REFIT, shaders::LBVH_REFIT_LEVEL_COMP)?,
            refit_top: Pipeline::compute::<RangePush>(ctx, REFIT, shaders::LBVH_REFIT_TOP_COMP)?,
            compact: Pipeline::compute::<CompactPush>(ctx, COMPACT, shaders::LBVH_COMPACT_COMP)?,
            order: order::OrderKernels::new(ctx)?,
            ploc: ploc::PlocBuilder::new(ctx)?,
        })
    }

    /// Records a full build of `bvh` over `geom`, each stage under its timer scope. The
    /// geometry must be visible to compute reads; the nodes end visible to all later
    /// reads. Earlier GPU use of the BVH's buffers must be complete (caller's barrier).
    pub fn record_build(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, geom: Geometry<'_>, bvh: &Bvh) {
        self.record_keys(cmd, timer, geom, bvh);
        timer.begin(cmd, FIT);
        self.record_fit(cmd, geom, bvh);
        timer.end(cmd, FIT);
    }

    /// Records a rebuild of `bvh` over rigid bodies (`rigid`, posed by `poses`: one
    /// `Mat4` per body, visible to compute reads): their keys without a sort
    /// (`rigid::RigidKeys`), then `lbvh.fit`, each stage under its timer scope.
    pub fn record_build_rigid(
        &self,
        cmd: vk::CommandBuffer,
        timer: &mut GpuTimer,
        geom: Geometry<'_>,
        bvh: &Bvh,
        rigid: &rigid::RigidKeys,
        poses: &Buffer,
    ) {
        assert_eq!(geom.tri_count, bvh.tri_count, "BVH sized for another triangle count");
        rigid.record(cmd, timer, poses, bvh);
        timer.begin(cmd, FIT);
        self.record_fit(cmd, geom, bvh);
        timer.end(cmd, FIT);
    }

    /// Records a PLOC build of `bvh` over `geom`: the LBVH's bounds, codes and sort,
    /// then `ploc::first_rounds` rounds of `lbvh.ploc` and its tail, each stage under its timer scope. After
    /// the submission, `self.ploc.finish` ends a build that needed more rounds.
    pub fn record_build_ploc(
        &self,
        cmd: vk::CommandBuffer,
        timer: &mut GpuTimer,
        geom: Geometry<'_>,
        bvh: &Bvh,
        scratch: &ploc::PlocScratch,
    ) {
        self.record_keys(cmd, timer, geom, bvh);
        timer.begin(cmd, ploc::PLOC);
        self.ploc
            .record(cmd, geom, bvh, scratch, ploc::first_rounds(geom.tri_count));
        timer.end(cmd, ploc::PLOC);
    }

    /// Builds `bvh` over `geom` now (submits and waits), for geometry built once, with
    /// `kind`. A PLOC tree deeper than the traversal's stack can walk (none seen: PLOC
    /// trees are shallower than the LBVH's) is replaced by the LBVH, whose depth the
    /// key width bounds. Then the compact nodes (`record_compact`). Returns each
    /// stage's GPU milliseconds and the kind built.
    pub fn build_now(
        &self,
        geom: Geometry<'_>,
        bvh: &Bvh,
        kind: BvhKind,
    ) -> Result<(Vec<(&'static str, f64)>, BvhKind)> {
        let mut timer = GpuTimer::new(&self.ctx, 8)?;
        let mut built = None;
        if kind == BvhKind::Ploc {
            let scratch = ploc::PlocScratch::new(&self.ctx, geom.tri_count)?;
            let first = timer.one_shot(|cmd, timer| self.record_build_ploc(cmd, timer, geom, bvh, &scratch))?;
            self.ploc
                .finish(geom.tri_count, bvh, &scratch, ploc::first_rounds(geom.tri_count))?;
            let nodes: Vec<TraversalNode> = bytemuck::pod_collect_to_vec(&bvh.tnodes.read()?);
            let layout = bvh.compact.as_ref().map_or(StaticLayout::Binary, |c| c.layout);
            if layout.fits(&nodes) {
                built = Some((first.scopes, BvhKind::Ploc));
            }
        }
        let (mut scopes, kind) = match built {
            Some(built) => built,
            None => {
                let readout = timer.one_shot(|cmd, timer| self.record_build(cmd, timer, geom, bvh))?;
                (readout.scopes, BvhKind::Lbvh)
            }
        };
        scopes.extend(self.compact_now(bvh)?);
        Ok((scopes, kind))
    }

    /// Records `lbvh.compact` into `bvh` now (submits and waits): its walk's nodes in
    /// its layout, for the tree as built. Returns its GPU milliseconds, under its scope.
    pub fn compact_now(&self, bvh: &Bvh) -> Result<Vec<(&'static str, f64)>> {
        let mut timer = GpuTimer::new(&self.ctx, 2)?;
        Ok(timer
            .one_shot(|cmd, timer| self.record_compact(cmd, timer, bvh))?
            .scopes)
    }

    /// Records what both builders start with, each under its timer scope: bounds,
    /// Morton codes, and the sort of (code, triangle id), left in `bvh.sort`.
    fn record_keys(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, geom: Geometry<'_>, bvh: &Bvh) {
        assert_eq!(geom.tri_count, bvh.tri_count, "BVH sized for another triangle count");
        timer.begin(cmd, BOUNDS);
        self.record_bounds(cmd, geom, bvh);
        timer.end(cmd, BOUNDS);
        timer.begin(cmd, MORTON);
        self.record_morton(cmd, geom, bvh);
        timer.end(cmd, MORTON);
        timer.begin(cmd, SORT);
        if self.time_sort_steps {
            self.sort.record_timed(cmd, &bvh.sort, geom.tri_count, timer);
        } else {
            self.sort.record(cmd, &bvh.sort, geom.tri_count);
        }
        timer.end(cmd, SORT);
    }

    /// `lbvh.bounds`: centroid and scene bounds into the BVH's bounds buffer.
    pub fn record_bounds(&self, cmd: vk::CommandBuffer, geom: Geometry<'_>, bvh: &Bvh) {
        let d = &self.ctx.device;
        let n = geom.tri_count;
        // Reset the atomic min/max targets: min words to 0xffffffff, max words to 0.
        // SAFETY: `cmd` is recording; the bounds buffer is live and 48 bytes or more.
        unsafe {
            d.cmd_fill_buffer(cmd, bvh.bounds.raw, 0, 12, u32::MAX);
            d.cmd_fill_buffer(cmd, bvh.bounds.raw, 12, 12, 0);
            d.cmd_fill_buffer(cmd, bvh.bounds.raw, 24, 12, u32::MAX);
            d.cmd_fill_buffer(cmd, bvh.bounds.raw, 36, 12, 0);
        }
        // RAW: the bounds kernel's atomics read the reset values.
        barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE);
        self.bounds.dispatch(
            cmd,
            &[
                ("vertices", Resource::Buffer(geom.vertices)),
                ("indices", Resource::Buffer(geom.indices)),
                ("bounds", Resource::Buffer(&bvh.bounds)),
            ],
            &n,
            Groups::Exact([n.div_ceil(LBVH_WG * LBVH_BOUNDS_ITEMS), 1, 1]),
        );
        // RAW: Morton codes are quantized in the bounds just reduced.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
    }

    /// `lbvh.morton`: keys and triangle ids into `bvh.sort.keys[0]` / `values[0]`.
    pub fn record_morton(&self, cmd: vk::CommandBuffer, geom: Geometry<'_>, bvh: &Bvh) {
        let n = geom.tri_count;
        self.morton.dispatch(
            cmd,
            &[
                ("vertices", Resource::Texels(&geom.texels.vertices)),
                ("indices", Resource::Texels(&geom.texels.indices)),
                ("bounds", Resource::Buffer(&bvh.bounds)),
                ("keys", Resource::Buffer(&bvh.sort.keys[0])),
                ("values", Resource::Buffer(&bvh.sort.values[0])),
            ],
            &KeyPush {
                tri_count: n,
                key_words: bvh.bits.key_words(),
            },
            Groups::Cover([n, 1, 1]),
        );
        // RAW: the sort reads the codes and ids.
        barrier::global(&self.ctx.device, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
    }

    /// Records a refit by re-running the fit: new boxes for the same tree after the
    /// vertices moved (the tree comes from the keys the last build sorted, still in
    /// `bvh.sort`).
    pub fn record_refit(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, geom: Geometry<'_>, bvh: &Bvh) {
        assert_eq!(geom.tri_count, bvh.tri_count, "BVH sized for another triangle count");
        timer.begin(cmd, REFIT);
        self.record_fit(cmd, geom, bvh);
        timer.end(cmd, REFIT);
    }

    /// Records a refit of `bvh` by its `schedule` (which must be of the tree as it is):
    /// the leaves, then each height level with more than `REFIT_TOP_WG` nodes in a
    /// dispatch of its own, then every smaller level in one workgroup. The same boxes
    /// as `record_refit` (min and max are exact), without its atomics and climb.
    pub fn record_refit_scheduled(
        &self,
        cmd: vk::CommandBuffer,
        timer: &mut GpuTimer,
        geom: Geometry<'_>,
        bvh: &Bvh,
        schedule: &RefitSchedule,
    ) {
        use crate::shader_defines::REFIT_TOP_WG;
        assert_eq!(geom.tri_count, bvh.tri_count, "BVH sized for another triangle count");
        bvh.reshaped();
        let d = &self.ctx.device;
        timer.begin(cmd, REFIT);
        // WAR: earlier reads of the nodes (traversal) finish before the boxes change.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        let n = geom.tri_count;
        self.refit_leaves.dispatch(
            cmd,
            &[
                ("vertices", Resource::Texels(&geom.texels.vertices)),
                ("indices", Resource::Texels(&geom.texels.indices)),
                ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                ("t_tris", Resource::Buffer(&bvh.ttris)),
            ],
            &n,
            Groups::Cover([n, 1, 1]),
        );
        let levels = &schedule.level_list;
        let big = levels.iter().take_while(|l| l[1] > REFIT_TOP_WG).count();
        for l in &levels[..big] {
            // RAW: this level reads the boxes of the levels below.
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
            self.refit_level.dispatch(
                cmd,
                &[
                    ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                    ("order", Resource::Buffer(&schedule.order)),
                    ("node_texels", Resource::Texels(&bvh.node_texels)),
                ],
                &RangePush {
                    first: l[0],
                    count: l[1],
                    tri_count: n,
                },
                Groups::Cover([l[1], 1, 1]),
            );
        }
        if big < levels.len() {
            // RAW: the top's first level reads the boxes below it.
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
            self.refit_top.dispatch(
                cmd,
                &[
                    ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                    ("order", Resource::Buffer(&schedule.order)),
                    ("levels", Resource::Buffer(&schedule.levels)),
                ],
                &RangePush {
                    first: big as u32,
                    count: levels.len() as u32,
                    tri_count: n,
                },
                Groups::Exact([1, 1, 1]),
            );
        }
        // RAW: traversal (or a readback) reads the finished boxes.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ALL_READ_WRITE);
        timer.end(cmd, REFIT);
    }

    /// `lbvh.fit`: the tree over the sorted keys in `bvh.sort` and its boxes, in one
    /// bottom-up pass.
    pub fn record_fit(&self, cmd: vk::CommandBuffer, geom: Geometry<'_>, bvh: &Bvh) {
        bvh.reshaped();
        let d = &self.ctx.device;
        // SAFETY: `cmd` is recording; the buffer is the BVH's, live for its recording.
        unsafe { d.cmd_fill_buffer(cmd, bvh.ends.raw, 0, vk::WHOLE_SIZE, BVH_INVALID) };
        // RAW: the fit's swap words start empty; WAR: earlier reads of the nodes
        // (traversal) finish before the fit rewrites them.
        barrier::record(
            d,
            cmd,
            &[
                barrier::memory(access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE),
                barrier::memory(access::COMPUTE_READ, access::COMPUTE_WRITE),
            ],
            &[],
        );
        self.fit.dispatch(
            cmd,
            &[
                ("vertices", Resource::Texels(&geom.texels.vertices)),
                ("indices", Resource::Texels(&geom.texels.indices)),
                ("keys", Resource::Buffer(&bvh.sort.keys[0])),
                ("values", Resource::Buffer(&bvh.sort.values[0])),
                ("ends", Resource::Buffer(&bvh.ends)),
                ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                ("t_tris", Resource::Buffer(&bvh.ttris)),
                ("costs", Resource::Buffer(&bvh.costs)),
                ("counts", Resource::Buffer(&bvh.counts)),
            ],
            &FitPush {
                tri_count: geom.tri_count,
                key_words: bvh.bits.key_words(),
                order: bvh.ordered(),
            },
            Groups::Cover([geom.tri_count, 1, 1]),
        );
        // RAW: traversal (or a readback) reads the finished boxes.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ALL_READ_WRITE);
    }

    /// Records `lbvh.compact` under its timer scope: the compact nodes the walk of the
    /// static BVH reads, from the nodes as the last build or refit left them (which
    /// must be visible to compute reads, as those leave them), in preorder (`order`).
    /// The compact nodes end visible to all later reads.
    /// Panics for a BVH made without them (`Bvh::new`).
    pub fn record_compact(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, bvh: &Bvh) {
        let compact = bvh
            .compact
            .as_ref()
            .expect("compact nodes of a BVH made by Bvh::new_static");
        let d = &self.ctx.device;
        // WAR: earlier walks of the compact nodes, and the last order's reads of its
        // scratch (its rounds' arguments too), finish before they are rewritten.
        barrier::global(d, cmd, access::COMPUTE_ANY, access::COMPUTE_WRITE);
        let nodes = (bvh.tri_count - 1).max(1);
        timer.begin(cmd, COMPACT);
        let slots = compact.layout.slots();
        let o = &compact.order;
        self.order
            .record(cmd, Resource::Texels(&bvh.node_texels), &bvh.counts, nodes, slots, o);
        self.compact.dispatch(
            cmd,
            &[
                ("nodes", Resource::Texels(&bvh.node_texels)),
                ("compact", Resource::Buffer(&compact.buffer)),
                ("counts", Resource::Buffer(&bvh.counts)),
                ("jump0", Resource::Texels(&o.jump_texels[0])),
                ("jump1", Resource::Texels(&o.jump_texels[1])),
            ],
            &CompactPush {
                node_count: nodes,
                slots,
            },
            Groups::Cover([nodes, 1, 1]),
        );
        timer.end(cmd, COMPACT);
        // RAW: the walk (or a readback) reads them.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ALL_READ_WRITE);
        bvh.compacted
            .store(bvh.shaped.load(Ordering::Relaxed), Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::{lockstep_fit, stack_need, wide8_stack_need, wide_stack_need, StaticLayout};
    use crate::gpu_types::{bvh_leaf_link, TraversalNode};

    /// A walk needs one stack entry per internal node on the longest path: a chain of
    /// k nodes (each with a leaf beside the next) needs k, a single node 1.
    #[test]
    fn stack_need_is_the_longest_path_in_nodes() {
        let node = |c0: u32, c1: u32| TraversalNode {
            child0: c0,
            child1: c1,
            ..Default::default()
        };
        let leaf = |j| bvh_leaf_link(j, 1);
        assert_eq!(stack_need(&[node(leaf(0), leaf(0))]), 1);
        let chain: Vec<TraversalNode> = (0..70u32)
            .map(|s| {
                if s < 69 {
                    node(leaf(s), s + 1)
                } else {
                    node(leaf(s), leaf(s + 1))
                }
            })
            .collect();
        assert_eq!(stack_need(&chain), 70);
        let balanced = [node(1, 2), node(leaf(0), leaf(1)), node(leaf(2), leaf(3))];
        assert_eq!(stack_need(&balanced), 2);
        // The wide walk: a chain never pushes (one internal grandchild a step), two
        // levels of four internal grandchildren push three at the root.
        assert_eq!(wide_stack_need(&chain), 0);
        assert_eq!(wide_stack_need(&balanced), 0);
        let mut deep = vec![node(1, 2), node(3, 4), node(5, 6)];
        deep.extend((0..4).map(|j| node(leaf(2 * j), leaf(2 * j + 1))));
        assert_eq!(stack_need(&deep), 3);
        assert_eq!(wide_stack_need(&deep), 3);
        // The compressed wide walk opens three levels: `deep`'s are leaves; a tree of
        // eight internal nodes three levels down pushes seven at the root.
        assert_eq!(wide8_stack_need(&chain), 0);
        assert_eq!(wide8_stack_need(&deep), 0);
        let mut deeper = vec![node(1, 2), node(3, 4), node(5, 6)];
        deeper.extend((0..4).map(|j| node(7 + 2 * j, 8 + 2 * j)));
        deeper.extend((0..8).map(|j| node(leaf(2 * j), leaf(2 * j + 1))));
        assert_eq!(wide8_stack_need(&deeper), 7);
        assert_eq!(wide_stack_need(&deeper), 3);
        // Units of `deeper`'s shape whose first great-grandchild is the next unit: the
        // compressed walk holds seven a unit where the binary one holds one a level, so
        // 22 units (66 levels) fit the binary walk's stack and not the compressed one's.
        let units = |n: u32| -> Vec<TraversalNode> {
            let mut t = Vec::new();
            for u in 0..n {
                let x = 14 * u;
                t.extend([node(x + 1, x + 2), node(x + 3, x + 4), node(x + 5, x + 6)]);
                t.push(node(x + 14, x + 7));
                t.extend((0..3).map(|j| node(x + 8 + 2 * j, x + 9 + 2 * j)));
                t.extend((0..7).map(|j| node(leaf(2 * j), leaf(2 * j + 1))));
            }
            t.push(node(leaf(0), leaf(1)));
            t
        };
        let deep = units(22);
        assert_eq!(StaticLayout::Binary.stack_need(&deep), stack_need(&deep));
        assert_eq!(StaticLayout::Wide8.stack_need(&deep), 7 * 22);
        assert!(StaticLayout::Binary.fits(&deep) && StaticLayout::Wide.fits(&deep));
        assert!(!StaticLayout::Wide8.fits(&deep) && StaticLayout::Wide8.fits(&units(21)));
    }

    #[test]
    fn the_fit_climbs_in_lockstep_only_on_lavapipe_before_mesa_25() {
        assert!(lockstep_fit("llvmpipe", "Mesa 22.3.6 (LLVM 15.0.6)"));
        assert!(lockstep_fit("llvmpipe", "Mesa 24.2.8-1 (LLVM 17.0.6)"));
        assert!(!lockstep_fit("llvmpipe", "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"));
        assert!(!lockstep_fit("llvmpipe", "Mesa 26.1.0"));
        assert!(lockstep_fit("llvmpipe", "an unknown version text"));
        assert!(!lockstep_fit("NVIDIA", "560.35.03"));
    }
}
