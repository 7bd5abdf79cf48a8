//! `speculum bench dynamic`: what a moving scene costs per frame as its dynamic
//! geometry grows. For each body count of a scene with a `[spawn]` (`stress`), each
//! cloth resolution of a scene with cloths (`cloth`), or each size of a skinned tube
//! (`builtin::skinned_tube`), the
//! frames of one run give the medians of `sim.rigid` (CPU), `sim.transform`, `sim.skin`, the
//! dynamic BVH's rebuild (its five `lbvh.*` stages summed per frame), a refit of the
//! same BVH over the same frame (timed after the frame, side by side), `rt.reflect`
//! and the frame. At the last frame, rays are traced through the BVH rebuilt that
//! frame and through one built at the first measured frame and refit since (refit
//! trees trace slower as the bodies scatter). Checked: both BVHs' hits equal the CPU
//! BVH's over the frame's vertices on a sample of the rays. On a device with the
//! vendor tracer, the same frames again through it (`tracer = khr`): its top level's
//! rebuild and the cloth's bottom-level update against the LBVH's rebuild, and the
//! frame (the `tracer` setting is ignored: both run).

use super::lbvh::{check_hits, incoherent_rays};
use super::rays::Through;
use crate::cpu_ref::trace::CpuBvh;
use crate::error::Result;
use crate::gpu_types::{Hit, Ray};
use crate::passes::rt_trace::TracePass;
use crate::renderer::{FRAME, SIM_RIGID};
use crate::report::{Header, Stat};
use crate::scene::Scene;
use crate::settings::{Settings, Tracer};
use crate::steady::{WarmUp, WarmUpReport};
use crate::tracers::khr;
use crate::tracers::lbvh::{self, Bvh, LbvhBuilder, MortonBits, RefitSchedule};
use crate::tracers::{Lbvh, TraceScene, Traceable};
use crate::vk::{remeasure, remeasure_readout, Context, GpuTimer, TimingCheck};
use crate::Renderer;
use serde::Serialize;
use std::sync::Arc;

/// The dynamic BVH's build stages, summed into `rebuild_ms`.
const BUILD: [&str; 4] = lbvh::BvhKind::Lbvh.stages();

/// One body count.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicPoint {
    /// How the warm-up went (`steady`). The measured frames of a moving scene are each
    /// a different frame, so none is measured again for straying.
    pub warmup: WarmUpReport,
    pub bodies: u32,
    /// Particles per side of the scene's cloths (0: none).
    pub cloth_resolution: u32,
    /// Joints of the scene's animated model (0: none).
    pub joints: u32,
    pub dynamic_triangles: u32,
    /// CPU wall clock.
    pub sim_rigid_ms: Stat,
    pub sim_transform_ms: Stat,
    /// The cloths' step (0 without cloth).
    pub sim_cloth_ms: Stat,
    /// The animated model's skinning (0 without one).
    pub sim_skin_ms: Stat,
    /// The per-frame rebuild: `lbvh.bounds` … `lbvh.fit` summed.
    pub rebuild_ms: Stat,
    /// `lbvh.refit` of the same BVH over the same frame's vertices.
    pub refit_ms: Stat,
    /// Median over frames of refit / rebuild.
    pub refit_over_rebuild: f64,
    /// With an animated model, the median over frames of (`sim.skin` + refit) /
    /// rebuild: what following the skin costs against rebuilding its tree.
    pub skin_refit_over_rebuild: Option<f64>,
    pub rt_reflect_ms: Stat,
    pub frame_ms: Stat,
    /// GPU ms (`rt.trace`, median of 3) to trace `rays` random rays at the last frame
    /// through the BVH rebuilt that frame, and through one built at the first measured
    /// frame and refit since.
    pub trace_rebuilt_ms: f64,
    pub trace_refit_ms: f64,
    pub rays: u32,
    /// Sampled rays whose hits differ from the CPU BVH's (beyond genuine ties), both
    /// BVHs together; 0 when valid.
    pub mismatches: u32,
    /// The same frames through the vendor tracer (`null` on a device without it).
    pub khr: Option<KhrPoint>,
    /// The self-check of every timed frame, refit and traversal (`vk::timing`).
    pub timing: TimingCheck,
    pub valid: bool,
}

/// One point's frames through the vendor tracer (`tracer = khr`): its per-frame
/// structures (the top level rebuilt; the cloth's bottom level updated, rebuilt every
/// `refit_rebuild_every` frames) against the LBVH's rebuild, and the frame.
#[derive(Clone, Debug, Serialize)]
pub struct KhrPoint {
    pub as_tlas_ms: Stat,
    /// `as.cloth` (0 without cloth).
    pub as_cloth_ms: Stat,
    pub rt_reflect_ms: Stat,
    pub frame_ms: Stat,
    /// Median frame over the LBVH's median frame (measured before it, not interleaved).
    pub frame_over_lbvh: f64,
}

