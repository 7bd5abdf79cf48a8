//! `ssr.trace`: screen-space reflections (McGuire & Mara 2014 DDA) and the fail mask.

use super::gbuffer::GBuffer;
use super::ssr_compact::MASK_FORMAT;
use crate::error::Result;
use crate::shaders;
use crate::vk::{Buffer, Context, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "ssr.trace";
/// rgb: reflected colour found on screen; a: confidence (0 where SSR failed).
pub const COLOR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Push constants of `ssr_trace.comp` (see `Settings` for what each trades).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SsrParams {
    pub max_steps: u32,
    pub stride: f32,
    pub thickness: f32,
    pub max_distance: f32,
    pub edge_fade: f32,
    pub min_confidence: f32,
    pub reflective_min: f32,
    /// Hits on surfaces more reflective than this fail (need the ray tracer's bounce).
    pub recursion_min: f32,
}

pub struct SsrOutputs {
    pub color: Image,
    /// Fail reasons per pixel (`FAIL_*` bits); nonzero sends the pixel to rt.trace.
    pub mask: Image,
}

impl SsrOutputs {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let usage =
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
        Ok(Self {
            color: Image::new(ctx, "ssr.color", extent, COLOR_FORMAT, usage)?,
            mask: Image::new(ctx, "ssr.fail_mask", extent, MASK_FORMAT, usage)?,
        })
    }
}

pub struct SsrPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    /// The `rt` mode's variant (`MASK_ONLY`): no SSR, every reflective pixel fails.
    mask_only: Pipeline,
    sampler: Sampler,
    pub out: SsrOutputs,
}

impl SsrPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let push = std::mem::size_of::<SsrParams>() as u32;
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute(ctx, NAME, ("ssr_trace.comp", shaders::SSR_TRACE_COMP), push)?,
            mask_only: Pipeline::compute_specialized(
                ctx,
                "ssr.mask_only",
                ("ssr_trace.comp", shaders::SSR_TRACE_COMP),
                push,
                &[1],
            )?,
            sampler: Sampler::nearest_clamp(ctx, "ssr.sampler")?,
            out: SsrOutputs::new(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = SsrOutputs::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the march, or with `mask_only` (the `rt` mode) only the fail mask, every
    /// reflective pixel failed (`FAIL_FORCED`). G-buffer in `SHADER_READ_ONLY_OPTIMAL`;
    /// `lit` and the outputs in `GENERAL`.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        frame: &Buffer,
        gbuffer: &GBuffer,
        lit: &Image,
        params: &SsrParams,
        mask_only: bool,
    ) {
        let s = &self.sampler;
        let pipeline = if mask_only { &self.mask_only } else { &self.pipeline };
        pipeline.bind(
            cmd,
            &[
                Resource::Buffer(frame),
                Resource::Sampled(&gbuffer.depth, s),
                Resource::Sampled(&gbuffer.normal, s),
                Resource::Sampled(&gbuffer.material, s),
                Resource::StorageImage(lit),
                Resource::StorageImage(&self.out.color),
                Resource::StorageImage(&self.out.mask),
            ],
            bytemuck::bytes_of(params),
        );
        let e = self.out.color.extent;
        pipeline.dispatch_covering(cmd, [e.width, e.height, 1]);
    }
}
