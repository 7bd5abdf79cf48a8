//! `rt.trace` for reflections: the compacted pixels' reflection rays through the static
//! and dynamic BVHs, shaded, with recursive bounces; an indirect dispatch sized by
//! `ssr.compact`.

use super::gbuffer::GBuffer;
use super::rt_trace::TraceScene;
use super::ssr_compact::CompactOutputs;
use crate::error::Result;
use crate::shaders;
use crate::vk::{Buffer, Context, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "rt.trace";
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReflectPush {
    max_bounces: u32,
    static_tris: u32,
    dynamic_tris: u32,
    shadow_rays: u32,
}

pub struct RtReflectPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// Reflected radiance of the listed pixels (others are left as they were).
    pub color: Image,
}

fn color_image(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Image> {
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
    Image::new(ctx, "rt.color", extent, FORMAT, usage)
}

/// What the reflection tracer needs besides the G-buffer.
pub struct ReflectInputs<'a> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    pub materials: &'a Buffer,
    pub shadow_map: &'a Image,
    pub list: &'a CompactOutputs,
    pub scene: TraceScene<'a>,
}

impl RtReflectPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let push = std::mem::size_of::<ReflectPush>() as u32;
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute(ctx, NAME, ("rt_reflect.comp", shaders::RT_REFLECT_COMP), push)?,
            sampler: Sampler::nearest_clamp(ctx, "rt.sampler")?,
            color: color_image(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.color = color_image(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the indirect dispatch. `color` in `GENERAL`; the list and its arguments
    /// visible to compute reads and indirect dispatch.
    pub fn record(&self, cmd: vk::CommandBuffer, inputs: &ReflectInputs<'_>, max_bounces: u32, shadow_rays: bool) {
        let ([sn, sv, si, dn, dv, di], static_tris, dynamic_tris) = inputs.scene.bindings();
        let push = ReflectPush {
            max_bounces,
            static_tris,
            dynamic_tris,
            shadow_rays: shadow_rays as u32,
        };
        let s = &self.sampler;
        self.pipeline.bind(
            cmd,
            &[
                Resource::Buffer(inputs.frame),
                Resource::Sampled(&inputs.gbuffer.depth, s),
                Resource::Sampled(&inputs.gbuffer.normal, s),
                Resource::Buffer(inputs.materials),
                Resource::Sampled(inputs.shadow_map, s),
                Resource::Buffer(&inputs.list.pixels),
                Resource::Buffer(&inputs.list.indirect),
                Resource::StorageImage(&self.color),
                sn,
                sv,
                si,
                dn,
                dv,
                di,
            ],
            bytemuck::bytes_of(&push),
        );
        unsafe { self.ctx.device.cmd_dispatch_indirect(cmd, inputs.list.indirect.raw, 0) };
    }
}
