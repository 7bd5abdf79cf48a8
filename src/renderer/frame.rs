//! The frame: docs/architecture.md's table as data (`Row`, from which `SCOPES` comes) and as the
//! function that records it (`Renderer::record_frame`), every row visible and recorded in
//! table order (`FrameRecorder` asserts it), each under its timer scope. Every pass's
//! `record` places its own barriers (see `passes`); this file only does what spans
//! passes: the uniform upload, which rows a mode runs, and the scopes.

use super::exchange::Path;
use super::{FrameSlot, Renderer};
use crate::gpu_types::FrameUniforms;
use crate::passes::compose::{self, ComposeInputs, ComposeMode};
use crate::passes::khr;
use crate::passes::lbvh::dynamic::DynamicBvh;
use crate::passes::light_direct::Sun;
use crate::passes::reflect_denoise::{self, DenoiseInputs, DenoiseParams};
use crate::passes::reflect_merge::{self, BlurParams, MergeInputs, MergeParams};
use crate::passes::rt_reflect::{self, ReflectInputs};
use crate::passes::ssr_hiz;
use crate::passes::ssr_trace::{self, Classify, MarchInputs};
use crate::passes::{
    gbuffer, light_direct, shadow_map, shadow_trace, sim_cloth, sim_skin, sim_transform, ssr_compact, SceneGeometry,
};
use crate::passes::{TraceScene, Traceable, Tracing};
use crate::settings::SsrParams;
use crate::settings::{HybridPolicy, Mode};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, GpuTimer};
use ash::vk;

/// Timer scope of the whole frame.
pub const FRAME: &str = "frame";
/// Timer scope of the per-frame uniform upload.
pub const UNIFORMS: &str = "uniforms";
/// The rigid bodies' time step on the CPU (wall clock, while the frame is recorded).
pub const SIM_RIGID: &str = "sim.rigid";

/// The rows the adaptive hybrid's paths are priced by (`exchange::Paths`): those that
/// differ between them, `ssr.hiz` to `reflect.denoise`.
pub fn reflection_rows() -> &'static [Row] {
    let at = |row| Row::ALL.iter().position(|&r| r == row).expect("a row of the table");
    &Row::ALL[at(Row::SsrHiz)..=at(Row::ReflectDenoise)]
}

/// One row of the frame table (docs/architecture.md), declared in frame order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Row {
    Uniforms,
    SimRigid,
    SimTransform,
    SimCloth,
    SimSkin,
    /// The dynamic BVH's rebuild or refit (`lbvh.*`; the static BVH is built once).
    DynamicBvh,
    /// The vendor tracer's structures of a moving scene (`as.*`; the static ones are
    /// built once).
    DynamicAccel,
    ShadowMap,
    GBuffer,
    ShadowClassify,
    ShadowCompact,
    ShadowTrace,
    LightDirect,
    SsrHiz,
    SsrClassify,
    SsrTrace,
    SsrCompact,
    RtReflect,
    ReflectMerge,
    /// The glossy reflections' spatial and temporal filters (`glossy` on, with a
    /// `denoise_radius` or a `denoise_history` to apply).
    ReflectDenoise,
    Compose,
}

impl Row {
    /// Every row, in frame order.
    pub const ALL: [Row; 21] = [
        Row::Uniforms,
        Row::SimRigid,
        Row::SimTransform,
        Row::SimCloth,
        Row::SimSkin,
        Row::DynamicBvh,
        Row::DynamicAccel,
        Row::ShadowMap,
        Row::GBuffer,
        Row::ShadowClassify,
        Row::ShadowCompact,
        Row::ShadowTrace,
        Row::LightDirect,
        Row::SsrHiz,
        Row::SsrClassify,
        Row::SsrTrace,
        Row::SsrCompact,
        Row::RtReflect,
        Row::ReflectMerge,
        Row::ReflectDenoise,
        Row::Compose,
    ];

