//! `lbvh.ploc`: a BVH of higher quality than the LBVH's, for geometry built once (the
//! static scene): PLOC (Meister & Bittner 2018) over the triangles in Morton order,
//! after the LBVH's bounds, codes and sort, into the same layout (`glsl/shared/bvh.glsl`,
//! `glsl/shared/ploc.glsl`). Rounds of nearest-neighbour search, merge and compaction
//! run until one cluster is left: four dispatches each while more than
//! `PLOC_TAIL_CAP` clusters are left, then all the rest in one workgroup
//! (`glsl/ploc_tail.comp`). Their count is the data's, so their sizes live on the GPU
//! (indirect dispatches) and `finish` records more rounds when the first submission
//! did not end the build. A merged cluster of at most `BVH_LEAF_MAX`
//! triangles that are one run in key order becomes a leaf where that costs no more SAH
//! than its split; the refit follows the parent links as for the LBVH.
//! CPU reference: `cpu_ref::lbvh::ploc` (tests/suite/lbvh.rs).

use super::{Bvh, Geometry};
use crate::error::{Error, Result};
use crate::shader_defines::{LBVH_WG, PLOC_RADIUS, PLOC_TAIL_CAP};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource, TexelView};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const PLOC: &str = "lbvh.ploc";

/// Rounds of four dispatches a build of `n` triangles records (before the one-workgroup
/// tail) before it looks whether one cluster is left: enough to reach `PLOC_TAIL_CAP`
/// clusters where each round keeps 0.85 of them, and one more. Rounds kept 0.75-0.82
/// of the clusters on soups of 10K to 1M triangles and `room` until 512 were left,
/// 0.84 on `gallery` (on average); a round recorded past the cap dispatches nothing
/// but its one-workgroup scan, and a build that needs more rounds submits again
/// (`finish`).
pub fn first_rounds(n: u32) -> u32 {
    if n <= PLOC_TAIL_CAP {
        return 0;
    }
    let rounds = (f64::from(n) / f64::from(PLOC_TAIL_CAP)).ln() / (1.0f64 / 0.85).ln();
    rounds.ceil() as u32 + 1
}

/// Rounds `finish` records per submission after the first.
const MORE_ROUNDS: u32 = 8;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PlocPush {
    n: u32,
    parity: u32,
    /// 1: the merges write the order counts (`Bvh::counts`).
    order: u32,
}

impl PlocPush {
    fn new(n: u32, parity: u32, bvh: &Bvh) -> Self {
        Self {
            n,
            parity,
            order: bvh.ordered(),
        }
    }
}

/// The scratch memory of a PLOC build over up to `capacity` triangles.
pub struct PlocScratch {
    clusters: [Buffer; 2],
    /// `clusters` as texels, what the nearest-neighbour search reads.
    cluster_texels: [TexelView; 2],
    /// Each cluster's union-box areas with the `PLOC_RADIUS` after it (`ploc_areas`).
    areas: Buffer,
    nearest: Buffer,
    tile_counts: Buffer,
    tile_offsets: Buffer,
    /// `PlocState` (ploc.glsl): the rounds' counts and slots.
    state: Buffer,
    /// Indirect dispatch arguments of even and odd rounds.
    args: [Buffer; 2],
    capacity: u32,
}

impl PlocScratch {
    pub fn new(ctx: &Arc<Context>, capacity: u32) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let buf = |name: &str, bytes: u64, extra: vk::BufferUsageFlags| {
            Buffer::new(ctx, name, bytes.max(16), usage | extra, MemoryLocation::GpuOnly)
        };
        let n = capacity.max(1) as u64;
        let tiles = capacity.div_ceil(LBVH_WG).max(1) as u64;
        let none = vk::BufferUsageFlags::empty();
        let indirect = vk::BufferUsageFlags::INDIRECT_BUFFER;
        let texels = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let clusters = [
            buf("ploc.clusters0", n * 48, texels)?,
            buf("ploc.clusters1", n * 48, texels)?,
        ];
        Ok(Self {
            cluster_texels: [TexelView::new(ctx, &clusters[0])?, TexelView::new(ctx, &clusters[1])?],
            clusters,
            areas: buf("ploc.areas", n * 4 * u64::from(PLOC_RADIUS), none)?,
            nearest: buf("ploc.nearest", n * 4, none)?,
            tile_counts: buf("ploc.tile_counts", tiles * 4, none)?,
            tile_offsets: buf("ploc.tile_offsets", tiles * 8, none)?,
            state: buf("ploc.state", 32, none)?,
            args: [buf("ploc.args0", 16, indirect)?, buf("ploc.args1", 16, indirect)?],
            capacity,
        })
    }

    /// Clusters left after the rounds recorded so far (read back; waits for the GPU).
    pub fn clusters_left(&self, rounds: u32) -> Result<u32> {
        let w: Vec<u32> = bytemuck::pod_collect_to_vec(&self.state.read()?);
        Ok(w[(rounds % 2) as usize])
    }
}

