//! `light.direct`: deferred shading of the G-buffer with the sun, shadowed by the
//! PCF-filtered shadow map or by the visibility `shadow.trace` left, and the sky
//! ambient, into an HDR image. CPU reference: `cpu_ref::shading`.

use super::GBuffer;
use crate::error::Result;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use std::sync::Arc;

pub const NAME: &str = "light.direct";
/// Linear HDR colour. rgba32f rather than rgba16f: lavapipe's storage-image path for
/// 16-bit floats was over 40x slower in `compose` at 960x540 (see the issue notes); on
/// GPUs the extra bandwidth is small next to the reflection passes.
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Where the sun's visibility comes from.
#[derive(Clone, Copy)]
pub struct Sun<'a> {
    /// The shadow map (`SHADER_READ_ONLY_OPTIMAL`).
    pub map: &'a Image,
    /// Per-pixel visibility (`GENERAL`, `shadow_trace::VISIBILITY_FORMAT`): read when
    /// `traced`, else written with the map's.
    pub visibility: &'a Image,
    /// Read `visibility` (the shadows are `rays` or `hybrid`) instead of the map.
    pub traced: bool,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightPush {
    traced: u32,
}

pub struct LightDirectPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// Lit HDR colour (linear, `FORMAT`); always `GENERAL`.
    pub out: Image,
}

impl LightDirectPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<LightPush>(ctx, NAME, shaders::LIGHT_DIRECT_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "light.sampler")?,
            out: Image::storage(ctx, "light.lit", extent, FORMAT)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = Image::storage(&self.ctx, "light.lit", extent, FORMAT)?;
        Ok(())
    }

    /// Records the shading dispatch. G-buffer in `SHADER_READ_ONLY_OPTIMAL`. `lit` ends
    /// visible to its readers, `ssr.trace` and `compose` (compute).
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &Buffer, gbuffer: &GBuffer, sun: Sun<'_>) {
        let d = &self.ctx.device;
        let s = &self.sampler;
        // WAR: the previous frame's reads of `lit` finish before it is overwritten.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        let e = self.out.extent;
        self.pipeline.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("gb_depth", Resource::Sampled(&gbuffer.depth, s)),
                ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
                ("gb_albedo", Resource::Sampled(&gbuffer.albedo, s)),
                ("gb_material", Resource::Sampled(&gbuffer.material, s)),
                ("shadow_map", Resource::Sampled(sun.map, s)),
                ("lit", Resource::StorageImage(&self.out)),
                ("gb_motion", Resource::Sampled(&gbuffer.motion, s)),
                ("visibility", Resource::StorageImage(sun.visibility)),
            ],
            &LightPush {
                traced: sun.traced as u32,
            },
            Groups::Cover([e.width, e.height, 1]),
        );
        // RAW: ssr.trace and compose read the lit colour.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
