//! `rt.reflect`: the compacted pixels' reflection rays through the static
//! and dynamic BVHs, shaded, with recursive bounces; an indirect dispatch sized by
//! `ssr.compact`.
//! CPU reference: `cpu_ref::reflect::reflected_radiance` (tests/suite/rt_reflect.rs).

use super::GBuffer;
use super::{CompactOutputs, Surfaces, TraceScene};
use crate::error::Result;
use crate::settings::Shadows;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "rt.reflect";
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReflectPush {
    max_bounces: u32,
    static_tris: u32,
    dynamic_tris: u32,
    shadows: u32,
}

pub struct RtReflectPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// Reflected radiance of the listed pixels (others are left as they were); always
    /// `GENERAL`.
    pub out: Image,
}

/// What the reflection tracer needs besides the G-buffer.
pub struct ReflectInputs<'a> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    pub surfaces: Surfaces<'a>,
    pub shadow_map: &'a Image,
    pub list: &'a CompactOutputs,
    pub scene: TraceScene<'a>,
}

impl RtReflectPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<ReflectPush>(ctx, NAME, shaders::RT_REFLECT_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "rt.sampler")?,
            out: Image::storage(ctx, "rt.color", extent, FORMAT)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = Image::storage(&self.ctx, "rt.color", extent, FORMAT)?;
        Ok(())
    }

    /// Records the indirect dispatch over the list (visible to compute reads and
    /// indirect dispatch). `color` ends visible to its reader, `reflect.merge`.
    /// `shadows`: how the hits are shadowed (the `shadows` setting).
    pub fn record(&self, cmd: vk::CommandBuffer, inputs: &ReflectInputs<'_>, max_bounces: u32, shadows: Shadows) {
        let ([sn, sv, si, dn, dv, di, st, dt], static_tris, dynamic_tris) = inputs.scene.bindings();
        let push = ReflectPush {
            max_bounces,
            static_tris,
            dynamic_tris,
            shadows: shadows.gpu(),
        };
        let s = &self.sampler;
        let d = &self.ctx.device;
        // WAR/WAW: the previous frame's merge reads and tracer writes of the colour are done.
        barrier::global(d, cmd, access::COMPUTE_ANY, access::COMPUTE_WRITE);
        self.pipeline.dispatch(
            cmd,
            &[
                Resource::Buffer(inputs.frame),
                Resource::Sampled(&inputs.gbuffer.depth, s),
                Resource::Sampled(&inputs.gbuffer.normal, s),
                Resource::Buffer(inputs.surfaces.materials),
                Resource::Sampled(inputs.shadow_map, s),
                Resource::Buffer(&inputs.list.pixels),
                Resource::Buffer(&inputs.list.indirect),
                Resource::StorageImage(&self.out),
                sn,
                sv,
                si,
                dn,
                dv,
                di,
                st,
                dt,
                Resource::Buffer(inputs.surfaces.uvs[0]),
                Resource::Buffer(inputs.surfaces.uvs[1]),
                Resource::Sampled(inputs.surfaces.textures, inputs.surfaces.sampler),
            ],
            &push,
            Groups::Indirect(&inputs.list.indirect),
        );
        // RAW: the merge reads the ray-traced colour.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