/// The PLOC kernels.
pub struct PlocBuilder {
    ctx: Arc<Context>,
    init: Pipeline,
    areas: Pipeline,
    nearest: Pipeline,
    count: Pipeline,
    scan: Pipeline,
    scatter: Pipeline,
    tail: Pipeline,
}

impl PlocBuilder {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let p = |name, shader| Pipeline::compute::<PlocPush>(ctx, name, shader);
        Ok(Self {
            ctx: ctx.clone(),
            init: p("lbvh.ploc.init", shaders::PLOC_INIT_COMP)?,
            areas: p("lbvh.ploc.areas", shaders::PLOC_AREAS_COMP)?,
            nearest: p("lbvh.ploc.nearest", shaders::PLOC_NEAREST_COMP)?,
            count: p("lbvh.ploc.count", shaders::PLOC_COUNT_COMP)?,
            scan: p("lbvh.ploc.scan", shaders::PLOC_SCAN_COMP)?,
            scatter: p("lbvh.ploc.scatter", shaders::PLOC_SCATTER_COMP)?,
            tail: p("lbvh.ploc.tail", shaders::PLOC_TAIL_COMP)?,
        })
    }

    /// Records the leaves (from the ids `bvh.sort` left in key order), `rounds` rounds
    /// and the tail. The sorted ids must be visible to compute reads; the BVH ends visible to
    /// all reads.
    pub fn record(&self, cmd: vk::CommandBuffer, geom: Geometry<'_>, bvh: &Bvh, s: &PlocScratch, rounds: u32) {
        assert!(
            geom.tri_count <= s.capacity,
            "PLOC scratch for {} triangles",
            s.capacity
        );
        bvh.reshaped();
        let d = &self.ctx.device;
        let n = geom.tri_count;
        // WAR: earlier reads of the BVH and the scratch (traversal, a previous build's
        // rounds, the state read back) finish before they are rewritten.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_WRITE);
        self.init.dispatch(
            cmd,
            &[
                ("vertices", Resource::Texels(&geom.texels.vertices)),
                ("indices", Resource::Texels(&geom.texels.indices)),
                ("values", Resource::Buffer(&bvh.sort.values[0])),
                ("clusters", Resource::Buffer(&s.clusters[0])),
                ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                ("t_tris", Resource::Buffer(&bvh.ttris)),
                ("state", Resource::Buffer(&s.state)),
                ("args", Resource::Buffer(&s.args[0])),
                ("counts", Resource::Buffer(&bvh.counts)),
            ],
            &PlocPush::new(n, 0, bvh),
            Groups::Cover([n, 1, 1]),
        );
        self.record_rounds(cmd, n, bvh, s, 0, rounds);
    }

    /// Records `rounds` more rounds after the first `done`, then the tail (which ends
    /// the build if at most `PLOC_TAIL_CAP` clusters are left by then).
    pub fn record_rounds(&self, cmd: vk::CommandBuffer, n: u32, bvh: &Bvh, s: &PlocScratch, done: u32, rounds: u32) {
        let d = &self.ctx.device;
        let rw = access::COMPUTE_READ_WRITE;
        for r in done..done + rounds {
            let (p, q) = ((r % 2) as usize, ((r + 1) % 2) as usize);
            let push = PlocPush::new(n, p as u32, bvh);
            // RAW: this round reads the clusters, count and arguments the previous
            // step wrote (its dispatch size too).
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_AND_INDIRECT);
            self.areas.dispatch(
                cmd,
                &[
                    ("cluster_texels", Resource::Texels(&s.cluster_texels[p])),
                    ("areas", Resource::Buffer(&s.areas)),
                    ("state", Resource::Buffer(&s.state)),
                ],
                &push,
                Groups::Indirect(&s.args[p]),
            );
            // RAW: the search reads the areas (WAR: the areas' previous reads are this
            // round's earlier barriers' sources).
            barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
            self.nearest.dispatch(
                cmd,
                &[
                    ("areas", Resource::Buffer(&s.areas)),
                    ("nearest", Resource::Buffer(&s.nearest)),
                    ("state", Resource::Buffer(&s.state)),
                ],
                &push,
                Groups::Indirect(&s.args[p]),
            );
            // RAW: the counts read every cluster's nearest.
            barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
            self.count.dispatch(
                cmd,
                &[
                    ("nearest", Resource::Buffer(&s.nearest)),
                    ("tile_counts", Resource::Buffer(&s.tile_counts)),
                    ("state", Resource::Buffer(&s.state)),
                ],
                &push,
                Groups::Indirect(&s.args[p]),
            );
            // RAW: the scan reads the tile counts.
            barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
            self.scan.dispatch(
                cmd,
                &[
                    ("tile_counts", Resource::Buffer(&s.tile_counts)),
                    ("tile_offsets", Resource::Buffer(&s.tile_offsets)),
                    ("state", Resource::Buffer(&s.state)),
                    ("next_args", Resource::Buffer(&s.args[q])),
                ],
                &push,
                Groups::Exact([1, 1, 1]),
            );
            // RAW: the scatter reads the offsets and the round's first slot.
            barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
            self.scatter.dispatch(
                cmd,
                &[
                    ("cluster_texels", Resource::Texels(&s.cluster_texels[p])),
                    ("next_clusters", Resource::Buffer(&s.clusters[q])),
                    ("nearest", Resource::Buffer(&s.nearest)),
                    ("tile_offsets", Resource::Buffer(&s.tile_offsets)),
                    ("state", Resource::Buffer(&s.state)),
                    ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                    ("t_tris", Resource::Buffer(&bvh.ttris)),
                    ("counts", Resource::Buffer(&bvh.counts)),
                ],
                &push,
                Groups::Indirect(&s.args[p]),
            );
        }
        let p = (done + rounds) % 2;
        // RAW: the tail reads the clusters, the count and the tree the rounds wrote.
        barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
        self.tail.dispatch(
            cmd,
            &[
                ("clusters0", Resource::Buffer(&s.clusters[0])),
                ("clusters1", Resource::Buffer(&s.clusters[1])),
                ("nearest", Resource::Buffer(&s.nearest)),
                ("state", Resource::Buffer(&s.state)),
                ("t_nodes", Resource::Buffer(&bvh.tnodes)),
                ("t_tris", Resource::Buffer(&bvh.ttris)),
                ("counts", Resource::Buffer(&bvh.counts)),
            ],
            &PlocPush::new(n, p, bvh),
            Groups::Exact([1, 1, 1]),
        );
        // RAW: traversal, a readback or the next build reads the tree and the state.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ALL_READ_WRITE);
    }

    /// After a submitted `record` of `rounds` rounds: records and submits more rounds
    /// (each time with the tail) until one cluster is left. Returns the rounds of four
    /// dispatches recorded in all. Every round merges at least the closest pair in
    /// reach (each is the other's nearest), so a submission that leaves as many
    /// clusters as it found is a defect, said as an error rather than a build that
    /// never ends.
    pub fn finish(&self, n: u32, bvh: &Bvh, s: &PlocScratch, mut rounds: u32) -> Result<u32> {
        let mut left = s.clusters_left(rounds)?;
        while left > 1 {
            bvh.reshaped();
            self.ctx
                .one_shot(|cmd| self.record_rounds(cmd, n, bvh, s, rounds, MORE_ROUNDS))?;
            rounds += MORE_ROUNDS;
            let now = s.clusters_left(rounds)?;
            if now >= left {
                return Err(Error::Bvh(format!(
                    "PLOC's build of {n} triangles stopped merging: {now} clusters left after {rounds} rounds"
                )));
            }
            left = now;
        }
        Ok(rounds)
    }
}
