//! `reflect.merge`: SSR where it succeeded, ray-traced reflections where it failed,
//! labelled by source; then a separable Gaussian blur restricted to the band around
//! SSR/RT seams (horizontal, then vertical), dispatched indirectly over a list of the
//! 8x8 tiles a seam comes near (`glsl/reflect_tiles.comp`, `glsl/reflect_blur.comp`).
//! A full-screen dispatch costs lavapipe about as much for a pixel with nothing to do
//! as for one with work (it runs both sides of every branch), so the blur must not be
//! dispatched over tiles it leaves unchanged.
//! CPU reference: `cpu_ref::merge` (`merge`, `active_tiles`, `seam_blur`; tests/suite/merge.rs).

use super::GBuffer;
use crate::error::Result;
use crate::shader_defines::WG_2D;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Image, Pipeline, Resource, Sampler};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "reflect.merge";
/// rgb: reflected radiance; a: source (`SOURCE_*`).
pub const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MergePush {
    reflective_min: f32,
    rt_enabled: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TilesPush {
    band: i32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BlurPush {
    axis: [i32; 2],
    radius: i32,
    band: i32,
}

/// Seam blur settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlurParams {
    /// Blur radius in pixels (0: no blur; where only one source exists, as in the `rt`
    /// and `ssr` modes, there are no seams and the blur would copy every pixel).
    pub radius: u32,
    /// Half-width in pixels of the band around seams that is blurred.
    pub band: u32,
}

/// The blur's working images and per-tile buffers, which depend on the resolution.
struct Targets {
    /// The horizontal blur's output (written for active tiles only).
    scratch: Image,
    /// Per WG_2D x WG_2D tile: bit `1 << SOURCE_*` for each source it holds.
    tile_sources: Buffer,
    /// Per tile: 1 when the blur works on it this frame.
    tile_active: Buffer,
    /// The active tiles' indices (row-major tile index), in no particular order.
    tile_list: Buffer,
    /// `[groups_x, groups_y, 1, count]`: the blur's indirect dispatch (one workgroup per
    /// listed tile, `list_groups` of the count), then the count.
    blur_args: Buffer,
    tiles: u32,
}

impl Targets {
    fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let tiles = (extent.width.div_ceil(WG_2D) * extent.height.div_ceil(WG_2D)) as u64;
        let buffer = |name, size| Buffer::device_list(ctx, name, size);
        Ok(Self {
            scratch: Image::storage(ctx, "reflect.scratch", extent, FORMAT)?,
            tile_sources: buffer("reflect.tile_sources", tiles * 4)?,
            tile_active: buffer("reflect.tile_active", tiles * 4)?,
            tile_list: buffer("reflect.tile_list", tiles * 4)?,
            blur_args: buffer("reflect.blur_args", 16)?,
            tiles: tiles as u32,
        })
    }
}

pub struct MergePass {
    ctx: Arc<Context>,
    merge: Pipeline,
    tiles: Pipeline,
    blur: Pipeline,
    sampler: Sampler,
    targets: Targets,
    /// The merged, seam-blurred reflection (always `GENERAL`).
    pub out: Image,
}

/// What `reflect.merge` reads: the frame uniforms, the G-buffer, the fail mask and both
/// sources (`GENERAL`; the G-buffer read-only).
pub struct MergeInputs<'a> {
    pub frame: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    pub fail_mask: &'a Image,
    pub ssr: &'a Image,
    pub rt: &'a Image,
}

/// How `reflect.merge` merges: whether the RT source was traced this frame, the
/// reflectivity above which a pixel reflects, and the seam blur.
#[derive(Clone, Copy, Debug)]
pub struct MergeParams {
    pub rt_enabled: bool,
    pub reflective_min: f32,
    pub blur: BlurParams,
}

