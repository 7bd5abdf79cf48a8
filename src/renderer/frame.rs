//! The frame as the function that records it (`Renderer::record_frame`): the plan
//! first (`plan::FramePlan`), then the table's rows (`table::Row`) as the plan says,
//! each under its timer scope, in table order (`FrameRecorder` holds the frame to the
//! plan and the order). Every pass's `record` places its own barriers (see `passes`);
//! this file only does what spans passes: the uniform upload, and which inputs each
//! row reads.

use super::exchange::{FrameCounts, FramePath, Path};
use super::gpu_scene::DynamicGeometry;
use super::plan::{FramePlan, Motion, Previous, Ways};
use super::stages::Taken;
use super::table::{Row, FRAME};
use super::tracer::{FrameTracer, Kernels};
use super::{FrameSlot, Lighting, Reflections, Renderer};
use crate::gpu_types::FrameUniforms;
use crate::passes::compose::ComposeInputs;
use crate::passes::gbuffer_trace::PrimaryInputs;
use crate::passes::light_direct::Sun;
use crate::passes::reflect_denoise::{DenoiseInputs, DenoiseParams};
use crate::passes::reflect_merge::{MergeInputs, MergeParams, MergePass};
use crate::passes::rt_reflect::{ReflectInputs, RtReflectPass};
use crate::passes::sim_cloth::ClothPass;
use crate::passes::sim_skin::SimSkinPass;
use crate::passes::sim_transform::SimTransformPass;
use crate::passes::ssr_compact::CompactPass;
use crate::passes::ssr_trace::{MarchInputs, SsrPass};
use crate::passes::{SceneGeometry, Surfaces};
use crate::settings::{Hybrid, Settings};
use crate::tracers::khr::KhrScene;
use crate::tracers::lbvh::LbvhBuilder;
use crate::tracers::{TraceScene, Traceable, Tracer};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, GpuTimer};
use ash::vk;

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
/// scope, and holds the frame to its plan: a row the plan does not run, or a planned
/// row left out, panics.
struct FrameRecorder<'a> {
    timer: &'a mut GpuTimer,
    cmd: vk::CommandBuffer,
    order: RowOrder,
    /// The plan's rows, in table order; `recorded` of them so far.
    planned: Vec<Row>,
    recorded: usize,
}

impl<'a> FrameRecorder<'a> {
    /// Starts the frame of the `planned` rows: the timer's queries reset, the `frame`
    /// scope open.
    fn begin(timer: &'a mut GpuTimer, cmd: vk::CommandBuffer, planned: Vec<Row>) -> Self {
        timer.reset(cmd);
        timer.begin(cmd, FRAME);
        let order = RowOrder::default();
        Self {
            timer,
            cmd,
            order,
            planned,
            recorded: 0,
        }
    }

    fn follow(&mut self, row: Row) {
        self.order.follow(row);
        assert_eq!(
            self.planned.get(self.recorded),
            Some(&row),
            "frame row {row:?} recorded where the plan has {:?}",
            self.planned
        );
        self.recorded += 1;
    }

    /// Records `row` under its scope.
    fn row<R>(&mut self, row: Row, record: impl FnOnce() -> R) -> R {
        self.follow(row);
        self.timer.scope(self.cmd, row.scope(), record)
    }

    /// Records a row whose stages open their own scopes on the timer it is given.
    fn staged_row(&mut self, row: Row, record: impl FnOnce(&mut GpuTimer)) {
        self.follow(row);
        record(self.timer);
    }

    /// Runs a row on the host while the frame is recorded; its wall-clock milliseconds.
    fn host_row(&mut self, row: Row, run: impl FnOnce()) -> f64 {
        self.follow(row);
        let start = std::time::Instant::now();
        run();
        start.elapsed().as_secs_f64() * 1e3
    }

    fn end(self) {
        assert_eq!(
            self.recorded,
            self.planned.len(),
            "the frame left out planned rows {:?}",
            &self.planned[self.recorded..]
        );
        self.timer.end(self.cmd, FRAME);
    }
}

