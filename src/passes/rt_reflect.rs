//! `rt.reflect`: the compacted pixels' reflection rays through the static
//! and dynamic BVHs, shaded, with recursive bounces; an indirect dispatch sized by
//! `ssr.compact`. With the vendor tracer the same path (`glsl/shared/reflect_path.glsl`)
//! runs as a ray-generation shader through the scene's acceleration structures, one
//! launch per entry, sized on the GPU (`tracers::TRACE_RAYS_ARGS`). The pass holds
//! the output; the kernel, made for one tracer, is its own value (`Kernel<T>`), so the
//! renderer keeps one tracer's kernels together with that tracer's structures.
//! CPU reference: `cpu_ref::reflect::reflected_radiance` (tests/suite/rt_reflect.rs).

use super::GBuffer;
use super::{CompactOutputs, Surfaces};
use crate::error::Result;
use crate::settings::Shadows;
use crate::shaders;
use crate::tracers::{Rays, TraceKernel, Tracer};
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

/// `rt.reflect`'s kernel for tracer `T`.
pub struct Kernel<T: Tracer>(TraceKernel<T>);

impl<T: Tracer> Kernel<T> {
    /// The kernel (the vendor tracer's needs a context with ray tracing).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let (comp, rgen) = (shaders::RT_REFLECT_COMP, shaders::RT_REFLECT_RGEN);
        Ok(Self(TraceKernel::new::<ReflectPush>(ctx, NAME, comp, rgen)?))
    }
}

pub struct RtReflectPass {
    ctx: Arc<Context>,
    sampler: Sampler,
    /// Reflected radiance of the listed pixels (others are left as they were); always
    /// `GENERAL`.
    pub out: Image,
}

/// What the reflection tracer needs besides the G-buffer.
pub struct ReflectInputs<'a, T: Tracer> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    pub surfaces: Surfaces<'a>,
    pub shadow_map: &'a Image,
    pub list: &'a CompactOutputs,
    pub scene: T::Scene<'a>,
    /// Where the traced pixels' mean first-hit distance goes (`GENERAL`; `ssr.classify`
    /// and `ssr.trace` wrote the rest), for `reflect.denoise`.
    pub hit_distance: &'a Image,
}

impl RtReflectPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            sampler: Sampler::nearest_clamp(ctx, "rt.sampler")?,
            out: Image::storage(ctx, "rt.color", extent, FORMAT)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = Image::storage(&self.ctx, "rt.color", extent, FORMAT)?;
        Ok(())
    }

    /// Records `kernel` over the list (visible to compute reads and indirect
    /// dispatch). `color` ends visible to its reader, `reflect.merge`. `shadows`: how
    /// the hits are shadowed (the `shadows` setting).
    pub fn record<T: Tracer>(
        &self,
        cmd: vk::CommandBuffer,
        kernel: &Kernel<T>,
        inputs: &ReflectInputs<'_, T>,
        max_bounces: u32,
        shadows: Shadows,
    ) {
        let push = |static_tris, dynamic_tris| ReflectPush {
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
        // WAR/WAW: the previous frame's merge reads and tracer writes of the colour are
        // done (and, for the vendor tracer, the compute passes' list, arguments and
        // images before its ray-tracing shaders read them).
        barrier::global(d, cmd, access::COMPUTE_ANY, T::RUNS);
        let rays = Rays::Listed(&inputs.list.indirect);
        kernel.0.run(cmd, &own, &inputs.scene, push, rays);
        // RAW: the merge reads the ray-traced colour.
        barrier::global(d, cmd, T::WRITES, access::COMPUTE_READ);
    }
}
