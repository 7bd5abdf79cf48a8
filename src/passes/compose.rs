//! `compose`: exposure, ACES tonemap and sRGB encoding of the HDR frame into the LDR
//! image that is presented or saved. CPU reference: `cpu_ref::compose`.

use crate::error::Result;
use crate::shaders;
use crate::vk::{Context, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "compose";
/// sRGB-encoded values in a UNORM image (storage images cannot be SRGB).
pub const FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// Push constants of `compose.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ComposePush {
    pub size: [u32; 2],
    pub exposure: f32,
    /// `COMPOSE_PLAIN`, `COMPOSE_REFLECT` or `COMPOSE_PROVENANCE`.
    pub mode: u32,
}

/// The reflection and the surface data compose weighs it with.
pub struct ComposeInputs<'a> {
    pub hdr: &'a Image,
    /// Merged reflection (rgb, a: source); read unless the mode is `COMPOSE_PLAIN`.
    pub reflection: &'a Image,
    /// G-buffer normal + reflectivity.
    pub normal: &'a Image,
}

pub struct ComposePass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    sampler: Sampler,
    /// The tonemapped frame; `GENERAL` between frames.
    pub ldr: Image,
}

fn ldr_image(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Image> {
    Image::new(
        ctx,
        "compose.ldr",
        extent,
        FORMAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST,
    )
}

impl ComposePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let pipeline = Pipeline::compute(
            ctx,
            NAME,
            ("compose.comp", shaders::COMPOSE_COMP),
            std::mem::size_of::<ComposePush>() as u32,
        )?;
        Ok(Self {
            ctx: ctx.clone(),
            pipeline,
            sampler: Sampler::nearest_clamp(ctx, "compose.sampler")?,
            ldr: ldr_image(ctx, extent)?,
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.ldr = ldr_image(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the tonemap. `hdr`, `reflection` and `ldr` in `GENERAL`, `normal` in
    /// `SHADER_READ_ONLY_OPTIMAL`, all of the render size.
    pub fn record(&self, cmd: vk::CommandBuffer, inputs: &ComposeInputs<'_>, exposure: f32, mode: u32) {
        let e = self.ldr.extent;
        let push = ComposePush {
            size: [e.width, e.height],
            exposure,
            mode,
        };
        self.pipeline.bind(
            cmd,
            &[
                Resource::StorageImage(inputs.hdr),
                Resource::StorageImage(&self.ldr),
                Resource::StorageImage(inputs.reflection),
                Resource::Sampled(inputs.normal, &self.sampler),
            ],
            bytemuck::bytes_of(&push),
        );
        self.pipeline.dispatch_covering(cmd, [e.width, e.height, 1]);
    }
}