impl Renderer {
    /// This frame's plan (`plan::FramePlan`): whether it steps the scene (taking a
    /// single step asked for), what moves, and the adaptive hybrid's path (counted
    /// among the paths taken).
    fn plan_frame(&mut self) -> (FramePlan, Taken) {
        let advance = !self.paused || std::mem::take(&mut self.step_once);
        let dy = self.dynamic.as_ref();
        let motion = Motion {
            dynamic: dy.is_some(),
            rigid: dy.is_some_and(|dy| dy.rigid.vertex_count > 0),
            cloth: dy.is_some_and(|dy| !dy.cloths.is_empty()),
            skin: dy.is_some_and(|dy| dy.animated.is_some()),
            advance,
            vendor: matches!(self.tracer, FrameTracer::Khr(..)),
        };
        let hybrid = Hybrid::of(&self.settings);
        let path = match hybrid.adaptive() {
            true => self.paths.frame_path(self.frame_index, hybrid.priced()),
            false => FramePath::plain(Path::March),
        };
        if hybrid.adaptive() {
            self.paths.count(path, self.frame_index);
        }
        let (visibility, shadows, taken) = self.stages.frame_ways(&self.settings, self.frame_index);
        let ways = Ways {
            path,
            visibility,
            shadows,
        };
        let plan = FramePlan::new(&self.settings, motion, ways, self.exchange.applied, self.fail_mask_view);
        (plan, taken)
    }

    /// Records one frame into `cmd` (begun, not ended) with frame slot `slot`'s queries
    /// and staging: docs/architecture.md's frame table, row by row, as this frame's plan
    /// says (`FrameRecorder` holds it to the plan and the table's order). A dynamic scene
    /// advances one time step unless it is paused. The caller submits it, and must have
    /// seen the slot's previous frame finish (a fence) before; several slots' frames may
    /// be in flight on the queue at once.
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, slot: usize) {
        let (plan, taken) = self.plan_frame();
        self.last_plan = Some(plan);
        let Self {
            ctx,
            settings: st,
            scene,
            frame_ubo: ubo,
            uniforms,
            frame_index,
            sample_stream,
            static_bvh,
            tracer,
            dynamic,
            slots,
            ..
        } = self;
        let FrameSlot {
            timer,
            sim_ms,
            counts,
            taken: slot_taken,
        } = &mut slots[slot];
        // The adaptive stages' ways, priced when the frame has finished.
        *slot_taken = taken;
        let d = &ctx.device;
        let mut f = FrameRecorder::begin(timer, cmd, plan.rows());
        // This frame's uniforms: the view's, and where the glossy rays' sequence is.
        let uniforms = &FrameUniforms {
            frame_index: *frame_index,
            sample_stream: *sample_stream,
            ..*uniforms
        };
        *frame_index = frame_index.wrapping_add(1);
        f.row(Row::Uniforms, || upload_uniforms(d, cmd, ubo, uniforms));
        if let Some(dy) = dynamic.as_mut() {
            let steps = Steps {
                transform: &self.transform,
                cloth: &self.cloth,
                skin: &self.skin,
                builder: &self.builder,
                khr: tracer.khr_mut(),
            };
            *sim_ms = record_motion(&mut f, &plan, (d, cmd, slot), dy, steps);
        }
        let dynamic = dynamic.as_ref();
        let frame = FrameInputs {
            ubo,
            st,
            uniforms,
            geometries: std::iter::once(scene.mesh.geometry())
                .chain(dynamic.map(|dy| dy.geometry()))
                .collect(),
            surfaces: scene.surfaces(dynamic),
        };
        let passes = (&self.lighting, &mut self.reflections);
        let at = (&mut f, &plan, d, cmd);
        match tracer {
            FrameTracer::Lbvh(kernels) => {
                let scene = TraceScene {
                    static_bvh: Some(Traceable {
                        bvh: static_bvh,
                        geometry: scene.mesh.triangles(),
                    }),
                    dynamic_bvh: dynamic.map(|dy| dy.traceable()),
                };
                record_shading(at, passes, &frame, Traced { kernels, scene }, counts)
            }
            FrameTracer::Khr(kernels, khr) => {
                let scene = khr.trace(scene.mesh.triangles(), dynamic.map(|dy| dy.mesh.triangles()));
                record_shading(at, passes, &frame, Traced { kernels, scene }, counts)
            }
        }
        let inputs = ComposeInputs {
            frame: ubo,
            hdr: &self.lighting.light.out,
            reflection: &self.reflections.merge.out,
            gbuffer: &self.lighting.gbuffer.out,
            fail_mask: &self.reflections.ssr.out.mask,
            reflective_min: st.reflective_min,
        };
        let compose = &self.compose;
        f.row(Row::Compose, || compose.record(cmd, &inputs, st.exposure, plan.compose));
        f.end();
    }
}

