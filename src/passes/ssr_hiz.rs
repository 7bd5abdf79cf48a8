//! `ssr.hiz`: the min-depth pyramid (Hi-Z) of the G-buffer depth, for a hierarchical
//! screen-space march (FidelityFX SSSR's depth hierarchy): level 0 is the depth, each
//! level above holds the minimum (the nearest surface) of its 2x2 children, sizes
//! rounding up, down to 1x1. The levels lie one after another in one storage buffer
//! (`HiZ::levels` gives each one's offset and size), which every device binds the same
//! way (no per-mip storage views).
//! CPU reference: `cpu_ref::ssr::hiz` (tests/suite/ssr.rs), exactly.

use super::{HiZ, Level};
use crate::error::Result;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "ssr.hiz";

/// Push constants of `ssr_hiz.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct HizPush {
    src_offset: u32,
    mid_offset: u32,
    top_offset: u32,
    from_depth: u32,
    src_size: [u32; 2],
    mid_size: [u32; 2],
    top_size: [u32; 2],
}

/// The levels of the pyramid of a `width` x `height` depth image: level 0 that size,
/// each next one `ceil(w / 2) x ceil(h / 2)`, the last 1x1.
pub fn levels(width: u32, height: u32) -> Vec<Level> {
    let mut out = vec![Level {
        offset: 0,
        size: [width, height],
    }];
    while out.last().is_some_and(|l| l.size != [1, 1]) {
        let l = out.last().expect("one level at least");
        out.push(Level {
            offset: l.offset + l.size[0] * l.size[1],
            size: [l.size[0].div_ceil(2), l.size[1].div_ceil(2)],
        });
    }
    out
}

impl HiZ {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let levels = levels(extent.width, extent.height);
        let last = levels.last().expect("one level at least");
        let floats = (last.offset + 1) as u64;
        Ok(Self {
            buffer: Buffer::device_list(ctx, "ssr.hiz", floats * 4)?,
            levels,
        })
    }

    /// The pyramid read back, one `Vec` per level (a readback, for tests).
    pub fn read(&self) -> Result<Vec<Vec<f32>>> {
        let all: Vec<f32> = bytemuck::pod_collect_to_vec(&self.buffer.read()?);
        Ok(self
            .levels
            .iter()
            .map(|l| all[l.offset as usize..(l.offset + l.size[0] * l.size[1]) as usize].to_vec())
            .collect())
    }
}

pub struct HiZPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    pub out: HiZ,
}

impl HiZPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<HizPush>(ctx, NAME, shaders::SSR_HIZ_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "ssr.hiz.sampler")?,
            out: HiZ::new(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = HiZ::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the pyramid of `depth` (the G-buffer's, `SHADER_READ_ONLY_OPTIMAL`, of
    /// the pass's extent), two levels per dispatch. `out` ends visible to compute reads
    /// (the march).
    pub fn record(&self, cmd: vk::CommandBuffer, depth: &Image) {
        let d = &self.ctx.device;
        let levels = &self.out.levels;
        assert_eq!(
            [depth.extent.width, depth.extent.height],
            levels[0].size,
            "ssr.hiz sized for another depth image"
        );
        // WAR: the previous frame's reads of the pyramid finish before it is rewritten.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        // Two levels per dispatch, from level `src`: the first reads the depth image
        // and writes levels 0, 1 and 2 (of a 1x1 image, level 0 alone).
        let mut src = 0;
        loop {
            let (from, mid, top) = (levels[src], levels.get(src + 1), levels.get(src + 2));
            let push = HizPush {
                src_offset: from.offset,
                mid_offset: mid.map_or(0, |m| m.offset),
                top_offset: top.map_or(0, |t| t.offset),
                from_depth: (src == 0) as u32,
                src_size: from.size,
                mid_size: mid.map_or([0, 0], |m| m.size),
                top_size: top.map_or([0, 0], |t| t.size),
            };
            // One invocation per texel of level src + 2 (4x4 of level src).
            let cover = [from.size[0].div_ceil(4), from.size[1].div_ceil(4), 1];
            self.pipeline.dispatch(
                cmd,
                &[
                    ("gb_depth", Resource::Sampled(depth, &self.sampler)),
                    ("pyramid", Resource::Buffer(&self.out.buffer)),
                ],
                &push,
                Groups::Cover(cover),
            );
            src += 2;
            if src + 1 >= levels.len() {
                break;
            }
            // RAW: the next levels read the ones just written.
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
        }
        // RAW: the march reads the pyramid.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
