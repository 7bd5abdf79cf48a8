//! `rt.reflect`: the compacted pixels' reflection rays through the static
//! and dynamic BVHs, shaded, with recursive bounces; an indirect dispatch sized by
//! `ssr.compact`. With the vendor tracer the same path (`glsl/shared/reflect_path.glsl`)
//! runs as a ray-generation shader through the scene's acceleration structures, one
//! launch per entry, sized on the GPU (`TRACE_RAYS_ARGS`).
//! CPU reference: `cpu_ref::reflect::reflected_radiance` (tests/suite/rt_reflect.rs).

use super::GBuffer;
use super::{with_trace, CompactOutputs, Surfaces, TraceKernel, Tracing};
use crate::error::Result;
use crate::settings::{Shadows, Tracer};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Image, Resource, Sampler};
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
    kernel: TraceKernel,
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
    pub scene: Tracing<'a>,
    /// Where the traced pixels' mean first-hit distance goes (`GENERAL`; `ssr.classify`
    /// and `ssr.trace` wrote the rest), for `reflect.denoise`.
    pub hit_distance: &'a Image,
}

impl RtReflectPass {
    /// The pass for `tracer` (`khr` needs a context with ray tracing).
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D, tracer: Tracer) -> Result<Self> {
        let (comp, rgen) = (shaders::RT_REFLECT_COMP, shaders::RT_REFLECT_RGEN);
        let kernel = TraceKernel::new::<ReflectPush>(ctx, NAME, tracer, comp, rgen)?;
        Ok(Self {
            ctx: ctx.clone(),
            kernel,
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
        let (trace, static_tris, dynamic_tris) = inputs.scene.bindings();
        let push = ReflectPush {
            max_bounces,
            static_tris,
            dynamic_tris,
            shadows: shadows.gpu(),
        };
        let s = &self.sampler;
        let d = &self.ctx.device;
        let own = [
            ("frame", Resource::Buffer(inputs.frame)),
            ("gb_depth", Resource::Sampled(&inputs.gbuffer.depth, s)),
            ("gb_normal", Resource::Sampled(&inputs.gbuffer.normal, s)),
            ("materials", Resource::Buffer(inputs.surfaces.materials)),
            ("shadow_map", Resource::Sampled(inputs.shadow_map, s)),
            ("pixels", Resource::Buffer(&inputs.list.pixels)),
            ("indirect", Resource::Buffer(&inputs.list.indirect)),
            ("rt_out", Resource::StorageImage(&self.out)),
            ("static_uvs", Resource::Buffer(inputs.surfaces.uvs[0])),
            ("dynamic_uvs", Resource::Buffer(inputs.surfaces.uvs[1])),
            (
                "scene_textures",
                Resource::Sampled(inputs.surfaces.textures, inputs.surfaces.sampler),
            ),
            ("gb_albedo", Resource::Sampled(&inputs.gbuffer.albedo, s)),
            ("hit_distance", Resource::StorageImage(inputs.hit_distance)),
        ];
        let resources = with_trace(&own, &trace);
        // WAR/WAW: the previous frame's merge reads and tracer writes of the colour are
        // done (and, for the vendor tracer, the compute passes' list, arguments and
        // images before its ray-tracing shaders read them).
        barrier::global(d, cmd, access::COMPUTE_ANY, self.kernel.runs());
        let k = &self.kernel;
        k.over_list(NAME, cmd, &resources, &push, inputs.list, &inputs.scene);
        // RAW: the merge reads the ray-traced colour.
        barrier::global(d, cmd, k.writes(), access::COMPUTE_READ);
    }
}
