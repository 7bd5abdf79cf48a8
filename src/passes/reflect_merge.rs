//! `reflect.merge`: SSR where it succeeded, ray-traced reflections where it failed,
//! labelled by source; then a separable Gaussian blur restricted to the band around
//! SSR/RT seams (horizontal, then vertical).

use super::gbuffer::GBuffer;
use crate::error::Result;
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
    /// Blur radius in pixels (0: no blur).
    pub radius: u32,
    /// Half-width in pixels of the band around seams that is blurred.
    pub band: u32,
}

pub struct MergePass {
    ctx: Arc<Context>,
    merge: Pipeline,
    blur: Pipeline,
    sampler: Sampler,
    /// The merged (and seam-blurred) reflection; `GENERAL` between frames.
    pub reflection: Image,
    scratch: Image,
}

fn images(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<(Image, Image)> {
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
    Ok((
        Image::new(ctx, "reflect.merged", extent, FORMAT, usage)?,
        Image::new(ctx, "reflect.scratch", extent, FORMAT, usage)?,
    ))
}

impl MergePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let (reflection, scratch) = images(ctx, extent)?;
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
            reflection,
            scratch,
        })
    }

    /// The blur's intermediate image (for layout transitions by the renderer).
    pub fn scratch(&self) -> &Image {
        &self.scratch
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        (self.reflection, self.scratch) = images(&self.ctx, extent)?;
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
        let e = self.reflection.extent;
        let s = &self.sampler;
        // merge → reflection, blur H → scratch, blur V → reflection.
        self.merge.bind(
            cmd,
            &[
                Resource::Buffer(frame),
                Resource::StorageImage(fail_mask),
                Resource::StorageImage(ssr),
                Resource::StorageImage(rt),
                Resource::Sampled(&gbuffer.normal, s),
                Resource::Sampled(&gbuffer.material, s),
                Resource::StorageImage(&self.reflection),
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
        let rw = (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_READ | vk::AccessFlags2::SHADER_WRITE,
        );
        for (axis, src, dst) in [
            ([1, 0], &self.reflection, &self.scratch),
            ([0, 1], &self.scratch, &self.reflection),
        ] {
            // RAW: this blur pass reads what the previous step wrote; WAR: it overwrites
            // the image the previous step read.
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
                    Resource::StorageImage(src),
                    Resource::StorageImage(dst),
                ],
                bytemuck::bytes_of(&push),
            );
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
