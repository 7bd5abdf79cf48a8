//! `reflect.merge`: SSR where it succeeded, ray-traced reflections where it failed,
//! labelled by source; then a separable Gaussian blur restricted to the band around
//! SSR/RT seams (horizontal, then vertical), run only on the 8x8 tiles a seam comes
//! near (see `glsl/reflect_blur.comp`).

use super::gbuffer::GBuffer;
use crate::error::Result;
use crate::shader_defines::WG_2D;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "reflect.merge";
/// rgb: reflected radiance; a: source (`SOURCE_*`).
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MergePush {
    reflective_min: f32,
    rt_enabled: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BlurPush {
    axis: [i32; 2],
    radius: i32,
    band: i32,
}

/// Seam blur settings.
#[derive(Clone, Copy, Debug)]
pub struct BlurParams {
    /// Blur radius in pixels (0: no blur; where only one source exists, as in the `rt`
    /// and `ssr` modes, there are no seams and the blur would copy every pixel).
    pub radius: u32,
    /// Half-width in pixels of the band around seams that is blurred.
    pub band: u32,
}

/// Images and per-tile buffers that depend on the resolution.
struct Targets {
    /// The merged (and seam-blurred) reflection; `GENERAL` between frames.
    reflection: Image,
    /// The horizontal blur's output (written for active tiles only).
    scratch: Image,
    /// Per WG_2D x WG_2D tile: bit `1 << SOURCE_*` for each source it holds.
    tile_sources: Buffer,
    /// Per tile: 1 when the blur works on it this frame.
    tile_active: Buffer,
}

impl Targets {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let usage =
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
        let tiles = (extent.width.div_ceil(WG_2D) * extent.height.div_ceil(WG_2D)) as u64;
        let buffer = |name| {
            Buffer::new(
                ctx,
                name,
                tiles * 4,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                gpu_allocator::MemoryLocation::GpuOnly,
            )
        };
        Ok(Self {
            reflection: Image::new(ctx, "reflect.merged", extent, FORMAT, usage)?,
            scratch: Image::new(ctx, "reflect.scratch", extent, FORMAT, usage)?,
            tile_sources: buffer("reflect.tile_sources")?,
            tile_active: buffer("reflect.tile_active")?,
        })
    }
}

pub struct MergePass {
    ctx: Arc<Context>,
    merge: Pipeline,
    blur: Pipeline,
    sampler: Sampler,
    targets: Targets,
}

impl MergePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            merge: Pipeline::compute(ctx, NAME, ("reflect_merge.comp", shaders::REFLECT_MERGE_COMP), 8)?,
            blur: Pipeline::compute(
                ctx,
                "reflect.blur",
                ("reflect_blur.comp", shaders::REFLECT_BLUR_COMP),
                16,
            )?,
            sampler: Sampler::nearest_clamp(ctx, "reflect.sampler")?,
            targets: Targets::new(ctx, extent)?,
        })
    }

    /// The merged, seam-blurred reflection (`GENERAL` between frames).
    pub fn reflection(&self) -> &Image {
        &self.targets.reflection
    }

    /// The blur's intermediate image (for layout transitions by the renderer).
    pub fn scratch(&self) -> &Image {
        &self.targets.scratch
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.targets = Targets::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records merge + blur. Inputs and outputs in `GENERAL` (G-buffer read-only);
    /// `reflection` ends visible to compute reads.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        frame: &Buffer,
        gbuffer: &GBuffer,
        fail_mask: &Image,
        ssr: &Image,
        rt: &Image,
        rt_enabled: bool,
        reflective_min: f32,
        blur: BlurParams,
    ) {
        let d = &self.ctx.device;
        let t = &self.targets;
        let e = t.reflection.extent;
        let s = &self.sampler;
        // merge → reflection, blur H → scratch, blur V → reflection.
        // WAR: the previous frame's blur reads of the tile bits finish before they are zeroed.
        barrier::record(
            d,
            cmd,
            &[barrier::memory(access::COMPUTE_READ, access::TRANSFER_WRITE)],
            &[],
        );
        unsafe { d.cmd_fill_buffer(cmd, t.tile_sources.raw, 0, vk::WHOLE_SIZE, 0) };
        // RAW/WAW: the merge's atomics see the zeroed tile bits.
        barrier::record(
            d,
            cmd,
            &[barrier::memory(access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE)],
            &[],
        );
        self.merge.bind(
            cmd,
            &[
                Resource::Buffer(frame),
                Resource::StorageImage(fail_mask),
                Resource::StorageImage(ssr),
                Resource::StorageImage(rt),
                Resource::Sampled(&gbuffer.normal, s),
                Resource::Sampled(&gbuffer.material, s),
                Resource::StorageImage(&t.reflection),
                Resource::Buffer(&t.tile_sources),
            ],
            bytemuck::bytes_of(&MergePush {
                reflective_min,
                rt_enabled: rt_enabled as u32,
            }),
        );
        self.merge.dispatch_covering(cmd, [e.width, e.height, 1]);
        if blur.radius == 0 {
            // RAW: compose reads the merged reflection.
            barrier::record(
                d,
                cmd,
                &[barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ)],
                &[],
            );
            return;
        }
        let rw = access::COMPUTE_READ_WRITE;
        for axis in [[1, 0], [0, 1]] {
            // RAW: this blur pass reads what the previous step wrote (images and tile
            // buffers); WAR: it overwrites what the previous step read.
            barrier::record(
                d,
                cmd,
                &[
                    barrier::memory(access::COMPUTE_WRITE, rw),
                    barrier::memory(access::COMPUTE_READ, rw),
                ],
                &[],
            );
            let push = BlurPush {
                axis,
                radius: blur.radius as i32,
                band: blur.band as i32,
            };
            self.blur.bind(
                cmd,
                &[
                    Resource::Buffer(frame),
                    Resource::StorageImage(&t.reflection),
                    Resource::StorageImage(&t.scratch),
                    Resource::Buffer(&t.tile_sources),
                    Resource::Buffer(&t.tile_active),
                ],
                bytemuck::bytes_of(&push),
            );
            // The same tile grid as the merge, so tile indices agree.
            self.blur.dispatch_covering(cmd, [e.width, e.height, 1]);
        }
        // RAW: compose reads the blurred reflection.
        barrier::record(
            d,
            cmd,
            &[barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ)],
            &[],
        );
    }
}
