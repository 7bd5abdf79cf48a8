//! `lbvh.*`: a linear BVH built on the GPU from Morton codes (Lauterbach et al. 2009;
//! Karras 2012; Apetrei 2014). Kernels, each under its timer scope:
//! `lbvh.bounds` → `lbvh.morton` → `lbvh.sort` → `lbvh.fit` (the tree and its boxes
//! in one bottom-up pass), or `lbvh.refit` alone when vertices moved but the triangles
//! stayed the same. One layout, the one the traversal reads (`glsl/shared/bvh.glsl`):
//! N-1 internal nodes of 64 bytes holding both children's boxes (`TraversalNode`, root
//! in slot 0) and the triangles in leaf order (`TraversalTri`), each with a link to its
//! box's half of the parent, which the refit climbs. `lbvh.compact` then writes the
//! 32-byte nodes the walk of the static BVH reads (boxes rounded outward to 16 bits).
//! CPU reference: `cpu_ref::lbvh` (every stage exactly; tests/lbvh.rs).

pub mod dynamic;
pub mod ploc;
pub mod rigid;
pub mod sort;

use crate::aabb::{ordered_to_float, Aabb};
use crate::error::{Error, Result};
use crate::gpu_types::{GpuVertex, PackedBvh, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, LBVH_BOUNDS_ITEMS, LBVH_WG};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Groups, Pipeline, Resource, TexelView};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use sort::{RadixSort, SortBuffers};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

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
// ceil(log2 MAX_TRIANGLES) deep, and a traversal holds at most one pending child per
// level: its stack can never overflow in the frame (see TRACE_STACK).
const MAX_DEPTH: u32 = 32 + (MAX_TRIANGLES - 1).ilog2() + 1;
const _: () = assert!(MAX_DEPTH <= crate::shader_defines::TRACE_STACK);

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

/// Triangles on the GPU: the scene's vertex and index buffers, and their texel views
/// (what the build kernels read the corners through).
#[derive(Clone, Copy)]
pub struct Geometry<'a> {
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    pub texels: &'a TriangleTexels,
    pub tri_count: u32,
}

/// The usage a vertex buffer needs for the BVH kernels (a storage buffer and a texel
/// buffer); its size is whole texels, as every vertex is 32 bytes.
pub const VERTEX_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw() | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER.as_raw(),
);

/// A mesh's vertex and index buffers as texels of uvec4 (bvh.glsl: TRIANGLE_CORNERS):
/// lavapipe fetches a texel for all lanes without a branch, where it loads a storage
/// buffer one lane and one word at a time, each behind a branch.
pub struct TriangleTexels {
    pub vertices: TexelView,
    pub indices: TexelView,
}

impl TriangleTexels {
    /// Views of `vertices` (made with `VERTEX_USAGE`) and `indices` (made by
    /// `index_buffer`).
    pub fn new(ctx: &Arc<Context>, vertices: &Buffer, indices: &Buffer) -> Result<Self> {
        Ok(Self {
            vertices: TexelView::new(ctx, vertices)?,
            indices: TexelView::new(ctx, indices)?,
        })
    }
}

/// Triangles uploaded for the BVH kernels and the traversal alone (benchmarks, tests):
/// the vertices, the padded indices and their texel views.
pub struct UploadedTriangles {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub texels: TriangleTexels,
    pub tri_count: u32,
}

impl UploadedTriangles {
    pub fn new(ctx: &Arc<Context>, name: &str, vertices: &[GpuVertex], indices: &[u32]) -> Result<Self> {
        let v = Buffer::with_data(
            ctx,
            &format!("{name}.vertices"),
            VERTEX_USAGE,
            bytemuck::cast_slice(vertices),
        )?;
        let i = index_buffer(ctx, &format!("{name}.indices"), vk::BufferUsageFlags::empty(), indices)?;
        Ok(Self {
            texels: TriangleTexels::new(ctx, &v, &i)?,
            vertices: v,
            indices: i,
            tri_count: (indices.len() / 3) as u32,
        })
    }

    pub fn geometry(&self) -> Geometry<'_> {
        Geometry {
            vertices: &self.vertices,
            indices: &self.indices,
            texels: &self.texels,
            tri_count: self.tri_count,
        }
    }
}

/// An index buffer the BVH kernels can read: `indices` uploaded, padded to whole
/// texels of 4, with `usage` and the storage and texel usages.
pub fn index_buffer(ctx: &Arc<Context>, name: &str, usage: vk::BufferUsageFlags, indices: &[u32]) -> Result<Buffer> {
    let mut padded = indices.to_vec();
    padded.resize(indices.len().next_multiple_of(4).max(4), 0);
    Buffer::with_data(ctx, name, usage | VERTEX_USAGE, bytemuck::cast_slice(&padded))
}

