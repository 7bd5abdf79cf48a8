//! `ssr.classify` and `ssr.trace`: screen-space reflections and the fail mask. The march
//! steps through `ssr.hiz`'s min-depth pyramid (FidelityFX SSSR's hierarchical march),
//! or, with `ssr_hiz` off, by McGuire & Mara's 2014 linear DDA, kept for comparison. The classification lists the pixels worth a march and fails or
//! clears the rest; the march runs over that list by an indirect dispatch (the shape
//! of FidelityFX SSSR), so pixels with nothing to march cost it nothing.
//! CPU reference: `cpu_ref::ssr` (`classify`, `march`; tests/suite/ssr.rs).

use super::{GBuffer, HiZ};
use crate::error::Result;
use crate::settings::SsrParams;
use crate::shader_defines::{TILE_WORDS, WG_2D};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::cell::Cell;
use std::sync::Arc;

pub const NAME: &str = "ssr.trace";
pub const CLASSIFY_NAME: &str = "ssr.classify";
/// rgb: reflected colour found on screen; a: confidence (0 where SSR failed).
pub const COLOR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// The fail mask: `FAIL_*` bits per pixel, nonzero means "needs a ray".
pub const MASK_FORMAT: vk::Format = vk::Format::R32_UINT;
/// The reflected rays' distance to their hits.
pub const HIT_DISTANCE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

/// Push constants of `ssr_classify.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ClassifyPush {
    min_confidence: f32,
    reflective_min: f32,
    trace_min_weight: f32,
    tile_history: u32,
    skip_all: u32,
    measure_only: u32,
}

/// What `SsrPass::classify` does with the pixels a march could answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Classify {
    /// Lists them for the march, but in the adaptive hybrid's rays-only tiles only
    /// their probes (the rest: `FAIL_SKIPPED`); the tiles' states are updated first.
    Tiles,
    /// Lists none: every such pixel is skipped (`FAIL_SKIPPED`), as in a rays-only
    /// tile without probes; the tiles are left as they are (the adaptive hybrid's idle
    /// path).
    SkipAll,
    /// The `rt` mode's: every reflective pixel fails (`FAIL_FORCED`), none is left
    /// untraced; the tiles are left as they are.
    MaskOnly,
}

/// Push constants of `ssr_trace.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MarchPush {
    max_steps: u32,
    stride: f32,
    thickness: f32,
    max_distance: f32,
    edge_fade: f32,
    min_confidence: f32,
    recursion_min: f32,
    hiz_top: u32,
    trace_min_weight: f32,
    measure_only: u32,
}

pub struct SsrOutputs {
    pub color: Image,
    /// Fail reasons per pixel (`FAIL_*` bits); nonzero sends the pixel to rt.reflect.
    pub mask: Image,
    /// The pixels to march (packed x | y << 16), in no particular order.
    pub march_list: Buffer,
    /// `[groups_x, groups_y, 1, length]`: ssr.trace's indirect dispatch (`list_groups`
    /// of the workgroups the list needs) and the list's length.
    pub march_args: Buffer,
    /// The glossy pixels (`glossy.glsl`), for `reflect.denoise`, and their
    /// `[groups_x, groups_y, 1, length]` in `SSR_LIST_WG` workgroups.
    pub glossy_list: Buffer,
    pub glossy_args: Buffer,
    /// The reflected rays' mean distance to their hits (`HIT_FAR` where SSR did not
    /// answer; `rt.reflect` writes its pixels'), for `reflect.denoise`'s footprint.
    pub hit_distance: Image,
    /// The adaptive hybrid's tiles (`TILE_WORDS` words each: state, marched, answered),
    /// two buffers in turn: a frame reads the last one's and writes the other.
    pub tiles: [Buffer; 2],
    /// Word 0: pixels the classification listed in SSR-first tiles (probes aside); word
    /// 1: on a frame that only measures, the marched pixels outside rays-only tiles
    /// that SSR answered.
    pub ssr_first_marches: Buffer,
}

