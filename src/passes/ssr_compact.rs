//! `ssr.compact`: stream compaction of the fail mask into a list of pixels (in 8x8
//! block order, see `glsl/shared/compact.glsl`; deterministic) plus the indirect
//! dispatch arguments of the ray-tracing pass.
//! Count per tile → scan (one workgroup) → scatter: no workgroup waits on another.
//! CPU reference: `cpu_ref::compact`.

use super::CompactOutputs;
use crate::error::Result;
use crate::shader_defines::{COMPACT_ITEMS, COMPACT_WG, WG_2D};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const NAME: &str = "ssr.compact";
/// The debug names of the fail mask's compaction pipelines.
pub const PIPELINES: [&str; 3] = ["ssr.compact.count", "ssr.compact.scan", "ssr.compact.scatter"];
/// Slots per tile of the count and scatter kernels.
pub const TILE: u32 = COMPACT_WG * COMPACT_ITEMS;

/// Slots of the list's order for a mask of `extent`: whole `WG_2D` x `WG_2D` blocks.
fn slots(extent: vk::Extent2D) -> u32 {
    extent.width.div_ceil(WG_2D) * extent.height.div_ceil(WG_2D) * WG_2D * WG_2D
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CompactPush {
    size: [u32; 2],
    num_tiles: u32,
    slots: u32,
}

impl CompactOutputs {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let n = extent.width as u64 * extent.height as u64;
        let tiles = slots(extent).div_ceil(TILE).max(1) as u64;
        Ok(Self {
            pixels: Buffer::new(ctx, "compact.pixels", n * 4, usage, MemoryLocation::GpuOnly)?,
            indirect: Buffer::new(
                ctx,
                "compact.indirect",
                32,
                usage | vk::BufferUsageFlags::INDIRECT_BUFFER | crate::vk::accel::address_usage(ctx),
                MemoryLocation::GpuOnly,
            )?,
            tile_counts: Buffer::new(ctx, "compact.tiles", tiles * 4, usage, MemoryLocation::GpuOnly)?,
            extent,
        })
    }

    /// Number of listed pixels of the last run (a readback: for stats and tests).
    pub fn read_count(&self) -> Result<u32> {
        let v: Vec<u32> = bytemuck::pod_collect_to_vec(&self.indirect.read()?);
        Ok(v[3])
    }

    /// The listed pixels of the last run, as (x, y).
    pub fn read_pixels(&self) -> Result<Vec<(u32, u32)>> {
        let count = self.read_count()? as usize;
        let all: Vec<u32> = bytemuck::pod_collect_to_vec(&self.pixels.read()?);
        Ok(all[..count].iter().map(|p| (p & 0xffff, p >> 16)).collect())
    }
}

pub struct CompactPass {
    ctx: Arc<Context>,
    count: Pipeline,
    scan: Pipeline,
    scatter: Pipeline,
    pub out: CompactOutputs,
}

impl CompactPass {
    /// `names`: the count, scan and scatter pipelines' debug names (`PIPELINES`, or the
    /// shadows' own).
    pub fn new(ctx: &Arc<Context>, names: [&'static str; 3], extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            count: Pipeline::compute::<CompactPush>(ctx, names[0], shaders::COMPACT_COUNT_COMP)?,
            scan: Pipeline::compute::<CompactPush>(ctx, names[1], shaders::COMPACT_SCAN_COMP)?,
            scatter: Pipeline::compute::<CompactPush>(ctx, names[2], shaders::COMPACT_SCATTER_COMP)?,
            out: CompactOutputs::new(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = CompactOutputs::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the compaction of `mask` (`GENERAL` layout, visible to compute reads).
    /// The list and the indirect arguments end visible to compute reads and to
    /// indirect dispatches.
    pub fn record(&self, cmd: vk::CommandBuffer, mask: &Image) {
        let d = &self.ctx.device;
        let e = self.out.extent;
        let slots = slots(e);
        let num_tiles = slots.div_ceil(TILE);
        let push = CompactPush {
            size: [e.width, e.height],
            num_tiles,
            slots,
        };
        let rw = access::COMPUTE_READ_WRITE;
        let tiles = Groups::Exact([num_tiles, 1, 1]);
        let out = &self.out;
        // WAR: the previous frame's readers of the list and arguments are done.
        barrier::global(d, cmd, access::ALL_READ_WRITE, rw);
        let counts = ("tile_counts", Resource::Buffer(&out.tile_counts));
        self.count
            .dispatch(cmd, &[("mask", Resource::StorageImage(mask)), counts], &push, tiles);
        // RAW: the scan reads the tile counts.
        barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
        let scan = [
            ("tile_counts", Resource::Buffer(&out.tile_counts)),
            ("indirect", Resource::Buffer(&out.indirect)),
        ];
        self.scan.dispatch(cmd, &scan, &push, Groups::Exact([1, 1, 1]));
        // RAW: the scatter reads the tile offsets.
        barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
        let scatter = [
            ("mask", Resource::StorageImage(mask)),
            ("tile_offsets", Resource::Buffer(&out.tile_counts)),
            ("pixels", Resource::Buffer(&out.pixels)),
        ];
        self.scatter.dispatch(cmd, &scatter, &push, tiles);
        // RAW: the ray-tracing pass reads the list and dispatches from the arguments.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_AND_INDIRECT);
    }
}