    /// The timer scopes the row reports under (the dynamic BVH's stages each open
    /// their own).
    pub const fn scopes(self) -> &'static [&'static str] {
        match self {
            Row::Uniforms => &[UNIFORMS],
            Row::SimRigid => &[SIM_RIGID],
            Row::SimTransform => &[sim_transform::NAME],
            Row::SimCloth => &[sim_cloth::NAME],
            Row::SimSkin => &[sim_skin::NAME],
            Row::DynamicBvh => &DynamicBvh::SCOPES,
            Row::DynamicAccel => &khr::SCOPES,
            Row::ShadowMap => &[shadow_map::NAME],
            Row::GBuffer => &[gbuffer::NAME],
            Row::ShadowClassify => &[shadow_trace::CLASSIFY_NAME],
            Row::ShadowCompact => &[shadow_trace::COMPACT_NAME],
            Row::ShadowTrace => &[shadow_trace::NAME],
            Row::LightDirect => &[light_direct::NAME],
            Row::SsrHiz => &[ssr_hiz::NAME],
            Row::SsrClassify => &[ssr_trace::CLASSIFY_NAME],
            Row::SsrTrace => &[ssr_trace::NAME],
            Row::SsrCompact => &[ssr_compact::NAME],
            Row::RtReflect => &[rt_reflect::NAME],
            Row::ReflectMerge => &[reflect_merge::NAME],
            Row::ReflectDenoise => &[reflect_denoise::NAME],
            Row::Compose => &[compose::NAME],
        }
    }

    /// The row's one scope; rows with stages have none of their own.
    fn scope(self) -> &'static str {
        match self.scopes() {
            [name] => name,
            _ => panic!("frame row {self:?} has stages, not one scope"),
        }
    }
}

const SCOPE_COUNT: usize = {
    let (mut n, mut i) = (1, 0);
    while i < Row::ALL.len() {
        assert!(Row::ALL[i] as usize == i, "Row::ALL is the declaration order");
        n += Row::ALL[i].scopes().len();
        i += 1;
    }
    n
};

/// Every timer scope a frame can have, in frame order (`FRAME` last), from the rows'
/// scopes: the keys of every report's `passes_ms`, a pass a mode (or a static scene)
/// does not run reported as `null`. All are GPU time but `sim.rigid`, the CPU's; the
/// dynamic BVH's stages are `lbvh.*` (the static BVH's, built once, are reported apart).
pub const SCOPES: [&str; SCOPE_COUNT] = {
    let mut out = [FRAME; SCOPE_COUNT];
    let (mut k, mut i) = (0, 0);
    while i < Row::ALL.len() {
        let scopes = Row::ALL[i].scopes();
        let mut j = 0;
        while j < scopes.len() {
            out[k] = scopes[j];
            k += 1;
            j += 1;
        }
        i += 1;
    }
    out
};

/// Holds a frame to the table's order: a row after a later one panics.
#[derive(Default)]
struct RowOrder {
    /// The index in `Row::ALL` the next row must be at or after.
    next: usize,
}

impl RowOrder {
    fn follow(&mut self, row: Row) {
        assert!(
            row as usize >= self.next,
            "frame row {row:?} recorded out of table order"
        );
        self.next = row as usize + 1;
    }
}

/// Records the rows of one frame into a command buffer in table order, each under its
/// scope.
struct FrameRecorder<'a> {
    timer: &'a mut GpuTimer,
    cmd: vk::CommandBuffer,
    order: RowOrder,
}

impl<'a> FrameRecorder<'a> {
    /// Starts the frame: the timer's queries reset, the `frame` scope open.
    fn begin(timer: &'a mut GpuTimer, cmd: vk::CommandBuffer) -> Self {
        timer.reset(cmd);
        timer.begin(cmd, FRAME);
        let order = RowOrder::default();
        Self { timer, cmd, order }
    }

    /// Records `row` under its scope.
    fn row<R>(&mut self, row: Row, record: impl FnOnce() -> R) -> R {
        self.order.follow(row);
        self.timer.scope(self.cmd, row.scope(), record)
    }

    /// Records a row whose stages open their own scopes on the timer it is given.
    fn staged_row(&mut self, row: Row, record: impl FnOnce(&mut GpuTimer)) {
        self.order.follow(row);
        record(self.timer);
    }

