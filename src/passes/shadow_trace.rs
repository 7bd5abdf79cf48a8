//! `shadow.classify` and `shadow.trace`: the sun's visibility of every pixel, from the
//! shadow map where it is sure and from shadow rays elsewhere (the `shadows` setting:
//! `rays` traces every lit pixel, `hybrid` only the pixels where the map is unsure;
//! `map` runs none of this). The same classify → compact → indirect-trace shape as the
//! reflections; between the two, `shadow.compact` is the reflections' compaction
//! (`ssr_compact::CompactPass`) run over this pass's mask.
//! `shadow.trace` runs through either tracer: its kernel, made for one, is its own
//! value (`Kernel<T>`), as `rt.reflect`'s is.
//! CPU reference: `cpu_ref::shadows` (tests/suite/shadows.rs).

use super::{CompactOutputs, GBuffer};
use crate::error::Result;
use crate::settings::Shadows;
use crate::shaders;
use crate::tracers::{Rays, TraceKernel, Tracer};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const CLASSIFY_NAME: &str = "shadow.classify";
pub const COMPACT_NAME: &str = "shadow.compact";
pub const NAME: &str = "shadow.trace";
/// The debug names of the shadow mask's compaction pipelines.
pub const COMPACT_PIPELINES: [&str; 3] = ["shadow.compact.count", "shadow.compact.scan", "shadow.compact.scatter"];
/// The shadow mask: `SHADOW_*` bits per pixel, nonzero means "gets a shadow ray".
pub const MASK_FORMAT: vk::Format = vk::Format::R32_UINT;
/// The sun's visibility per pixel, 0..1.
pub const VISIBILITY_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ClassifyPush {
    shadows: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TracePush {
    static_tris: u32,
    dynamic_tris: u32,
}

/// What the three steps leave; every image always `GENERAL`.
pub struct ShadowOutputs {
    /// Why each pixel got a shadow ray (`SHADOW_*` bits; 0: the map answered, or the
    /// pixel is sky or faces away from the sun).
    pub mask: Image,
    /// The sun's visibility of each pixel: what `light.direct` multiplies the sun by
    /// when the shadows are not `map`.
    pub visibility: Image,
}

/// `shadow.trace`'s kernel for tracer `T`.
pub struct Kernel<T: Tracer>(TraceKernel<T>);

impl<T: Tracer> Kernel<T> {
    /// The kernel (the vendor tracer's needs a context with ray tracing).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let (comp, rgen) = (shaders::SHADOW_TRACE_COMP, shaders::SHADOW_TRACE_RGEN);
        Ok(Self(TraceKernel::new::<TracePush>(ctx, NAME, comp, rgen)?))
    }
}

pub struct ShadowTracePass {
    ctx: Arc<Context>,
    classify: Pipeline,
    sampler: Sampler,
    pub out: ShadowOutputs,
}

impl ShadowOutputs {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            mask: Image::storage(ctx, "shadow.mask", extent, MASK_FORMAT)?,
            visibility: Image::storage(ctx, "shadow.visibility", extent, VISIBILITY_FORMAT)?,
        })
    }
}

impl ShadowTracePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            classify: Pipeline::compute::<ClassifyPush>(ctx, CLASSIFY_NAME, shaders::SHADOW_CLASSIFY_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "shadow.sampler")?,
            out: ShadowOutputs::new(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = ShadowOutputs::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records `shadow.classify` (`shadows` is `rays` or `hybrid`): the mask and the
    /// map's visibility. G-buffer and shadow map in `SHADER_READ_ONLY_OPTIMAL` (the map
    /// is not read under `rays`). Mask and visibility end visible to compute reads.
    pub fn classify(
        &self,
        cmd: vk::CommandBuffer,
        frame: &Buffer,
        gbuffer: &GBuffer,
        shadow_map: &Image,
        shadows: Shadows,
    ) {
        assert!(shadows.traces(), "shadow.classify under map shadows");
        let d = &self.ctx.device;
        let s = &self.sampler;
        // WAR: the previous frame's reads of the mask and visibility are done.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_WRITE);
        let e = self.out.mask.extent;
        self.classify.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("gb_depth", Resource::Sampled(&gbuffer.depth, s)),
                ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
                ("gb_material", Resource::Sampled(&gbuffer.material, s)),
                ("shadow_map", Resource::Sampled(shadow_map, s)),
                ("mask", Resource::StorageImage(&self.out.mask)),
                ("visibility", Resource::StorageImage(&self.out.visibility)),
            ],
            &ClassifyPush { shadows: shadows.gpu() },
            Groups::Cover([e.width, e.height, 1]),
        );
        // RAW: the compaction reads the mask.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }

    /// Records `shadow.trace` (`kernel`) over `list`, the mask's compaction (visible
    /// to compute reads and indirect dispatch): the listed pixels' visibility, from
    /// any-hit rays through `scene`. The visibility ends visible to compute reads
    /// (`light.direct`).
    pub fn trace<T: Tracer>(
        &self,
        cmd: vk::CommandBuffer,
        (kernel, scene): (&Kernel<T>, &T::Scene<'_>),
        frame: &Buffer,
        gbuffer: &GBuffer,
        list: &CompactOutputs,
    ) {
        let d = &self.ctx.device;
        let s = &self.sampler;
        let own = [
            ("frame", Resource::Buffer(frame)),
            ("gb_depth", Resource::Sampled(&gbuffer.depth, s)),
            ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
            ("pixels", Resource::Buffer(&list.pixels)),
            ("indirect", Resource::Buffer(&list.indirect)),
            ("visibility", Resource::StorageImage(&self.out.visibility)),
        ];
        let push = |static_tris, dynamic_tris| TracePush {
            static_tris,
            dynamic_tris,
        };
        if !T::COMPUTE {
            // RAW: the compaction's list and arguments and the G-buffer before the
            // ray-tracing shaders read them (the compute kernel's are made visible to
            // compute reads by the compaction).
            barrier::global(d, cmd, access::ALL_READ_WRITE, T::RUNS);
        }
        kernel.0.run(cmd, &own, scene, push, Rays::Listed(&list.indirect));
        // RAW: light.direct reads the visibility.
        barrier::global(d, cmd, T::WRITES, access::COMPUTE_READ);
    }
}