/// What every row of a frame reads besides its own pass: the uniforms, the settings,
/// the geometry as the raster draws it, and the surfaces.
struct FrameInputs<'a> {
    ubo: &'a Buffer,
    st: &'a Settings,
    uniforms: &'a FrameUniforms,
    geometries: Vec<SceneGeometry<'a>>,
    surfaces: Surfaces<'a>,
}

/// What the tracing rows trace with: tracer `T`'s kernels and what they walk.
struct Traced<'a, T: Tracer> {
    kernels: &'a Kernels<T>,
    scene: T::Scene<'a>,
}

/// `shadow.map` to `reflect.denoise` through tracer `T`, as `plan` says (an idle
/// hybrid frame counted in `counts`).
fn record_shading<'a, T: Tracer>(
    (f, plan, d, cmd): (&mut FrameRecorder<'_>, &FramePlan, &ash::Device, vk::CommandBuffer),
    (lighting, reflections): (&'a Lighting, &'a mut Reflections),
    frame: &FrameInputs<'a>,
    traced: Traced<'a, T>,
    counts: &mut FrameCounts,
) {
    record_lighting(f, plan, cmd, lighting, frame, &traced);
    if plan.path != Path::March {
        counts.record_idle(plan.frame_path());
    }
    record_reflections(f, plan, (d, cmd), (lighting, reflections), frame, &traced, counts);
}

/// `shadow.map` to `light.direct`, as `plan` says.
fn record_lighting<'a, T: Tracer>(
    f: &mut FrameRecorder<'_>,
    plan: &FramePlan,
    cmd: vk::CommandBuffer,
    l: &Lighting,
    i: &FrameInputs<'a>,
    t: &Traced<'a, T>,
) {
    let (ubo, g, shadows) = (i.ubo, &l.gbuffer.out, plan.shadows);
    if plan.runs(Row::ShadowMap) {
        f.row(Row::ShadowMap, || l.shadow.record(cmd, ubo, &i.geometries));
    }
    if plan.runs(Row::GBuffer) {
        f.row(Row::GBuffer, || l.gbuffer.record(cmd, ubo, &i.surfaces, &i.geometries));
    } else {
        let inputs = PrimaryInputs {
            frame: ubo,
            surfaces: i.surfaces,
            // The dynamic geometry's, drawn after the static scene's (any buffer without).
            previous: i.geometries.last().expect("the static scene's geometry").previous,
            scene: t.scene,
        };
        let kernel = &t.kernels.primary;
        f.row(Row::GBufferTrace, || l.gbuffer_trace.record(cmd, kernel, &inputs, g));
    }
    if plan.shadow_rays() {
        f.row(Row::ShadowClassify, || {
            l.shadow_trace.classify(cmd, ubo, g, &l.shadow.out, shadows)
        });
        f.row(Row::ShadowCompact, || {
            l.shadow_compact.record(cmd, &l.shadow_trace.out.mask)
        });
        let list = &l.shadow_compact.out;
        let kernel = (&t.kernels.shadow, &t.scene);
        f.row(Row::ShadowTrace, || l.shadow_trace.trace(cmd, kernel, ubo, g, list));
    }
    let sun = Sun {
        map: &l.shadow.out,
        visibility: &l.shadow_trace.out.visibility,
        traced: plan.shadow_rays(),
    };
    f.row(Row::LightDirect, || l.light.record(cmd, ubo, g, sun));
}