/// The compact nodes (`lbvh.compact`; `glsl/shared/bvh.glsl`): 2 + 2 max(N-1, 1)
/// texels of 16 bytes, and the same as the walk reads them.
pub struct CompactNodes {
    pub buffer: Buffer,
    pub texels: TexelView,
}

/// A BVH on the GPU and the scratch memory to rebuild it.
pub struct Bvh {
    /// max(N-1, 1) `TraversalNode`s (written by the fit and the refit).
    pub tnodes: Buffer,
    /// N `TraversalTri`s, in leaf order.
    pub ttris: Buffer,
    /// `tnodes` and `ttris` as the traversal reads them (texel buffers).
    pub node_texels: TexelView,
    pub tri_texels: TexelView,
    /// The compact nodes the walk of the static BVH reads (`Bvh::new_static`; none for
    /// a BVH only ever walked as the dynamic one).
    pub compact: Option<CompactNodes>,
    /// Builds and refits recorded, and the count when `compact` was last recorded.
    shaped: AtomicU32,
    compacted: AtomicU32,
    /// The fit's swap word per internal node (the first child's outer end).
    ends: Buffer,
    /// The fit's SAH cost of the subtree in each half of each node.
    costs: Buffer,
    bounds: Buffer,
    pub sort: SortBuffers,
    pub tri_count: u32,
    pub bits: MortonBits,
}

impl Bvh {
    /// Memory for a BVH over `tri_count` triangles.
    pub fn new(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits) -> Result<Self> {
        if tri_count == 0 {
            return Err(Error::Bvh("a BVH needs at least one triangle".into()));
        }
        if tri_count > MAX_TRIANGLES {
            return Err(Error::Bvh(format!(
                "{tri_count} triangles exceed the LBVH limit of {MAX_TRIANGLES}"
            )));
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let buf = |name: &str, bytes: u64| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        // What the traversal reads, also as texel buffers (TexelView).
        let texels = |name: &str, bytes: u64| {
            Buffer::new(
                ctx,
                name,
                bytes,
                usage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
                MemoryLocation::GpuOnly,
            )
        };
        let tnodes = texels(
            "lbvh.tnodes",
            (tri_count as u64 - 1).max(1) * std::mem::size_of::<TraversalNode>() as u64,
        )?;
        let ttris = texels(
            "lbvh.ttris",
            tri_count as u64 * std::mem::size_of::<TraversalTri>() as u64,
        )?;
        Ok(Self {
            node_texels: TexelView::new(ctx, &tnodes)?,
            tri_texels: TexelView::new(ctx, &ttris)?,
            compact: None,
            shaped: AtomicU32::new(1),
            compacted: AtomicU32::new(0),
            tnodes,
            ttris,
            ends: buf("lbvh.ends", (tri_count as u64 - 1).max(1) * 4)?,
            costs: buf("lbvh.costs", (tri_count as u64 - 1).max(1) * 2 * 4)?,
            bounds: buf("lbvh.bounds", 12 * 4)?,
            sort: SortBuffers::new(ctx, tri_count, bits.key_words())?,
            tri_count,
            bits,
        })
    }

    /// Memory for a BVH walked as the static one: `new` and its compact nodes.
    pub fn new_static(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits) -> Result<Self> {
        let mut bvh = Self::new(ctx, tri_count, bits)?;
        let buffer = Buffer::new(
            ctx,
            "lbvh.compact",
            (2 + 2 * (tri_count as u64 - 1).max(1)) * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        bvh.compact = Some(CompactNodes {
            texels: TexelView::new(ctx, &buffer)?,
            buffer,
        });
        Ok(bvh)
    }

    /// Bytes of the BVH itself (nodes, compact nodes if any, and triangles), without
    /// the rebuild scratch.
    pub fn bytes(&self) -> u64 {
        self.tnodes.size + self.compact.as_ref().map_or(0, |c| c.buffer.size) + self.ttris.size
    }

    /// Whether the BVH has compact nodes, recorded after the last build or refit
    /// recorded (what the walk of the static BVH needs).
    pub fn compact_current(&self) -> bool {
        self.compact.is_some() && self.compacted.load(Ordering::Relaxed) == self.shaped.load(Ordering::Relaxed)
    }

    /// A build or refit of the nodes was recorded: the compact nodes are stale.
    fn reshaped(&self) {
        self.shaped.fetch_add(1, Ordering::Relaxed);
    }

    /// (centroid bounds, scene bounds) from the last `lbvh.bounds`, read back.
    pub fn read_bounds(&self) -> Result<(Aabb, Aabb)> {
        let w: Vec<u32> = bytemuck::pod_collect_to_vec(&self.bounds.read()?);
        let v = |i: usize| {
            Vec3::new(
                ordered_to_float(w[i]),
                ordered_to_float(w[i + 1]),
                ordered_to_float(w[i + 2]),
            )
        };
        Ok((Aabb { lo: v(0), hi: v(3) }, Aabb { lo: v(6), hi: v(9) }))
    }

    /// The nodes and triangles, read back (for tests and benchmarks).
    pub fn read_packed(&self) -> Result<PackedBvh> {
        Ok(PackedBvh {
            nodes: bytemuck::pod_collect_to_vec(&self.tnodes.read()?),
            tris: bytemuck::pod_collect_to_vec(&self.ttris.read()?),
        })
    }
}

/// The order in which a refit of a fixed topology can visit the internal nodes: by
/// height (1: both children leaves), so a level's children are all done when it runs.
/// Made on the CPU from the nodes of a built BVH (`of`), valid until it is rebuilt.
pub struct RefitSchedule {
    /// Internal nodes by height, lowest first.
    order: Buffer,
    /// (first, count) into `order` of each height level.
    levels: Buffer,
    level_list: Vec<[u32; 2]>,
}

impl RefitSchedule {
    /// The schedule of `bvh` as built now (reads its nodes back; waits for the GPU).
    pub fn of(ctx: &Arc<Context>, bvh: &Bvh) -> Result<Self> {
        let (order, level_list) = refit_order(&bvh.read_packed()?, bvh.tri_count);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            order: Buffer::with_data(ctx, "lbvh.refit_order", usage, bytemuck::cast_slice(&order))?,
            levels: Buffer::with_data(ctx, "lbvh.refit_levels", usage, bytemuck::cast_slice(&level_list))?,
            level_list,
        })
    }
}