impl MergePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            merge: Pipeline::compute::<MergePush>(ctx, NAME, shaders::REFLECT_MERGE_COMP)?,
            tiles: Pipeline::compute::<TilesPush>(ctx, "reflect.tiles", shaders::REFLECT_TILES_COMP)?,
            blur: Pipeline::compute::<BlurPush>(ctx, "reflect.blur", shaders::REFLECT_BLUR_COMP)?,
            sampler: Sampler::nearest_clamp(ctx, "reflect.sampler")?,
            targets: Targets::new(ctx, extent)?,
            out: Image::storage(ctx, "reflect.merged", extent, FORMAT)?,
        })
    }

    /// The blur's intermediate image, for tests that poison it before a run.
    pub fn scratch(&self) -> &Image {
        &self.targets.scratch
    }

    /// The seam blur's tiles of the last run (a readback, for tests): per tile whether
    /// it was active, and the listed tiles, sorted.
    pub fn read_tiles(&self) -> Result<(Vec<bool>, Vec<u32>)> {
        let t = &self.targets;
        let active: Vec<u32> = bytemuck::pod_collect_to_vec(&t.tile_active.read()?);
        let args: Vec<u32> = bytemuck::pod_collect_to_vec(&t.blur_args.read()?);
        let listed: Vec<u32> = bytemuck::pod_collect_to_vec(&t.tile_list.read()?);
        let mut listed = listed[..(args[3] as usize).min(t.tiles as usize)].to_vec();
        listed.sort_unstable();
        Ok((active.iter().map(|&a| a != 0).collect(), listed))
    }

    /// The seam blur's per-tile buffers (activity, list, dispatch arguments), for tests
    /// that poison them before a run.
    pub fn tile_buffers(&self) -> [&Buffer; 3] {
        let t = &self.targets;
        [&t.tile_active, &t.tile_list, &t.blur_args]
    }

    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.targets = Targets::new(&self.ctx, extent)?;
        self.out = Image::storage(&self.ctx, "reflect.merged", extent, FORMAT)?;
        Ok(())
    }

    /// Records merge + blur; `out` ends visible to its reader, `compose`.
    pub fn record(&self, cmd: vk::CommandBuffer, inputs: &MergeInputs<'_>, params: MergeParams) {
        let MergeInputs {
            frame,
            gbuffer,
            fail_mask,
            ssr,
            rt,
        } = *inputs;
        let MergeParams {
            rt_enabled,
            reflective_min,
            blur,
        } = params;
        let d = &self.ctx.device;
        let t = &self.targets;
        let e = self.out.extent;
        let s = &self.sampler;
        // merge → reflection, blur H → scratch, blur V → reflection.
        // WAR: the previous frame's tile pass reads of the tile bits finish before they
        // are zeroed; WAR/WAW: its compose reads and blur writes of the images finish
        // before this frame rewrites them.
        barrier::record(
            d,
            cmd,
            &[
                barrier::memory(access::COMPUTE_READ, access::TRANSFER_WRITE),
                barrier::memory(access::COMPUTE_ANY, access::COMPUTE_WRITE),
            ],
            &[],
        );
        // SAFETY: `cmd` is recording; the buffer is live, the barrier above orders it.
        unsafe { d.cmd_fill_buffer(cmd, t.tile_sources.raw, 0, vk::WHOLE_SIZE, 0) };
        // RAW/WAW: the merge's atomics see the zeroed tile bits.
        barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE);
        self.merge.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("fail_mask", Resource::StorageImage(fail_mask)),
                ("ssr_in", Resource::StorageImage(ssr)),
                ("rt_in", Resource::StorageImage(rt)),
                ("gb_normal", Resource::Sampled(&gbuffer.normal, s)),
                ("gb_material", Resource::Sampled(&gbuffer.material, s)),
                ("merged", Resource::StorageImage(&self.out)),
                ("tile_sources", Resource::Buffer(&t.tile_sources)),
            ],
            &MergePush {
                reflective_min,
                rt_enabled: rt_enabled as u32,
            },
            Groups::Cover([e.width, e.height, 1]),
        );
        if blur.radius == 0 {
            // RAW: compose reads the merged reflection.
            barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
            return;
        }
        self.record_blur(cmd, (frame, gbuffer), blur);
    }

    /// The seam blur over the merged reflection: the tile pass lists the tiles near a
    /// seam, then a horizontal and a vertical pass over those tiles only.
    fn record_blur(&self, cmd: vk::CommandBuffer, (frame, gbuffer): (&Buffer, &GBuffer), blur: BlurParams) {
        let d = &self.ctx.device;
        let t = &self.targets;
        // RAW: the tile pass reads the merge's tile bits, the blur its merged image;
        // WAW: the tile pass rewrites the previous run's activity and list. WAR/WAW: the
        // previous run's uses of the dispatch arguments finish before they are reset.
        barrier::record(
            d,
            cmd,
            &[
                barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE),
                barrier::memory(access::COMPUTE_ANY, access::TRANSFER_WRITE),
            ],
            &[],
        );
        let args: [u32; 4] = [0, 1, 1, 0];
        // SAFETY: `cmd` is recording; the buffer is live and 16 bytes or more.
        unsafe { d.cmd_update_buffer(cmd, t.blur_args.raw, 0, bytemuck::bytes_of(&args)) };
        // RAW: the tile pass's atomics see the zeroed count.
        barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ_WRITE);
        self.tiles.dispatch(
            cmd,
            &[
                ("frame", Resource::Buffer(frame)),
                ("tile_sources", Resource::Buffer(&t.tile_sources)),
                ("tile_active", Resource::Buffer(&t.tile_active)),
                ("tile_list", Resource::Buffer(&t.tile_list)),
                ("blur_args", Resource::Buffer(&t.blur_args)),
            ],
            &TilesPush { band: blur.band as i32 },
            Groups::Cover([t.tiles, 1, 1]),
        );
        let rw = access::COMPUTE_READ_WRITE;
        for axis in [[1, 0], [0, 1]] {
            // RAW: this blur pass reads what the previous step wrote (images, tile list
            // and activity) and dispatches from the tile count; WAR: it overwrites what
            // the previous step read.
            barrier::record(
                d,
                cmd,
                &[
                    barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ_AND_INDIRECT),
                    barrier::memory(access::COMPUTE_READ, rw),
                ],
                &[],
            );
            let push = BlurPush {
                axis,
                radius: blur.radius as i32,
                band: blur.band as i32,
            };
            self.blur.dispatch(
                cmd,
                &[
                    ("frame", Resource::Buffer(frame)),
                    ("reflection", Resource::StorageImage(&self.out)),
                    ("scratch", Resource::StorageImage(&t.scratch)),
                    ("tile_active", Resource::Buffer(&t.tile_active)),
                    ("tile_list", Resource::Buffer(&t.tile_list)),
                    ("blur_args", Resource::Buffer(&t.blur_args)),
                    ("gb_albedo", Resource::Sampled(&gbuffer.albedo, &self.sampler)),
                ],
                &push,
                Groups::Indirect(&t.blur_args),
            );
        }
        // RAW: compose reads the blurred reflection.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