    /// Runs a row on the host while the frame is recorded; its wall-clock milliseconds.
    fn host_row(&mut self, row: Row, run: impl FnOnce()) -> f64 {
        self.order.follow(row);
        let start = std::time::Instant::now();
        run();
        start.elapsed().as_secs_f64() * 1e3
    }

    fn end(self) {
        self.timer.end(self.cmd, FRAME);
    }
}

impl Renderer {
    /// Records one frame into `cmd` (begun, not ended) with frame slot `slot`'s queries
    /// and staging: docs/architecture.md's frame table, row by row. A dynamic scene advances one
    /// time step unless it is paused. The caller submits it, and must have seen the
    /// slot's previous frame finish (a fence) before; several slots' frames may be in
    /// flight on the queue at once.
    // Long: it is docs/architecture.md's frame table, every row in order; split, rows would hide.
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, slot: usize) {
        let advance = !self.paused || std::mem::take(&mut self.step_once);
        let Self {
            ctx,
            settings: st,
            scene,
            frame_ubo: ubo,
            uniforms,
            frame_index,
            sample_stream,
            shadow,
            gbuffer,
            light,
            hiz,
            ssr,
            compact,
            shadow_trace,
            shadow_compact,
            rt,
            merge,
            denoise,
            compose,
            static_bvh,
            khr,
            dynamic,
            transform,
            cloth,
            skin,
            builder,
            slots,
            fail_mask_view,
            exchange,
            paths,
            ..
        } = self;
        let FrameSlot { timer, sim_ms, counts } = &mut slots[slot];
        let (d, mode, g) = (&ctx.device, st.mode, &gbuffer.out);
        let mut f = FrameRecorder::begin(timer, cmd);
        // This frame's uniforms: the view's, and where the glossy rays' sequence is.
        let uniforms = &FrameUniforms {
            frame_index: *frame_index,
            sample_stream: *sample_stream,
            ..*uniforms
        };
        *frame_index = frame_index.wrapping_add(1);
        f.row(Row::Uniforms, || upload_uniforms(d, cmd, ubo, uniforms));
        if let Some(dy) = dynamic.as_mut().filter(|_| !advance) {
            dy.keep_previous(d, cmd, false);
        }
        if let Some(dy) = dynamic.as_mut().filter(|_| advance) {
            *sim_ms = Some(f.host_row(Row::SimRigid, || dy.step(slot)));
            // The first of the steps keeps the last frame's vertices for the motion.
            if dy.rigid.vertex_count > 0 {
                f.row(Row::SimTransform, || {
                    dy.keep_previous(d, cmd, true);
                    transform.record_posed(cmd, &dy.rigid, slot, &dy.mesh.vertices)
                });
            }
            if !dy.cloths.is_empty() {
                f.row(Row::SimCloth, || {
                    if dy.rigid.vertex_count == 0 {
                        dy.keep_previous(d, cmd, true);
                    }
                    dy.cloths.iter().for_each(|c| cloth.record(cmd, c, &dy.mesh.vertices))
                });
            }
            if dy.animated.is_some() {
                f.row(Row::SimSkin, || {
                    if dy.rigid.vertex_count == 0 && dy.cloths.is_empty() {
                        dy.keep_previous(d, cmd, true);
                    }
                    let (model, _) = dy.animated.as_ref().expect("checked");
                    skin.record_posed(cmd, model, slot, &dy.mesh.vertices)
                });
            }
            match khr {
                None => f.staged_row(Row::DynamicBvh, |timer| {
                    dy.bvh
                        .record(cmd, timer, builder, dy.mesh.triangles(), dy.rigid.poses())
                }),
                Some(k) => {
                    let poses = dy.world.poses();
                    f.staged_row(Row::DynamicAccel, |timer| {
                        k.record_frame(cmd, timer, slot, &poses, &dy.mesh.triangles())
                    })
                }
            }
        }
        let dynamic = dynamic.as_ref();
        let geometries: Vec<SceneGeometry<'_>> = std::iter::once(scene.mesh.geometry())
            .chain(dynamic.map(|dy| dy.geometry()))
            .collect();
        let shadows = st.shadows;
        if shadows.uses_map() {
            f.row(Row::ShadowMap, || shadow.record(cmd, ubo, &geometries));
        }
        let surfaces = scene.surfaces(dynamic);
        f.row(Row::GBuffer, || gbuffer.record(cmd, ubo, &surfaces, &geometries));
        let trace_scene: Tracing<'_> = match khr {
            Some(k) => k
                .trace(scene.mesh.triangles(), dynamic.map(|dy| dy.mesh.triangles()))
                .into(),
            None => TraceScene {
                static_bvh: Some(Traceable {
                    bvh: static_bvh,
                    geometry: scene.mesh.triangles(),
                }),
                dynamic_bvh: dynamic.map(|dy| dy.traceable()),
            }
            .into(),
        };
        if shadows.traces() {
            f.row(Row::ShadowClassify, || {
                shadow_trace.classify(cmd, ubo, g, &shadow.out, shadows)
            });
            f.row(Row::ShadowCompact, || {
                shadow_compact.record(cmd, &shadow_trace.out.mask)
            });
            let list = &shadow_compact.out;
            f.row(Row::ShadowTrace, || shadow_trace.trace(cmd, ubo, g, list, &trace_scene));
        }
        let sun = Sun {
            map: &shadow.out,
            visibility: &shadow_trace.out.visibility,
            traced: shadows.traces(),
        };
        f.row(Row::LightDirect, || light.record(cmd, ubo, g, sun));
        let mut params = SsrParams::from_settings(st);
        let adaptive = mode.marches() && mode.traces() && st.hybrid_policy == HybridPolicy::Adaptive;
        // The idle path (`exchange::Paths`): no pyramid, no march; every pixel a march
        // could answer goes to the rays as in a rays-only tile without probes.
        let priced = adaptive && st.exchange_rate == 0.0;
        let path = if adaptive {
            paths.frame_path(uniforms.frame_index, priced)
        } else {
            Path::March
        };
        let (idle, marches) = (path != Path::March, mode.marches() && path == Path::March);
        if priced {
            params.tile_rate = exchange.applied;
        }
        if adaptive {
            paths.frames[path as usize] += 1;
        }
        if idle {
            counts.record_idle(path);
        }
        // Only a hybrid frame may skip marches (the ssr mode has no ray to send to).
        if !adaptive {
            params.tile_rate = 0;
        }
        if marches && params.hiz {
            f.row(Row::SsrHiz, || hiz.record(cmd, &g.depth));
        }
        if mode.reflects() {
            let kind = match (marches, path) {
                (true, _) => Classify::Tiles,
                (false, Path::SkipMarch) => Classify::SkipAll,
                (false, _) => Classify::MaskOnly,
            };
            f.row(Row::SsrClassify, || ssr.classify(cmd, (ubo, g), &params, kind));
        }
        if marches {
            let inputs = MarchInputs {
                frame: ubo,
                gbuffer: g,
                lit: &light.out,
                hiz: &hiz.out,
            };
            f.row(Row::SsrTrace, || ssr.trace(cmd, &inputs, &params));
        }
        if mode.traces() {
            f.row(Row::SsrCompact, || compact.record(cmd, &ssr.out.mask));
            let inputs = ReflectInputs {
                frame: ubo,
                gbuffer: g,
                surfaces,
                shadow_map: &shadow.out,
                list: &compact.out,
                scene: trace_scene,
                hit_distance: &ssr.out.hit_distance,
            };
            f.row(Row::RtReflect, || rt.record(cmd, &inputs, st.max_bounces, shadows));
            // A hybrid frame's counts price the march in rays (`exchange`).
            if marches {
                let o = &ssr.out;
                let lists = [&o.march_args, &compact.out.indirect, &o.ssr_first_marches];
                counts.record((d, cmd), lists, (params.tile_rate, priced));
            }
        }
        if mode.reflects() {
            // Seams exist only where both sources do (not on the adaptive hybrid's idle
            // paths, where SSR answers nothing).
            let blur = BlurParams {
                radius: if mode.has_seams() && !idle { st.blur_radius } else { 0 },
                band: st.blur_band,
            };
            let inputs = MergeInputs {
                frame: ubo,
                gbuffer: g,
                fail_mask: &ssr.out.mask,
                ssr: &ssr.out.color,
                rt: &rt.out,
            };
            let params = MergeParams {
                rt_enabled: mode.traces(),
                reflective_min: st.reflective_min,
                blur,
            };
            f.row(Row::ReflectMerge, || merge.record(cmd, &inputs, params));
        }
        let denoised = mode.reflects() && st.glossy && (st.denoise_radius > 0 || st.denoise_history > 1);
        if denoised {
            let inputs = DenoiseInputs {
                frame: ubo,
                gbuffer: g,
                merged: &merge.out,
                list: &ssr.out.glossy_list,
                list_args: &ssr.out.glossy_args,
                hit_distance: &ssr.out.hit_distance,
            };
            let params = DenoiseParams {
                radius: st.denoise_radius,
                history: st.denoise_history,
                reflective_min: st.reflective_min,
            };
            f.row(Row::ReflectDenoise, || denoise.record(cmd, &inputs, params, uniforms));
        }
        let inputs = ComposeInputs {
            frame: ubo,
            hdr: &light.out,
            reflection: &merge.out,
            gbuffer: g,
            fail_mask: &ssr.out.mask,
            reflective_min: st.reflective_min,
        };
        let compose_mode = match mode {
            Mode::Raster => ComposeMode::Plain,
            _ if *fail_mask_view => ComposeMode::FailMask,
            Mode::Provenance => ComposeMode::Provenance,
            Mode::Ssr | Mode::Hybrid | Mode::Rt => ComposeMode::Reflect,
        };
        f.row(Row::Compose, || compose.record(cmd, &inputs, st.exposure, compose_mode));
        f.end();
    }
}