/// Internal node slots ordered by height (triangles are 0) in the binary tree of parent
/// links (also the nodes inside leaves of several triangles, whose boxes the refit
/// keeps), and each level's (first, count).
pub fn refit_order(bvh: &PackedBvh, tri_count: u32) -> (Vec<u32>, Vec<[u32; 2]>) {
    let internal = tri_count.saturating_sub(1) as usize;
    // Each node's height, from its children's as they become known: a node is done when
    // both its halves have reported, then reports to its own parent.
    let mut height = vec![0u32; internal];
    let mut reported = vec![0u8; internal];
    let mut ready: Vec<(u32, u32)> = if internal == 0 {
        Vec::new()
    } else {
        bvh.tris.iter().map(|t| (t.parent, 0)).collect()
    };
    while let Some((link, h)) = ready.pop() {
        let s = (link >> 1) as usize;
        height[s] = height[s].max(h + 1);
        reported[s] += 1;
        if reported[s] == 2 && s != 0 {
            ready.push((bvh.nodes[s].parent, height[s]));
        }
    }
    let top = height.iter().copied().max().unwrap_or(0);
    let mut levels = vec![[0u32; 2]; top as usize];
    for h in &height {
        levels[*h as usize - 1][1] += 1;
    }
    let mut first = 0;
    for l in &mut levels {
        l[0] = first;
        first += l[1];
    }
    let mut fill: Vec<u32> = levels.iter().map(|l| l[0]).collect();
    let mut order = vec![0u32; internal];
    for (s, h) in height.iter().enumerate() {
        let h = *h as usize - 1;
        order[fill[h] as usize] = s as u32;
        fill[h] += 1;
    }
    (order, levels)
}

/// Stack entries a walk of this tree can need at most: the internal nodes on its
/// longest path from the root (a walk holds at most one pending child per node it
/// descends through).
pub fn stack_need(nodes: &[TraversalNode]) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((s, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let nd = &nodes[s as usize];
        for c in [nd.child0, nd.child1] {
            if crate::gpu_types::bvh_leaf(c).is_none() {
                stack.push((c, depth + 1));
            }
        }
    }
    deepest
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

/// Push constants of `lbvh_morton.comp` and `lbvh_fit.comp` (`lbvh.bounds` and the
/// refit push the triangle count alone, as a `u32`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct KeyPush {
    tri_count: u32,
    /// 1: 30-bit Morton codes, 2: 63-bit.
    key_words: u32,
}