/// `ssr.hiz` to `reflect.denoise`, as `plan` says (after its recheck, if any); a
/// marching hybrid frame's counts into `counts` (they price the march in rays:
/// `exchange`).
fn record_reflections<'a, T: Tracer>(
    f: &mut FrameRecorder<'_>,
    plan: &FramePlan,
    (d, cmd): (&ash::Device, vk::CommandBuffer),
    (l, r): (&'a Lighting, &'a mut Reflections),
    i: &FrameInputs<'a>,
    t: &Traced<'a, T>,
    counts: &mut FrameCounts,
) {
    // The passes the frame reads for all of 'a (the traced scene's lifetime), and the
    // one it writes (the glossy filter's history).
    let Reflections {
        hiz,
        ssr,
        compact,
        rt,
        merge,
        denoise,
    } = r;
    let (hiz, ssr, compact, rt, merge) = (&*hiz, &*ssr, &*compact, &*rt, &*merge);
    if let Some(idle) = plan.recheck_plan() {
        let sources = (ssr, compact, rt, merge);
        f.row(Row::ReflectRecheck, || record_recheck(&idle, cmd, l, sources, i, t));
    }
    let (ubo, g, st) = (i.ubo, &l.gbuffer.out, i.st);
    let params = plan.ssr_params(st);
    if plan.runs(Row::SsrHiz) {
        f.row(Row::SsrHiz, || hiz.record(cmd, &g.depth));
    }
    if let Some(kind) = plan.classify {
        f.row(Row::SsrClassify, || ssr.classify(cmd, (ubo, g), &params, kind));
    }
    if plan.marches {
        let inputs = MarchInputs {
            frame: ubo,
            gbuffer: g,
            lit: &l.light.out,
            hiz: &hiz.out,
        };
        f.row(Row::SsrTrace, || ssr.trace(cmd, &inputs, &params));
    }
    if plan.runs(Row::RtReflect) {
        f.row(Row::SsrCompact, || compact.record(cmd, &ssr.out.mask));
        let inputs = reflect_inputs(l, (ssr, compact), i, t);
        let kernel = &t.kernels.reflect;
        f.row(Row::RtReflect, || {
            rt.record(cmd, kernel, &inputs, st.max_bounces, plan.shadows)
        });
    }
    if plan.counts {
        let o = &ssr.out;
        let lists = [&o.march_args, &compact.out.indirect, &o.ssr_first_marches];
        let path = plan.frame_path();
        counts.record((d, cmd), lists, (plan.tile_rate, plan.hybrid.priced(), path));
    }
    if plan.runs(Row::ReflectMerge) {
        let inputs = merge_inputs(l, (ssr, rt), i);
        f.row(Row::ReflectMerge, || merge.record(cmd, &inputs, merge_params(plan, st)));
    }
    if plan.denoise {
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
        f.row(Row::ReflectDenoise, || denoise.record(cmd, &inputs, params, i.uniforms));
    }
}

/// The frame's recheck (`idle`: `FramePlan::recheck_plan`): the idle path's
/// classification, rays and merge, recorded as an idle frame records them but under one
/// scope (`reflect.recheck`); the frame's own path that follows writes every output again
/// (each pass's own barriers order it after these as after the frame before), so the
/// frame shows it. The idle path's price is this row with the frame's
/// `reflect.denoise`, which every path runs alike (`exchange::take_frame`).
fn record_recheck<'a, T: Tracer>(
    idle: &FramePlan,
    cmd: vk::CommandBuffer,
    l: &'a Lighting,
    (ssr, compact, rt, merge): (&'a SsrPass, &'a CompactPass, &'a RtReflectPass, &'a MergePass),
    i: &FrameInputs<'a>,
    t: &Traced<'a, T>,
) {
    let (ubo, g, st) = (i.ubo, &l.gbuffer.out, i.st);
    let kind = idle.classify.expect("an idle path classifies");
    ssr.classify(cmd, (ubo, g), &idle.ssr_params(st), kind);
    compact.record(cmd, &ssr.out.mask);
    let inputs = reflect_inputs(l, (ssr, compact), i, t);
    rt.record(cmd, &t.kernels.reflect, &inputs, st.max_bounces, idle.shadows);
    let inputs = merge_inputs(l, (ssr, rt), i);
    merge.record(cmd, &inputs, merge_params(idle, st));
}

