//! `compose`: exposure, ACES tonemap and sRGB encoding of the HDR frame into the LDR
//! image that is presented or saved. CPU reference: `cpu_ref::compose`.

use super::GBuffer;
use crate::error::Result;
use crate::shader_defines::{COMPOSE_FAIL_MASK, COMPOSE_PLAIN, COMPOSE_PROVENANCE, COMPOSE_REFLECT};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "compose";
/// sRGB-encoded values in a UNORM image (storage images cannot be SRGB).
pub const FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// What `compose` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposeMode {
    /// The lit colour alone (the `raster` mode).
    Plain,
    /// The lit colour plus the merged reflection weighted by reflectivity x Fresnel.
    Reflect,
    /// Each pixel painted by the source of its reflection.
    Provenance,
    /// Each reflective pixel painted by its fail-mask reason (`ReflectionMaps::fail_mask_rgba`).
    FailMask,
}

impl ComposeMode {
    /// The shader's `COMPOSE_*` value.
    fn code(self) -> u32 {
        match self {
            ComposeMode::Plain => COMPOSE_PLAIN,
            ComposeMode::Reflect => COMPOSE_REFLECT,
            ComposeMode::Provenance => COMPOSE_PROVENANCE,
            ComposeMode::FailMask => COMPOSE_FAIL_MASK,
        }
    }
}

/// Push constants of `compose.comp` (public for the layout test).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ComposePush {
    pub size: [u32; 2],
    pub exposure: f32,
    /// `COMPOSE_PLAIN`, `COMPOSE_REFLECT`, `COMPOSE_PROVENANCE` or `COMPOSE_FAIL_MASK`.
    pub mode: u32,
    /// `COMPOSE_FAIL_MASK`: reflectivity above which a pixel reflects.
    pub reflective_min: f32,
}

/// The reflection and the surface data compose weighs it with.
pub struct ComposeInputs<'a> {
    pub frame: &'a Buffer,
    pub hdr: &'a Image,
    /// Merged reflection (rgb, a: source); read unless the mode is `Plain`.
    pub reflection: &'a Image,
    /// The G-buffer (normal + reflectivity, base colour, depth, material id, metallic),
    /// for the reflection's Fresnel weight.
    pub gbuffer: &'a GBuffer,
    /// The SSR fail mask (`GENERAL`); read by `FailMask` only.
    pub fail_mask: &'a Image,
    /// `FailMask`: reflectivity above which a pixel reflects (`Settings::reflective_min`).
    pub reflective_min: f32,
}

pub struct ComposePass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// The tonemapped frame; always `GENERAL`.
    pub out: Image,
}

impl ComposePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<ComposePush>(ctx, NAME, shaders::COMPOSE_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "compose.sampler")?,
            out: Image::storage(ctx, "compose.ldr", extent, FORMAT)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = Image::storage(&self.ctx, "compose.ldr", extent, FORMAT)?;
        Ok(())
    }

    /// Records the tonemap. `hdr` and `reflection` in `GENERAL`, the G-buffer in
    /// `SHADER_READ_ONLY_OPTIMAL`, all of the render size. `ldr` ends visible to its
    /// readers: copies out of it (readbacks, a blit to a window).
    pub fn record(&self, cmd: vk::CommandBuffer, inputs: &ComposeInputs<'_>, exposure: f32, mode: ComposeMode) {
        let d = &self.ctx.device;
        let e = self.out.extent;
        let push = ComposePush {
            size: [e.width, e.height],
            exposure,
            mode: mode.code(),
            reflective_min: inputs.reflective_min,
        };
        // WAR: earlier copies out of the LDR image finish before it is overwritten.
        barrier::global(d, cmd, access::TRANSFER_READ, access::COMPUTE_WRITE);
        self.pipeline.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(inputs.frame)),
                ("hdr", Resource::StorageImage(inputs.hdr)),
                ("ldr", Resource::StorageImage(&self.out)),
                ("reflection", Resource::StorageImage(inputs.reflection)),
                ("gb_normal", Resource::Sampled(&inputs.gbuffer.normal, &self.sampler)),
                ("gb_albedo", Resource::Sampled(&inputs.gbuffer.albedo, &self.sampler)),
                ("gb_depth", Resource::Sampled(&inputs.gbuffer.depth, &self.sampler)),
                (
                    "gb_material",
                    Resource::Sampled(&inputs.gbuffer.material, &self.sampler),
                ),
                ("gb_motion", Resource::Sampled(&inputs.gbuffer.motion, &self.sampler)),
                ("fail_mask", Resource::StorageImage(inputs.fail_mask)),
            ],
            &push,
            Groups::Cover([e.width, e.height, 1]),
        );
        // RAW: copies read the finished frame.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::TRANSFER_READ);
    }
}