/// The LBVH kernels.
pub struct LbvhBuilder {
    ctx: Arc<Context>,
    bounds: Pipeline,
    morton: Pipeline,
    pub sort: RadixSort,
    fit: Pipeline,
    refit_leaves: Pipeline,
    refit_level: Pipeline,
    refit_top: Pipeline,
    compact: Pipeline,
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
        Self::with_fit(ctx, lockstep_fit(&ctx.driver_name, &ctx.driver_info))
    }

    /// The kernels with the fit climbing in lockstep or freely, whatever the driver
    /// (tests check both give the same tree).
    pub fn with_fit(ctx: &Arc<Context>, lockstep: bool) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            bounds: Pipeline::compute::<u32>(ctx, BOUNDS, shaders::LBVH_BOUNDS_COMP)?,
            morton: Pipeline::compute::<KeyPush>(ctx, MORTON, shaders::LBVH_MORTON_COMP)?,
            sort: RadixSort::new(ctx)?,
            fit: Pipeline::compute_specialized::<KeyPush>(ctx, FIT, shaders::LBVH_FIT_COMP, &[lockstep as u32])?,
            refit_leaves: Pipeline::compute::<u32>(ctx, REFIT, shaders::LBVH_REFIT_LEAVES_COMP)?,
            refit_level: Pipeline::compute::<RangePush>(ctx, REFIT, shaders::LBVH_REFIT_LEVEL_COMP)?,
            refit_top: Pipeline::compute::<RangePush>(ctx, REFIT, shaders::LBVH_REFIT_TOP_COMP)?,
            compact: Pipeline::compute::<u32>(ctx, COMPACT, shaders::LBVH_COMPACT_COMP)?,
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
    /// then `ploc::ROUNDS` rounds of `lbvh.ploc`, each stage under its timer scope. After
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
        self.ploc.record(cmd, geom, bvh, scratch, ploc::ROUNDS);
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
            self.ploc.finish(geom.tri_count, bvh, &scratch, ploc::ROUNDS)?;
            let nodes: Vec<TraversalNode> = bytemuck::pod_collect_to_vec(&bvh.tnodes.read()?);
            if stack_need(&nodes) <= crate::shader_defines::TRACE_STACK {
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
        let compact = timer.one_shot(|cmd, timer| self.record_compact(cmd, timer, bvh))?;
        scopes.extend(compact.scopes);
        Ok((scopes, kind))
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
        self.sort.record(cmd, &bvh.sort, geom.tri_count);
        timer.end(cmd, SORT);
    }

    /// `lbvh.bounds`: centroid and scene bounds into the BVH's bounds buffer.
    pub fn record_bounds(&self, cmd: vk::CommandBuffer, geom: Geometry<'_>, bvh: &Bvh) {
        let d = &self.ctx.device;
        let n = geom.tri_count;
        // Reset the atomic min/max targets: min words to 0xffffffff, max words to 0.
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
                Resource::Buffer(geom.vertices),
                Resource::Buffer(geom.indices),
                Resource::Buffer(&bvh.bounds),
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
                Resource::Texels(&geom.texels.vertices),
                Resource::Texels(&geom.texels.indices),
                Resource::Buffer(&bvh.bounds),
                Resource::Buffer(&bvh.sort.keys[0]),
                Resource::Buffer(&bvh.sort.values[0]),
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
                Resource::Texels(&geom.texels.vertices),
                Resource::Texels(&geom.texels.indices),
                Resource::Buffer(&bvh.tnodes),
                Resource::Buffer(&bvh.ttris),
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
                    Resource::Buffer(&bvh.tnodes),
                    Resource::Buffer(&schedule.order),
                    Resource::Texels(&bvh.node_texels),
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
                    Resource::Buffer(&bvh.tnodes),
                    Resource::Buffer(&schedule.order),
                    Resource::Buffer(&schedule.levels),
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
                Resource::Texels(&geom.texels.vertices),
                Resource::Texels(&geom.texels.indices),
                Resource::Buffer(&bvh.sort.keys[0]),
                Resource::Buffer(&bvh.sort.values[0]),
                Resource::Buffer(&bvh.ends),
                Resource::Buffer(&bvh.tnodes),
                Resource::Buffer(&bvh.ttris),
                Resource::Buffer(&bvh.costs),
            ],
            &KeyPush {
                tri_count: geom.tri_count,
                key_words: bvh.bits.key_words(),
            },
            Groups::Cover([geom.tri_count, 1, 1]),
        );
        // RAW: traversal (or a readback) reads the finished boxes.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ALL_READ_WRITE);
    }

    /// Records `lbvh.compact` under its timer scope: the compact nodes the walk of the
    /// static BVH reads, from the nodes as the last build or refit left them (which
    /// must be visible to compute reads, as those leave them). The compact nodes end
    /// visible to all later reads.
    /// Panics for a BVH made without them (`Bvh::new`).
    pub fn record_compact(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, bvh: &Bvh) {
        let compact = bvh
            .compact
            .as_ref()
            .expect("compact nodes of a BVH made by Bvh::new_static");
        let d = &self.ctx.device;
        // WAR: earlier walks of the compact nodes finish before they are rewritten.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        let nodes = (bvh.tri_count - 1).max(1);
        timer.begin(cmd, COMPACT);
        self.compact.dispatch(
            cmd,
            &[Resource::Texels(&bvh.node_texels), Resource::Buffer(&compact.buffer)],
            &nodes,
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
    use super::{lockstep_fit, stack_need};
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