/// What `rt.reflect` reads: the ray list `compact` made of `ssr`'s fail mask.
fn reflect_inputs<'a, T: Tracer>(
    l: &'a Lighting,
    (ssr, compact): (&'a SsrPass, &'a CompactPass),
    i: &FrameInputs<'a>,
    t: &Traced<'a, T>,
) -> ReflectInputs<'a, T> {
    ReflectInputs {
        frame: i.ubo,
        gbuffer: &l.gbuffer.out,
        surfaces: i.surfaces,
        shadow_map: &l.shadow.out,
        list: &compact.out,
        scene: t.scene,
        hit_distance: &ssr.out.hit_distance,
    }
}

/// What `reflect.merge` reads: SSR's and the rays' colours by the fail mask.
fn merge_inputs<'a>(
    l: &'a Lighting,
    (ssr, rt): (&'a SsrPass, &'a RtReflectPass),
    i: &FrameInputs<'a>,
) -> MergeInputs<'a> {
    MergeInputs {
        frame: i.ubo,
        gbuffer: &l.gbuffer.out,
        fail_mask: &ssr.out.mask,
        ssr: &ssr.out.color,
        rt: &rt.out,
    }
}

/// How `plan`'s merge merges (its seams' blur).
fn merge_params(plan: &FramePlan, st: &Settings) -> MergeParams {
    MergeParams {
        rt_enabled: plan.runs(Row::RtReflect),
        reflective_min: st.reflective_min,
        blur: plan.blur,
    }
}

/// The passes that step what moves, and the moving structures' builders.
struct Steps<'a> {
    transform: &'a SimTransformPass,
    cloth: &'a ClothPass,
    skin: &'a SimSkinPass,
    builder: &'a LbvhBuilder,
    khr: Option<&'a mut KhrScene>,
}

/// The frame's motion rows (`sim.*`, then the moving BVH or acceleration structures)
/// as `plan` says, the first step that writes the vertices keeping the last frame's
/// (or, paused, the copy alone); the rigid step's host milliseconds when it ran.
fn record_motion(
    f: &mut FrameRecorder<'_>,
    plan: &FramePlan,
    (d, cmd, slot): (&ash::Device, vk::CommandBuffer, usize),
    dy: &mut DynamicGeometry,
    steps: Steps<'_>,
) -> Option<f64> {
    if plan.previous == Previous::Held {
        dy.keep_previous(d, cmd, false);
    }
    if !plan.runs(Row::SimRigid) {
        return None;
    }
    let sim_ms = f.host_row(Row::SimRigid, || dy.step(slot));
    let keep = |dy: &mut DynamicGeometry, row| {
        if plan.keeps_previous(row) {
            dy.keep_previous(d, cmd, true);
        }
    };
    if plan.runs(Row::SimTransform) {
        f.row(Row::SimTransform, || {
            keep(dy, Row::SimTransform);
            steps.transform.record_posed(cmd, &dy.rigid, slot, &dy.mesh.vertices)
        });
    }
    if plan.runs(Row::SimCloth) {
        f.row(Row::SimCloth, || {
            keep(dy, Row::SimCloth);
            dy.cloths
                .iter()
                .for_each(|c| steps.cloth.record(cmd, c, &dy.mesh.vertices))
        });
    }
    if plan.runs(Row::SimSkin) {
        f.row(Row::SimSkin, || {
            keep(dy, Row::SimSkin);
            let (model, _) = dy.animated.as_ref().expect("the plan's skin");
            steps.skin.record_posed(cmd, model, slot, &dy.mesh.vertices)
        });
    }
    if plan.runs(Row::DynamicBvh) {
        f.staged_row(Row::DynamicBvh, |timer| {
            dy.bvh
                .record(cmd, timer, steps.builder, dy.mesh.triangles(), dy.rigid.poses())
        });
    }
    if plan.runs(Row::DynamicAccel) {
        let k = steps.khr.expect("the plan's vendor tracer");
        let poses = dy.world.poses();
        f.staged_row(Row::DynamicAccel, |timer| {
            k.record_frame(cmd, timer, slot, &poses, &dy.mesh.triangles())
        });
    }
    Some(sim_ms)
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