impl SsrOutputs {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            color: Image::storage(ctx, "ssr.color", extent, COLOR_FORMAT)?,
            mask: Image::storage(ctx, "ssr.fail_mask", extent, MASK_FORMAT)?,
            march_list: Buffer::device_list(ctx, "ssr.march_list", extent.width as u64 * extent.height as u64 * 4)?,
            march_args: Buffer::device_list(ctx, "ssr.march_args", 16)?,
            glossy_list: Buffer::device_list(ctx, "ssr.glossy_list", extent.width as u64 * extent.height as u64 * 4)?,
            glossy_args: Buffer::device_list(ctx, "ssr.glossy_args", 16)?,
            hit_distance: Image::storage(ctx, "ssr.hit_distance", extent, HIT_DISTANCE_FORMAT)?,
            tiles: [
                Buffer::device_list(ctx, "ssr.tiles.0", tile_count(extent) * TILE_WORDS as u64 * 4)?,
                Buffer::device_list(ctx, "ssr.tiles.1", tile_count(extent) * TILE_WORDS as u64 * 4)?,
            ],
            ssr_first_marches: Buffer::device_list(ctx, "ssr.ssr_first_marches", 16)?,
        })
    }
}

/// Tiles of `extent` (`ssr.classify`'s workgroups).
pub fn tile_count(extent: vk::Extent2D) -> u64 {
    extent.width.div_ceil(WG_2D) as u64 * extent.height.div_ceil(WG_2D) as u64
}

/// Where the tiles' turns stand: how many classifications have written them since
/// they were made or reset (0: the next has no last frame to read), and which of the
/// two buffers the last one wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileSequence {
    pub frames: u32,
    pub written: usize,
}

/// What the march reads besides its own outputs.
#[derive(Clone, Copy)]
pub struct MarchInputs<'a> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    /// The lit image, `GENERAL`.
    pub lit: &'a Image,
    /// `ssr.hiz`'s pyramid.
    pub hiz: &'a HiZ,
}

pub struct SsrPass {
    ctx: Arc<Context>,
    classify: Pipeline,
    /// The `rt` mode's classification (`MASK_ONLY`): every reflective pixel fails.
    mask_only: Pipeline,
    /// The adaptive hybrid's tile update before the classification (`ssr_tiles.comp`).
    tiles: Pipeline,
    /// The march through the Hi-Z pyramid, and the linear DDA (`ssr_hiz` off).
    trace_hiz: Pipeline,
    trace_linear: Pipeline,
    sampler: Sampler,
    pub out: SsrOutputs,
    tile_sequence: Cell<TileSequence>,
}