/// The `bench dynamic` report.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicReport {
    #[serde(flatten)]
    pub header: Header,
    pub scene: String,
    pub resolution: [u32; 2],
    pub frames: u32,
    /// The warm-up's rule (`frames N`, or `steady`); each point says how its went.
    pub warmup: String,
    pub points: Vec<DynamicPoint>,
    /// Dynamic BVH rebuild time at the largest body count / at the smallest, and the
    /// same ratio of dynamic triangles: near-linear growth keeps the first near the second.
    pub rebuild_growth: f64,
    pub triangle_growth: f64,
    pub valid: bool,
}

fn stat(samples: &[f64]) -> Stat {
    Stat::of(samples).expect("at least one frame")
}

/// The hits of `rays` through the dynamic BVH `t` alone (triangle ids with the dynamic
/// BVH's bit) and the median of three traversals' ms,
/// each self-checked against its wall clock.
fn trace_median(
    tracer: &TracePass<Lbvh>,
    rays: &[Ray],
    t: Traceable<'_>,
    timing: &mut TimingCheck,
) -> Result<(Vec<Hit>, f64)> {
    let mut times = Vec::new();
    let mut hits = Vec::new();
    for _ in 0..3 {
        let (readout, discarded);
        let scene = TraceScene::of_dynamic(t.bvh, t.geometry);
        (hits, readout, discarded) = remeasure(|| tracer.trace(rays, scene, false))?;
        timing.add_measured(readout.problem.as_deref(), discarded);
        times.push(readout.get(crate::passes::rt_trace::NAME).unwrap_or(f64::NAN));
    }
    let ms = stat(&times).median;
    Ok((hits, ms))
}

/// Per measured frame, the figures `measure_frames` lists.
type Series = [Vec<f64>; 10];

/// Renders `frames` frames of `r`: per frame the ms of `sim.rigid`, `sim.transform`,
/// `sim.cloth`, `sim.skin`, the rebuild, the scheduled refit a frame would do instead (timed apart,
/// its schedule made outside the timing), `rt.reflect`, the frame, refit / rebuild and
/// (skin + refit) / rebuild;
/// and a tree built at the first frame with its refit schedule, to refit at the end.
fn measure_frames(
    ctx: &Arc<Context>,
    r: &mut Renderer,
    frames: u32,
    timing: &mut TimingCheck,
    tick: super::Tick<'_>,
) -> Result<(Series, (Bvh, RefitSchedule))> {
    let builder = LbvhBuilder::new(ctx)?;
    let mut timer = GpuTimer::new(ctx, 8)?;
    // A tree built at the first measured frame and refit to the last: how a refit
    // tree's traversal ages.
    let aged = Bvh::new(ctx, r.dynamic_triangles(), MortonBits::Bits30)?;
    let mut aged_schedule = None;
    let mut series = Series::default();
    for k in 0..frames {
        let times = r.render_frame()?;
        timing.add(times.problem.as_deref());
        tick();
        let get = |name: &str| times.get(name).unwrap_or(0.0);
        let traceable = r.dynamic_traceable().expect("a dynamic scene");
        if k == 0 {
            ctx.one_shot(|cmd| {
                timer.reset(cmd);
                builder.record_build(cmd, &mut timer, traceable.geometry, &aged);
            })?;
            aged_schedule = Some(RefitSchedule::of(ctx, &aged)?);
        }
        let schedule = RefitSchedule::of(ctx, traceable.bvh)?;
        // A refit of unchanged vertices does the same work each run: re-measured.
        let (refit, discarded) = remeasure_readout(|| {
            timer.one_shot(|cmd, timer| {
                builder.record_refit_scheduled(cmd, timer, traceable.geometry, traceable.bvh, &schedule)
            })
        })?;
        timing.add_measured(refit.problem.as_deref(), discarded);
        let refit = refit.get(lbvh::REFIT).unwrap_or(f64::NAN);
        let rebuild: f64 = BUILD.iter().map(|s| get(s)).sum();
        let skin = get(crate::passes::sim_skin::NAME);
        for (s, v) in series.iter_mut().zip([
            get(SIM_RIGID),
            get(crate::passes::sim_transform::NAME),
            get(crate::passes::sim_cloth::NAME),
            skin,
            rebuild,
            refit,
            get(crate::passes::rt_reflect::NAME),
            get(FRAME),
            refit / rebuild,
            (skin + refit) / rebuild,
        ]) {
            s.push(v);
        }
    }
    Ok((series, (aged, aged_schedule.expect("frames > 0"))))
}

