//! `reflect.denoise`: the edge-aware, variance-guided spatial filter of glossy
//! reflections over the merged reflection (`glsl/reflect_denoise.comp` says what it
//! weighs), then their temporal accumulation with reprojection, disocclusion and
//! history clamping (`glsl/reflect_temporal.comp`). Mirror pixels pass through
//! unchanged. CPU reference: `cpu_ref::denoise`.

use super::GBuffer;
use crate::error::Result;
use crate::gpu_types::FrameUniforms;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use std::sync::Arc;

pub const NAME: &str = "reflect.denoise";
/// Linear HDR reflection, as `reflect.merge`'s.
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct DenoisePush {
    radius: u32,
    reflective_min: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct TemporalPush {
    prev_view_proj: [f32; 16],
    prev_camera: [f32; 4],
    reflective_min: f32,
    max_frames: u32,
}

/// The filter's settings.
#[derive(Clone, Copy, Debug)]
pub struct DenoiseParams {
    /// The spatial filter's largest radius in pixels (`denoise_radius`; 0: off).
    pub radius: u32,
    /// The temporal running mean's longest window in frames (`denoise_history`; 0 or 1: off).
    pub history: u32,
    pub reflective_min: f32,
}

/// Where the history stands (`DenoisePass::sequence`), to record a frame again as if
/// the last try had not been.
#[derive(Clone, Copy)]
pub struct Sequence {
    parity: usize,
    past: Option<Past>,
}

/// The view a history was made from.
#[derive(Clone, Copy)]
struct Past {
    view_proj: Mat4,
    camera: Vec4,
    frame_index: u32,
}

/// What the filter reads, and the image it leaves its result in.
pub struct DenoiseInputs<'a> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    /// The merged reflection (`GENERAL`; rgb, a: source): read, then its glossy pixels
    /// overwritten with their filtered reflection.
    pub merged: &'a Image,
    /// `ssr.classify`'s list of glossy pixels and its indirect arguments.
    pub list: &'a Buffer,
    pub list_args: &'a Buffer,
    /// The reflected rays' mean distance to their hits (`GENERAL`).
    pub hit_distance: &'a Image,
}

pub struct DenoisePass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    temporal: Pipeline,
    sampler: Sampler,
    /// The spatially filtered reflection (rgb, a: the source, unchanged); always `GENERAL`.
    pub out: Image,
    /// The accumulated reflection (rgb, a: the source) and its distance and frame count
    /// per pixel, of the last two frames (`parity` is the latest).
    history: [Image; 2],
    meta: [Image; 2],
    parity: usize,
    /// The last frame accumulated, if the last frame recorded was.
    past: Option<Past>,
}

