//! `light.direct`: deferred shading of the G-buffer with the sun, PCF-filtered shadow
//! map and sky ambient, into an HDR image. CPU reference: `cpu_ref::shading`.

use super::gbuffer::GBuffer;
use crate::error::Result;
use crate::shaders;
use crate::vk::{Buffer, Context, Image, Pipeline, Resource, Sampler};
use ash::vk;
use std::sync::Arc;

pub const NAME: &str = "light.direct";
/// Linear HDR colour. rgba32f rather than rgba16f: lavapipe's storage-image path for
/// 16-bit floats was over 40x slower in `compose` at 960x540 (see the issue notes); on
/// GPUs the extra bandwidth is small next to the reflection passes.
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct LightDirectPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// Lit HDR colour (linear, rgba16f); `GENERAL` between frames.
    pub lit: Image,
}

fn lit_image(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Image> {
    Image::new(
        ctx,
        "light.lit",
        extent,
        FORMAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST,
    )
}

impl LightDirectPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute(ctx, NAME, ("light_direct.comp", shaders::LIGHT_DIRECT_COMP), 0)?,
            sampler: Sampler::nearest_clamp(ctx, "light.sampler")?,
            lit: lit_image(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.lit = lit_image(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the shading dispatch. G-buffer and shadow map must be in
    /// `SHADER_READ_ONLY_OPTIMAL`, `lit` in `GENERAL`.
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &Buffer, gbuffer: &GBuffer, shadow_map: &Image) {
        let s = &self.sampler;
        self.pipeline.bind(
            cmd,
            &[
                Resource::Buffer(frame),
                Resource::Sampled(&gbuffer.depth, s),
                Resource::Sampled(&gbuffer.normal, s),
                Resource::Sampled(&gbuffer.albedo, s),
                Resource::Sampled(&gbuffer.material, s),
                Resource::Sampled(shadow_map, s),
                Resource::StorageImage(&self.lit),
            ],
            &[],
        );
        let e = self.lit.extent;
        self.pipeline.dispatch_covering(cmd, [e.width, e.height, 1]);
    }
}