/// Measures `scene` (its bodies as given) for `frames` frames after the warm-up.
pub fn run_point(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &Settings,
    warmup: WarmUp,
    frames: u32,
    rays: u32,
    tick: super::Tick<'_>,
) -> Result<DynamicPoint> {
    // Rebuilt every frame (a cloth would be refit): the refit is timed apart.
    let settings = Settings {
        cloth_rebuild: true,
        tracer: Tracer::Lbvh,
        ..settings.clone()
    };
    let mut r = Renderer::new(ctx, scene, &settings)?;
    let warmup_report = crate::headless::warm_up(&mut [&mut r], warmup, tick)?;
    r.reset_simulation()?;
    let mut timing = TimingCheck::default();
    let tris = r.dynamic_triangles();
    let (series, aged) = measure_frames(ctx, &mut r, frames, &mut timing, tick)?;
    let (builder, mut timer) = (LbvhBuilder::new(ctx)?, GpuTimer::new(ctx, 8)?);
    let fresh = r.dynamic_traceable().expect("a dynamic scene");
    let (aged, aged_schedule) = aged;
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        builder.record_refit_scheduled(cmd, &mut timer, fresh.geometry, &aged, &aged_schedule);
    })?;
    let vertices = r.read_dynamic_vertices()?.expect("a dynamic scene");
    let indices = scene.dynamic_meshes().indices;
    let (lo, hi) = vertices.iter().fold((glam::Vec3::MAX, glam::Vec3::MIN), |(lo, hi), v| {
        let p = glam::Vec3::from(v.position);
        (lo.min(p), hi.max(p))
    });
    let ray_set = incoherent_rays(lo, hi, rays, 41);
    let tracer = TracePass::<Lbvh>::new(ctx)?;
    let mut through = |bvh: &Bvh| {
        let t = Traceable {
            bvh,
            geometry: fresh.geometry,
        };
        trace_median(&tracer, &ray_set, t, &mut timing)
    };
    let (rebuilt_hits, trace_rebuilt_ms) = through(fresh.bvh)?;
    let (refit_hits, trace_refit_ms) = through(&aged)?;
    let cpu = CpuBvh::build(&vertices, &indices);
    let sample = rays.min(2000);
    // Hits through the dynamic BVH: their ids carry its bit.
    let check = |hits: &[Hit]| check_hits(&ray_set, hits, &cpu, &vertices, &indices, (sample, Through::Dynamic)).0;
    let (m1, m2) = (check(&rebuilt_hits), check(&refit_hits));
    let [sim, transform, cloth, skin, rebuild, refit, rt_reflect, frame, ratio, skin_ratio] = series;
    let mismatches = m1 + m2;
    let frame_ms = stat(&frame);
    let khr = match ctx.ray_tracing {
        Some(_) => Some(khr_point(
            ctx,
            scene,
            &settings,
            (warmup, frames),
            frame_ms.median,
            &mut timing,
            tick,
        )?),
        None => None,
    };
    Ok(DynamicPoint {
        warmup: warmup_report,
        bodies: scene.bodies.len() as u32,
        cloth_resolution: scene.cloths.first().map_or(0, |c| c.resolution),
        joints: scene.animated.as_ref().map_or(0, |a| a.joints.len() as u32),
        dynamic_triangles: tris,
        sim_rigid_ms: stat(&sim),
        sim_transform_ms: stat(&transform),
        sim_cloth_ms: stat(&cloth),
        sim_skin_ms: stat(&skin),
        rebuild_ms: stat(&rebuild),
        refit_ms: stat(&refit),
        refit_over_rebuild: stat(&ratio).median,
        skin_refit_over_rebuild: scene.animated.is_some().then(|| stat(&skin_ratio).median),
        rt_reflect_ms: stat(&rt_reflect),
        frame_ms,
        trace_rebuilt_ms,
        trace_refit_ms,
        rays,
        mismatches,
        khr,
        timing,
        valid: mismatches == 0 && frame_ms.median.is_finite() && trace_rebuilt_ms > 0.0,
    })
}

/// The frames of `run_point` through the vendor tracer, the cloth updated as the
/// LBVH's would be refit (`cloth_rebuild` off).
fn khr_point(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &Settings,
    (warmup, frames): (WarmUp, u32),
    lbvh_frame_ms: f64,
    timing: &mut TimingCheck,
    tick: super::Tick<'_>,
) -> Result<KhrPoint> {
    let settings = Settings {
        tracer: Tracer::Khr,
        cloth_rebuild: false,
        ..settings.clone()
    };
    let mut r = Renderer::new(ctx, scene, &settings)?;
    crate::headless::warm_up(&mut [&mut r], warmup, &mut || {})?;
    r.reset_simulation()?;
    let mut series: [Vec<f64>; 4] = Default::default();
    for _ in 0..frames {
        let times = r.render_frame()?;
        timing.add(times.problem.as_deref());
        tick();
        let get = |name: &str| times.get(name).unwrap_or(0.0);
        let names = [khr::TLAS, khr::CLOTH, crate::passes::rt_reflect::NAME, FRAME];
        for (s, name) in series.iter_mut().zip(names) {
            s.push(get(name));
        }
    }
    let [tlas, cloth, rt_reflect, frame] = series;
    let frame_ms = stat(&frame);
    Ok(KhrPoint {
        as_tlas_ms: stat(&tlas),
        as_cloth_ms: stat(&cloth),
        rt_reflect_ms: stat(&rt_reflect),
        frame_over_lbvh: frame_ms.median / lbvh_frame_ms,
        frame_ms,
    })
}