impl DenoisePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<DenoisePush>(ctx, NAME, shaders::REFLECT_DENOISE_COMP)?,
            temporal: Pipeline::compute::<TemporalPush>(ctx, "reflect.temporal", shaders::REFLECT_TEMPORAL_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "denoise.sampler")?,
            out: Image::storage(ctx, "denoise.out", extent, FORMAT)?,
            history: Self::pair(ctx, "denoise.history", extent)?,
            meta: Self::meta_pair(ctx, extent)?,
            parity: 0,
            past: None,
        })
    }

    fn pair(ctx: &Arc<Context>, name: &str, extent: vk::Extent2D) -> Result<[Image; 2]> {
        Ok([
            Image::storage(ctx, name, extent, FORMAT)?,
            Image::storage(ctx, name, extent, FORMAT)?,
        ])
    }

    /// The history's meta images, cleared to a stamp no frame writes (-1): a pixel no
    /// frame of this pass has written is never taken for last frame's, whatever the
    /// memory held before (another renderer's history, on the same allocator, made
    /// frames differ between runs of one process).
    fn meta_pair(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<[Image; 2]> {
        let meta = Self::pair(ctx, "denoise.meta", extent)?;
        let never = vk::ClearColorValue {
            float32: [0.0, 0.0, -1.0, 0.0],
        };
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        ctx.one_shot(|cmd| {
            for m in &meta {
                // SAFETY: `cmd` is recording; the image is in `GENERAL` (`Image::storage`)
                // and nothing else uses it yet.
                unsafe {
                    ctx.device
                        .cmd_clear_color_image(cmd, m.raw, vk::ImageLayout::GENERAL, &never, &[range])
                };
            }
            // RAW: the temporal step's reads of the meta come after the clear.
            barrier::global(&ctx.device, cmd, access::TRANSFER_WRITE, access::COMPUTE_ANY);
        })?;
        Ok(meta)
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = Image::storage(&self.ctx, "denoise.out", extent, FORMAT)?;
        self.history = Self::pair(&self.ctx, "denoise.history", extent)?;
        self.meta = Self::meta_pair(&self.ctx, extent)?;
        self.past = None;
        Ok(())
    }

    /// Where the history stands now.
    pub fn sequence(&self) -> Sequence {
        Sequence {
            parity: self.parity,
            past: self.past,
        }
    }

    /// Back to `s`: the frame recorded next reads the history `s` saw (a frame writes
    /// only the other history image, so the one it read is still there).
    pub fn restore(&mut self, s: Sequence) {
        (self.parity, self.past) = (s.parity, s.past);
    }

    /// Forgets the history: the next frame accumulates from scratch.
    pub fn reset_history(&mut self) {
        self.past = None;
    }

    /// The last frame's accumulated reflection and its meta (distance, frames) per pixel.
    pub fn history(&self) -> (&Image, &Image) {
        (&self.history[self.parity], &self.meta[self.parity])
    }

    /// Records the filters of the frame `frame` describes (its camera and frame index)
    /// over the glossy pixels' list: the spatial one into `out`, then the temporal one
    /// (a plain copy with `params.history` <= 1), whose history is used only when the
    /// previous frame recorded was the one before this, into `merged`'s glossy pixels
    /// and the history. The G-buffer in `SHADER_READ_ONLY_OPTIMAL`; the list and its
    /// arguments visible to compute reads and indirect dispatch. `merged` ends visible
    /// to its reader, `compose`.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        inputs: &DenoiseInputs<'_>,
        params: DenoiseParams,
        frame: &FrameUniforms,
    ) {
        let d = &self.ctx.device;
        let s = &self.sampler;
        let g = inputs.gbuffer;
        // WAR: the previous frame's reads of `out` and of the history finish before
        // they are overwritten; WAW/WAR on `merged`: the merge's writes and reads are
        // done before the temporal step writes it.
        barrier::global(d, cmd, access::COMPUTE_ANY, access::COMPUTE_ANY);
        let push = DenoisePush {
            radius: params.radius,
            reflective_min: params.reflective_min,
        };
        // What both steps read.
        let shared = [
            ("frame", Resource::Buffer(inputs.frame)),
            ("gb_depth", Resource::Sampled(&g.depth, s)),
            ("gb_normal", Resource::Sampled(&g.normal, s)),
            ("gb_albedo", Resource::Sampled(&g.albedo, s)),
            ("glossy_list", Resource::Buffer(inputs.list)),
            ("glossy_args", Resource::Buffer(inputs.list_args)),
        ];
        let own = [
            ("merged", Resource::StorageImage(inputs.merged)),
            ("denoised", Resource::StorageImage(&self.out)),
            ("hit_distance", Resource::StorageImage(inputs.hit_distance)),
        ];
        let resources = [&shared[..], &own].concat();
        self.pipeline
            .dispatch(cmd, &resources, &push, Groups::Indirect(inputs.list_args));
        // RAW: the temporal step reads the filtered reflection.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
        let accumulate = params.history > 1;
        let valid = self
            .past
            .filter(|p| accumulate && p.frame_index.wrapping_add(1) == frame.frame_index);
        let prev = valid.unwrap_or(Past {
            view_proj: Mat4::IDENTITY,
            camera: Vec4::ZERO,
            frame_index: 0,
        });
        let push = TemporalPush {
            prev_view_proj: prev.view_proj.to_cols_array(),
            prev_camera: prev.camera.truncate().extend(valid.is_some() as u32 as f32).to_array(),
            reflective_min: params.reflective_min,
            max_frames: params.history.max(1),
        };
        let (old, new) = (self.parity, 1 - self.parity);
        let own = [
            ("current", Resource::StorageImage(&self.out)),
            ("history_in", Resource::StorageImage(&self.history[old])),
            ("meta_in", Resource::StorageImage(&self.meta[old])),
            ("history_out", Resource::StorageImage(&self.history[new])),
            ("meta_out", Resource::StorageImage(&self.meta[new])),
            ("merged", Resource::StorageImage(inputs.merged)),
            ("gb_motion", Resource::Sampled(&g.motion, s)),
        ];
        let resources = [&shared[..], &own].concat();
        self.temporal
            .dispatch(cmd, &resources, &push, Groups::Indirect(inputs.list_args));
        // RAW: compose reads the merged reflection (and the next frame the history).
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
        self.parity = new;
        self.past = accumulate.then_some(Past {
            view_proj: frame.view_proj,
            camera: frame.camera_pos,
            frame_index: frame.frame_index,
        });
    }
}