impl SsrPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let classify = shaders::SSR_CLASSIFY_COMP;
        Ok(Self {
            ctx: ctx.clone(),
            classify: Pipeline::compute::<ClassifyPush>(ctx, CLASSIFY_NAME, classify)?,
            mask_only: Pipeline::compute_specialized::<ClassifyPush>(ctx, "ssr.mask_only", classify, &[1])?,
            tiles: Pipeline::compute::<[u32; 3]>(ctx, "ssr.tiles", shaders::SSR_TILES_COMP)?,
            trace_hiz: Pipeline::compute_specialized::<MarchPush>(ctx, NAME, shaders::SSR_TRACE_COMP, &[1])?,
            trace_linear: Pipeline::compute_specialized::<MarchPush>(
                ctx,
                "ssr.trace.linear",
                shaders::SSR_TRACE_COMP,
                &[0],
            )?,
            sampler: Sampler::nearest_clamp(ctx, "ssr.sampler")?,
            out: SsrOutputs::new(ctx, extent)?,
            tile_sequence: Cell::default(),
        })
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = SsrOutputs::new(&self.ctx, extent)?;
        self.reset_tiles();
        Ok(())
    }

    /// Where the tiles' turns stand (`restore_tiles` returns to it: a frame measured
    /// again reads the same last frame).
    pub fn tile_sequence(&self) -> TileSequence {
        self.tile_sequence.get()
    }

    pub fn restore_tiles(&self, s: TileSequence) {
        self.tile_sequence.set(s);
    }

    /// Forgets the tiles' history: the next classification starts every tile unknown
    /// (SSR-first), as the first frame does.
    pub fn reset_tiles(&self) {
        self.tile_sequence.set(TileSequence::default());
    }

    /// The tile buffer the last classification wrote (state and this frame's counts).
    pub fn tiles_written(&self) -> &Buffer {
        &self.out.tiles[self.tile_sequence.get().written]
    }

    /// Records the classification: the fail mask and SSR colour of every pixel not to
    /// be marched, the march list and the glossy pixels' list (`kind`: which pixels are
    /// marched; the list stays empty unless `Classify::Tiles`). G-buffer in
    /// `SHADER_READ_ONLY_OPTIMAL`. Ends with the list and its dispatch arguments visible
    /// to `trace`, the mask and colour to `trace` and to the mask's readers
    /// (`ssr.compact`, `reflect.merge`). The G-buffer's metallic weighs the pixels' own
    /// reflection (`trace_min_weight`).
    pub fn classify(&self, cmd: vk::CommandBuffer, inputs: (&Buffer, &GBuffer), params: &SsrParams, kind: Classify) {
        let mask_only = kind == Classify::MaskOnly;
        let (frame, gbuffer) = inputs;
        let d = &self.ctx.device;
        let out = &self.out;
        // WAR/WAW: the previous frame's march (list and argument reads, the indirect
        // dispatch) and classification (atomics) are done before the arguments reset;
        // its readers of the mask and colour (compaction, merge) before they change.
        barrier::record(
            d,
            cmd,
            &[
                barrier::memory(access::COMPUTE_ANY, access::TRANSFER_WRITE),
                barrier::memory(access::COMPUTE_ANY, access::COMPUTE_WRITE),
            ],
            &[],
        );
        let args: [u32; 4] = [0, 1, 1, 0];
        // SAFETY: `cmd` is recording; the three buffers are live and 16 bytes or more;
        // the barrier above orders the writes after earlier reads.
        unsafe {
            d.cmd_update_buffer(cmd, out.march_args.raw, 0, bytemuck::bytes_of(&args));
            d.cmd_update_buffer(cmd, out.glossy_args.raw, 0, bytemuck::bytes_of(&args));
            d.cmd_update_buffer(cmd, out.ssr_first_marches.raw, 0, bytemuck::bytes_of(&[0u32; 4]));
        }
        // RAW: the classification's atomics see the reset arguments.
        barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE);
        let s = &self.sampler;
        let pipeline = if mask_only { &self.mask_only } else { &self.classify };
        let e = out.color.extent;
        // The tiles: read the last frame's, write the other (only when they choose).
        let seq = self.tile_sequence.get();
        let (tiles_in, tiles_out) = (&out.tiles[seq.written], &out.tiles[1 - seq.written]);
        if kind == Classify::Tiles {
            self.tile_sequence.set(TileSequence {
                frames: seq.frames.saturating_add(1),
                written: 1 - seq.written,
            });
            // This frame's tile states first (`ssr_tiles.comp`).
            let tiles = tile_count(e) as u32;
            let push = [tiles, params.tile_rate, (seq.frames > 0) as u32];
            let buffers = [
                ("tiles_in", Resource::Buffer(tiles_in)),
                ("tiles_out", Resource::Buffer(tiles_out)),
            ];
            self.tiles.dispatch(cmd, &buffers, &push, Groups::Cover([tiles, 1, 1]));
            // RAW: the classification reads the states; WAW: the march adds to the counts.
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
        }
        pipeline.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("gb_depth", Resource::Sampled(&gbuffer.depth, s)),
                ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
                ("gb_material", Resource::Sampled(&gbuffer.material, s)),
                ("ssr_out", Resource::StorageImage(&out.color)),
                ("fail_mask", Resource::StorageImage(&out.mask)),
                ("march_list", Resource::Buffer(&out.march_list)),
                ("march_args", Resource::Buffer(&out.march_args)),
                ("gb_albedo", Resource::Sampled(&gbuffer.albedo, s)),
                ("gb_motion", Resource::Sampled(&gbuffer.motion, s)),
                ("glossy_list", Resource::Buffer(&out.glossy_list)),
                ("glossy_args", Resource::Buffer(&out.glossy_args)),
                ("hit_distance", Resource::StorageImage(&out.hit_distance)),
                ("tiles", Resource::Buffer(tiles_out)),
                ("ssr_first", Resource::Buffer(&out.ssr_first_marches)),
            ],
            &ClassifyPush {
                min_confidence: params.min_confidence,
                reflective_min: params.reflective_min,
                trace_min_weight: params.trace_min_weight,
                tile_history: (seq.frames > 0) as u32,
                skip_all: (kind == Classify::SkipAll) as u32,
                measure_only: params.measure_only as u32,
            },
            Groups::Cover([e.width, e.height, 1]),
        );
        // RAW: the march reads the list and dispatches from its arguments; compaction
        // and merge read the mask and colour. WAW: the march writes the SSR colour and
        // fail mask of pixels beside those written here (disjoint pixels, but the
        // images are the same resources).
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_ANY);
    }

    /// Records the march over the classification's list: SSR colour + confidence and
    /// the fail mask of the listed pixels, visible at the end to their readers
    /// (`ssr.compact`, `reflect.merge`). `lit` in `GENERAL`; the G-buffer's metallic
    /// weighs the hit surfaces' own reflection; the pyramid (`ssr.hiz`'s,
    /// visible to compute reads) is read when `params.hiz`.
    pub fn trace(&self, cmd: vk::CommandBuffer, inputs: &MarchInputs<'_>, params: &SsrParams) {
        let MarchInputs {
            frame,
            gbuffer,
            lit,
            hiz,
        } = *inputs;
        let out = &self.out;
        let s = &self.sampler;
        let pipeline = if params.hiz {
            &self.trace_hiz
        } else {
            &self.trace_linear
        };
        pipeline.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("gb_depth", Resource::Sampled(&gbuffer.depth, s)),
                ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
                ("lit", Resource::StorageImage(lit)),
                ("ssr_out", Resource::StorageImage(&out.color)),
                ("fail_mask", Resource::StorageImage(&out.mask)),
                ("march_list", Resource::Buffer(&out.march_list)),
                ("march_args", Resource::Buffer(&out.march_args)),
                ("gb_albedo", Resource::Sampled(&gbuffer.albedo, s)),
                ("gb_motion", Resource::Sampled(&gbuffer.motion, s)),
                ("pyramid", Resource::Buffer(&hiz.buffer)),
                ("hit_distance", Resource::StorageImage(&out.hit_distance)),
                ("tiles", Resource::Buffer(self.tiles_written())),
                ("ssr_first", Resource::Buffer(&out.ssr_first_marches)),
            ],
            &MarchPush {
                max_steps: params.max_steps,
                stride: params.stride,
                thickness: params.thickness,
                max_distance: params.max_distance,
                edge_fade: params.edge_fade,
                min_confidence: params.min_confidence,
                recursion_min: params.recursion_min,
                hiz_top: hiz.levels.len() as u32 - 1,
                trace_min_weight: params.trace_min_weight,
                measure_only: params.measure_only as u32,
            },
            Groups::Indirect(&out.march_args),
        );
        // RAW: compaction and merge read the fail mask and SSR colour.
        barrier::global(&self.ctx.device, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