/// Writes this frame's uniforms: spans passes, since every pass reads them.
fn upload_uniforms(d: &ash::Device, cmd: vk::CommandBuffer, ubo: &Buffer, uniforms: &FrameUniforms) {
    // WAR: the previous frame's shader reads of the uniforms finish before they change.
    barrier::global(d, cmd, access::ANY_SHADER_READ, access::TRANSFER_WRITE);
    // SAFETY: `cmd` is recording; the uniform buffer is live and holds `FrameUniforms`
    // (under the 64 KiB `cmd_update_buffer` allows, a multiple of 4 bytes).
    unsafe { d.cmd_update_buffer(cmd, ubo.raw, 0, bytemuck::bytes_of(uniforms)) };
    // RAW: every pass below reads the uniforms just written.
    barrier::global(d, cmd, access::TRANSFER_WRITE, access::ANY_SHADER_READ);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scopes are the rows' scopes in frame order, each once, `frame` last.
    #[test]
    fn scopes_are_the_rows_in_order() {
        let rows: Vec<&str> = Row::ALL.iter().flat_map(|r| r.scopes().iter().copied()).collect();
        assert_eq!(SCOPES[..SCOPES.len() - 1], rows[..]);
        assert_eq!(SCOPES.last(), Some(&FRAME));
        let mut unique = SCOPES.to_vec();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), SCOPES.len(), "a scope named twice");
        assert_eq!(SCOPES[..2], [UNIFORMS, SIM_RIGID]);
    }

    /// A frame may skip rows but never go back up the table.
    #[test]
    #[should_panic(expected = "out of table order")]
    fn a_row_before_one_recorded_panics() {
        let mut order = RowOrder::default();
        order.follow(Row::Uniforms);
        order.follow(Row::GBuffer);
        order.follow(Row::Compose);
        order.follow(Row::ShadowMap);
    }

    /// Skipping rows (a static scene, a mode without reflections) is allowed; a row
    /// recorded twice is not.
    #[test]
    fn rows_may_be_skipped_not_repeated() {
        let mut order = RowOrder::default();
        for row in [Row::Uniforms, Row::ShadowMap, Row::GBuffer, Row::Compose] {
            order.follow(row);
        }
        let again = std::panic::catch_unwind(move || order.follow(Row::Compose));
        assert!(again.is_err());
    }
}
