//! `speculum bench lbvh`: GPU BVH builds (the LBVH, and PLOC for geometry built once)
//! and traversal on random soups and scenes.
//!
//! Per case and builder: per-stage GPU medians over repeated builds, build throughput, refit time,
//! memory per triangle, the SAH cost of the tree relative to a CPU binned-SAH BVH over
//! the same triangles, and traversal throughput for coherent (pinhole camera) and
//! incoherent (random) rays. Checked in the same run: the BVH invariants after the
//! timed builds, and a sample of each ray set against the CPU SAH BVH's hits.

use super::anchor::{AnchorReport, AnchorRuns, AnchorSet};
pub(crate) use super::rays::check_hits;
use super::rays::{both_sets, time_rays, RefilledReport, Through};
pub use super::rays::{CpuCheck, RaySetReport};
use crate::cpu_ref::lbvh::{check_bvh, sah_cost};
use crate::error::Result;
use crate::gpu_types::{GpuVertex, Hit, Ray};
use crate::passes::rt_trace::{Refill, TracePass};
use crate::report::{Header, PassTimes, Stat};
use crate::shader_defines::SORT_RADIX_BITS;
use crate::tracers::lbvh::ploc::{first_rounds, PlocScratch};
use crate::tracers::lbvh::sort::STEPS;
use crate::tracers::lbvh::{
    Bvh, BvhKind, Geometry, LbvhBuilder, MortonBits, RefitSchedule, StaticLayout, UploadedTriangles,
};
use crate::tracers::{Lbvh, TraceScene};
use crate::vk::{remeasure, remeasure_readout, Context, GpuTimer, TimerReadout, TimingCheck, Timings};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::sync::Arc;

/// What to measure.
#[derive(Clone, Debug, Serialize)]
pub struct Options {
    /// Timed repetitions of each build and trace (medians are reported).
    pub repeats: u32,
    /// Rays per ray set.
    pub rays: u32,
    /// Rays of each set checked against the CPU.
    pub check_rays: u32,
    pub bits: MortonBits,
    /// The trees built of each case, in this order.
    pub builders: Vec<BvhKind>,
    /// The static walk's layouts each tree is walked in, in this order.
    pub layouts: Vec<StaticLayout>,
    /// Rays from a file (`--rays-file`), traced as a third set.
    #[serde(skip)]
    pub file_rays: Option<Vec<Ray>>,
    /// Keep the hits of the file's rays (or, without a file, of the incoherent set)
    /// for `--dump-hits`.
    #[serde(skip)]
    pub keep_hits: bool,
    /// Rays of each set the vendor tracer traces (the first of them; 0: no vendor
    /// tracer), on the first builder's case (`bench::khr`).
    pub khr_rays: u32,
    /// The sort's scatter writes its tiles out in order (`sort::SortTile::local`; `--local-sort-scatter`).
    pub local_sort_scatter: bool,
    /// Every sort of more than one tile runs its scan (`sort::SortTile::fused` 0; `--sort-scan`).
    pub sort_scan: bool,
    /// Also trace both sets through the walk with its lanes refilled
    /// (`TracePass::refilled`), in each of these shapes.
    pub refilled: Vec<Refill>,
}

/// Mean steps (nodes visited), box tests and triangle tests of a ray's walk, and the
/// share of lanes a SIMD group of 8 and of 32 keeps busy walking consecutive rays
/// (`cpu_ref::walk::lockstep_busy`: the divergence a device of that width pays).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct WalkPerRay {
    pub steps: f64,
    pub boxes: f64,
    pub triangles: f64,
    pub lanes_busy_8: f64,
    pub lanes_busy_32: f64,
}

/// Consecutive rays replayed together (`WalkPerRay::of`): the widest lockstep group.
const REPLAY_RUN: usize = 32;

impl WalkPerRay {
    /// `of` the coherent and the incoherent set, walked in `layout`.
    fn both(packed: &crate::gpu_types::PackedBvh, sets: [&[Ray]; 2], sample: u32, layout: StaticLayout) -> [Self; 2] {
        sets.map(|rays| Self::of(packed, rays, sample, layout.slots()))
    }

    /// Over about `sample` rays of `rays`, in runs of `REPLAY_RUN` consecutive rays
    /// evenly spaced through the set (a dispatch walks consecutive rays side by side),
    /// walked through `packed` with `slots` children a node: the means, and the
    /// lockstep shares within the runs.
    fn of(packed: &crate::gpu_types::PackedBvh, rays: &[Ray], sample: u32, slots: u32) -> Self {
        let run = REPLAY_RUN.min(rays.len()).max(1);
        let runs = (sample as usize / run).clamp(1, (rays.len() / run).max(1));
        let stride = rays.len() / runs;
        let all: Vec<crate::cpu_ref::walk::WalkCounts> = (0..runs)
            .flat_map(|k| &rays[k * stride..(k * stride + run).min(rays.len())])
            .map(|r| crate::cpu_ref::walk::replay(&packed.nodes, &packed.tris, r, slots).1)
            .collect();
        let mean = |f: fn(&crate::cpu_ref::walk::WalkCounts) -> u32| {
            all.iter().map(|c| f(c) as f64).sum::<f64>() / all.len().max(1) as f64
        };
        // Runs of 32 (or one run): no group of 8 or 32 spans two runs.
        let steps: Vec<u32> = all.iter().map(|c| c.steps).collect();
        let busy = |width| crate::cpu_ref::walk::lockstep_busy(&steps, width);
        Self {
            steps: mean(|c| c.steps),
            boxes: mean(|c| c.boxes),
            triangles: mean(|c| c.triangles),
            lanes_busy_8: busy(8),
            lanes_busy_32: busy(32),
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    pub name: String,
    /// How the tree was made from the sorted keys.
    pub builder: BvhKind,
    /// How the static walk reads it (`lbvh.compact`).
    pub layout: StaticLayout,
    pub triangles: u32,
    pub morton_bits: u32,
    /// Stage → GPU milliseconds, in build order.
    pub stages_ms: PassTimes,
    /// The sort's steps (`lbvh.sort.count`, `.scan`, `.scatter`), each summed over the
    /// passes (a sort of one tile: the scatter alone, the others null).
    pub sort_steps_ms: PassTimes,
    /// GPU milliseconds of a whole build (for PLOC, its first submission:
    /// `first_rounds` rounds and the tail), timed as one scope (its stages unstamped).
    pub build_ms: Stat,
    /// The same builds timed stage by stage (`stages_ms`), the stamps between stages
    /// and their barriers included.
    pub staged_build_ms: Stat,
    /// PLOC rounds a build needed beyond the first submission's (submitted again,
    /// untimed; 0 for the LBVH).
    pub untimed_rounds: u32,
    /// Builds beyond 2x the median built again (`steady`); unsettled: not valid.
    pub build_rounds_check: crate::steady::RoundsCheck,
    /// Million triangles built per second (at the median build time).
    pub mtris_per_s: f64,
    /// GPU milliseconds of the frame's refit (`record_refit_scheduled`) of the tree
    /// just built.
    pub refit_ms: Stat,
    /// GPU milliseconds of `lbvh.compact` after that refit: the compact nodes the
    /// walk of the static BVH reads (which the rays below walk), made once for a
    /// static BVH and not part of the build.
    pub compact_ms: Stat,
    /// Internal nodes per triangle.
    pub nodes_per_triangle: f64,
    /// What a walk of this tree in this layout does per ray, replayed on the CPU
    /// (`cpu_ref::walk`: the same on every device) over the checked rays of the
    /// coherent and the incoherent set.
    pub walk_per_ray: [WalkPerRay; 2],
    /// BVH bytes (nodes, compact nodes and triangles) per triangle.
    pub bytes_per_triangle: f64,
    /// Rebuild scratch (sort buffers, counters) per triangle.
    pub scratch_bytes_per_triangle: f64,
    /// SAH cost of the tree (unit traversal and triangle costs, relative to the root
    /// area).
    pub sah: f64,
    pub sah_cpu_binned: f64,
    /// `sah / sah_cpu_binned`: 1.0 would match the CPU builder.
    pub sah_ratio: f64,
    /// CPU milliseconds of the reference binned-SAH build (for scale, not a contest).
    pub cpu_sah_build_ms: f64,
    pub coherent: RaySetReport,
    pub incoherent: RaySetReport,
    /// The coherent and the incoherent set through the tree's own 64-byte nodes, as
    /// the dynamic BVH's walk reads them (no `lbvh.compact`); on each builder's first
    /// layout's case (the tree is the same in each), `None` on the others.
    pub exact_nodes: Option<[RaySetReport; 2]>,
    /// The coherent and the incoherent set through the walk with its lanes refilled
    /// (`TracePass::refilled`: the same tree and layout, each invocation taking a new
    /// ray when its walk ends), in each shape of `Options::refilled`.
    pub refilled: Vec<RefilledReport>,
    /// The rays of `--rays-file`, when given.
    pub file: Option<RaySetReport>,
    /// Embree 3 on the same triangles and rays, LOW then MEDIUM (built with the cargo
    /// feature `embree`; `null` without it).
    pub embree: Option<Vec<AnchorReport>>,
    /// The vendor tracer, file and Morton order (`bench::khr`): on the first builder's
    /// case, on a device with ray tracing; `null` otherwise.
    pub khr: Option<Vec<super::khr::KhrReport>>,
    /// The traced rays and their hits kept for `--dump-rays` / `--dump-hits`.
    #[serde(skip)]
    pub kept: Option<(Vec<Ray>, Vec<Hit>)>,
    /// The BVH passed every invariant after the timed builds.
    pub invariants_ok: bool,
    pub invariant_error: Option<String>,
    /// The self-check of every timed build, refit and ray batch (`vk::timing`).
    pub timing: TimingCheck,
    pub valid: bool,
}

/// The `bench lbvh` report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    #[serde(flatten)]
    pub header: Header,
    pub options: Options,
    pub cases: Vec<CaseReport>,
    /// Every case valid.
    pub valid: bool,
}

/// Rays of a pinhole camera looking at the box from outside, one per pixel of a
/// square image: neighbouring rays are nearly parallel (coherent).
pub fn coherent_rays(lo: Vec3, hi: Vec3, count: u32) -> Vec<Ray> {
    let side = (count as f64).sqrt().ceil() as u32;
    let center = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let eye = center + Vec3::new(0.3, 0.4, 1.0).normalize() * radius * 2.2;
    let forward = (center - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let half = (30f32).to_radians().tan();
    (0..count)
        .map(|k| {
            let (x, y) = (k % side, k / side);
            let sx = ((x as f32 + 0.5) / side as f32 * 2.0 - 1.0) * half;
            let sy = ((y as f32 + 0.5) / side as f32 * 2.0 - 1.0) * half;
            let d = forward + right * sx - up * sy;
            Ray {
                origin: eye.to_array(),
                tmin: 0.0,
                dir: d.to_array(),
                tmax: f32::MAX,
            }
        })
        .collect()
}

/// Rays from random points in the box in uniformly random directions (incoherent).
pub fn incoherent_rays(lo: Vec3, hi: Vec3, count: u32, seed: u64) -> Vec<Ray> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
            let d = loop {
                let v = Vec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                    break v.normalize();
                }
            };
            Ray {
                origin: o.to_array(),
                tmin: 0.0,
                dir: d.to_array(),
                tmax: f32::MAX,
            }
        })
        .collect()
}

/// One whole build of `geometry` into `bvh` (the `BUILD` scope around its stages),
/// submitted and waited for; its GPU milliseconds per scope, self-checked.
pub fn timed_build(
    timer: &mut GpuTimer,
    builder: &LbvhBuilder,
    geometry: Geometry<'_>,
    bvh: &Bvh,
) -> Result<TimerReadout> {
    timer.one_shot(|cmd, timer| {
        timer.begin(cmd, BUILD);
        builder.record_build(cmd, timer, geometry, bvh);
        timer.end(cmd, BUILD);
    })
}

/// One whole PLOC build (as `timed_build`): the first submission timed, then the rounds
/// it left (`finish`) submitted untimed; also returns how many rounds those were.
pub fn timed_ploc_build(
    timer: &mut GpuTimer,
    builder: &LbvhBuilder,
    geometry: Geometry<'_>,
    bvh: &Bvh,
    scratch: &PlocScratch,
) -> Result<(TimerReadout, u32)> {
    let readout = timer.one_shot(|cmd, timer| {
        timer.begin(cmd, BUILD);
        builder.record_build_ploc(cmd, timer, geometry, bvh, scratch);
        timer.end(cmd, BUILD);
    })?;
    let first = first_rounds(geometry.tri_count);
    let rounds = builder.ploc.finish(geometry.tri_count, bvh, scratch, first)?;
    Ok((readout, rounds - first))
}

/// The sort's steps (`sort::STEPS`, each summed over its passes) in `opts.repeats`
/// LBVH builds of `geometry` into `bvh`, each timed step by step (`time_sort_steps`; a
/// readout that fails its self-check measured again), in builds of their own before
/// the timed ones (the steps' stamps and barriers would add to those): once a case,
/// with its first builder and layout (`kind`, `layout`; others get nulls).
fn time_sort_steps(
    ctx: &Arc<Context>,
    (builder, geometry, bvh): (&mut LbvhBuilder, Geometry<'_>, &Bvh),
    opts: &Options,
    (kind, layout): (BvhKind, StaticLayout),
) -> Result<PassTimes> {
    let mut steps = Timings::default();
    if (kind, layout) != (opts.builders[0], opts.layouts[0]) {
        return Ok(PassTimes::of_scopes(&steps, &STEPS));
    }
    let mut timer = GpuTimer::new(ctx, 8 + 3 * 64 / SORT_RADIX_BITS)?;
    builder.time_sort_steps = true;
    for _ in 0..opts.repeats {
        let (readout, discarded) = remeasure_readout(|| timed_build(&mut timer, builder, geometry, bvh))?;
        steps.add_measured(&readout, discarded);
    }
    builder.time_sort_steps = false;
    Ok(PassTimes::of_scopes(&steps, &STEPS))
}

/// What the timed builds of one case measured: per-stage samples, whole builds', and
/// the refit and compact nodes made after each build.
struct BuildTimes {
    stages: Timings,
    whole_ms: Stat,
    refit_ms: Stat,
    compact_ms: Stat,
    /// PLOC rounds beyond the first submission's, the most any build needed.
    untimed_rounds: u32,
    timing: TimingCheck,
    rounds_check: crate::steady::RoundsCheck,
}

/// One warm-up build (pipeline JIT), then `repeats` timed builds of `geometry` into
/// `bvh` (PLOC with `scratch`, else the LBVH), each timed stage by stage and again
/// whole (`GpuTimer::outermost_only`), followed by the frame's refit and the compact
/// nodes. Every readout that fails its self-check is measured again (`remeasure`: a
/// build, a refit and a compaction do the same work each run).
fn time_builds(
    ctx: &Arc<Context>,
    (builder, geometry, bvh): (&LbvhBuilder, Geometry<'_>, &Bvh),
    scratch: Option<&PlocScratch>,
    repeats: u32,
    tick: super::Tick<'_>,
) -> Result<BuildTimes> {
    let mut timer = GpuTimer::new(ctx, 8)?;
    let mut untimed_rounds = 0;
    // One repeat: the build, then the frame's refit, scheduled by height from the tree
    // just built (the schedule is made once per build, as the frame does, and is not
    // timed), then the compaction.
    let mut repeat = || -> Result<super::Round> {
        let build = |timer: &mut GpuTimer| {
            remeasure(|| match scratch {
                Some(scratch) => timed_ploc_build(timer, builder, geometry, bvh, scratch).map(|(t, e)| (e, t)),
                None => Ok((0, timed_build(timer, builder, geometry, bvh)?)),
            })
        };
        let (extra, times, discarded) = build(&mut timer)?;
        timer.outermost_only(true);
        let whole = build(&mut timer);
        timer.outermost_only(false);
        let (_, whole, whole_discarded) = whole?;
        untimed_rounds = untimed_rounds.max(extra);
        let schedule = RefitSchedule::of(ctx, bvh)?;
        let refit = remeasure_readout(|| {
            timer.one_shot(|cmd, timer| builder.record_refit_scheduled(cmd, timer, geometry, bvh, &schedule))
        })?;
        let compact = remeasure_readout(|| timer.one_shot(|cmd, timer| builder.record_compact(cmd, timer, bvh)))?;
        tick();
        Ok(vec![(times, discarded), refit, compact, (whole, whole_discarded)])
    };
    // Untimed: its pipelines' first use. Then a repeat whose build strays beyond 2x the
    // median is measured again.
    repeat()?;
    let (measured, rounds_check) = super::measure_rounds(repeats, BUILD, repeat)?;
    let mut stages = Timings::default();
    let (mut refits, mut compacts, mut wholes) = (Vec::new(), Vec::new(), Vec::new());
    let mut timing = TimingCheck::default();
    for m in &measured {
        stages.add_measured(&m[0].0, m[0].1);
        for ((readout, discarded), out) in m[1..].iter().zip([&mut refits, &mut compacts, &mut wholes]) {
            out.push(readout.first().map_or(f64::NAN, |r| r.1));
            timing.add_measured(readout.problem.as_deref(), *discarded);
        }
    }
    timing.merge(stages.check());
    Ok(BuildTimes {
        stages,
        whole_ms: Stat::of(&wholes).expect("repeats > 0"),
        refit_ms: Stat::of(&refits).expect("repeats > 0"),
        compact_ms: Stat::of(&compacts).expect("repeats > 0"),
        untimed_rounds,
        timing,
        rounds_check,
    })
}

/// The Embree anchor of case `name`'s ray sets: (rays, Speculum's hits, its Mrays/s,
/// coherent) per set, against its (build, compaction) milliseconds (cargo feature
/// `embree`; `None` without it). Embree runs once a case: `runs` keeps its runs for
/// the case's other builders and layouts, and is made anew for another case.
#[cfg_attr(not(feature = "embree"), allow(unused_variables))]
fn anchor(
    (name, v, i): (&str, &[GpuVertex], &[u32]),
    sets: &[Option<AnchorSet<'_>>; 3],
    (repeats, runs): (u32, &mut Option<AnchorRuns>),
    build_ms: (f64, f64),
) -> Result<Option<Vec<AnchorReport>>> {
    #[cfg(feature = "embree")]
    {
        if !runs.as_ref().is_some_and(|r| r.of(name, sets)) {
            *runs = Some(super::embree::anchor_runs(name, (v, i), sets, repeats)?);
        }
        Ok(runs.as_ref().map(|r| r.report(sets, build_ms)))
    }
    #[cfg(not(feature = "embree"))]
    Ok(None)
}

/// The vendor tracer's figures (`bench::khr`), on the case of the first builder and
/// layout: the
/// case's triangles and its coherent and incoherent rays (and the file's).
fn vendor_tracer(
    ctx: &Arc<Context>,
    (opts, kind, layout): (&Options, BvhKind, StaticLayout),
    (v, i, [coherent, incoherent]): (&[GpuVertex], &[u32], [&[Ray]; 2]),
    cpu: &CpuCheck<'_>,
    (tracer, scene): (&TracePass<Lbvh>, TraceScene<'_>),
) -> Result<Option<Vec<super::khr::KhrReport>>> {
    if opts.builders.first() != Some(&kind) || opts.layouts.first() != Some(&layout) {
        return Ok(None);
    }
    let sets = [Some(coherent), Some(incoherent), opts.file_rays.as_deref()];
    super::khr::reports(ctx, (v, i), sets, (opts.repeats, opts.khr_rays, cpu), (tracer, scene))
}

/// The coherent and the incoherent set through the tree's own nodes, as the dynamic
/// BVH's walk reads them, once per builder (on the first layout's case: the tree is
/// the same in each; `None` on the others).
fn exact_walk(
    (opts, layout): (&Options, StaticLayout),
    (tracer, bvh, geometry): (&TracePass<Lbvh>, &Bvh, Geometry<'_>),
    sets: [&[Ray]; 2],
    cpu: &CpuCheck<'_>,
    timing: &mut TimingCheck,
) -> Result<Option<[RaySetReport; 2]>> {
    if opts.layouts.first() != Some(&layout) {
        return Ok(None);
    }
    let exact = TraceScene::of_dynamic(bvh, geometry);
    both_sets((tracer, exact, Through::Dynamic), sets, opts.repeats, cpu, timing).map(Some)
}

/// The coherent and the incoherent set through the walk with its lanes refilled (in
/// the case's layout), in each shape asked.
fn refilled_walk(
    ctx: &Arc<Context>,
    (opts, layout): (&Options, StaticLayout),
    scene: TraceScene<'_>,
    sets: [&[Ray]; 2],
    cpu: &CpuCheck<'_>,
    timing: &mut TimingCheck,
) -> Result<Vec<RefilledReport>> {
    let walk = |&shape: &Refill| {
        let tracer = TracePass::<Lbvh>::refilled(ctx, layout, shape)?;
        let sets = both_sets((&tracer, scene, Through::Static), sets, opts.repeats, cpu, timing)?;
        Ok(RefilledReport { shape, sets })
    };
    opts.refilled.iter().map(walk).collect()
}

impl CaseReport {
    /// Whether the case is sound: the tree's invariants hold, every ray set's checked
    /// hits are the CPU's with no failed walk and settled rounds, and so are the
    /// vendor tracer's, and the builds settled.
    fn sound(&self) -> bool {
        let sound = |r: &RaySetReport| r.mismatches == 0 && r.failed_walks == 0 && r.rounds_check.settled();
        self.invariants_ok
            && sound(&self.coherent)
            && sound(&self.incoherent)
            && self.file.as_ref().is_none_or(sound)
            && self.exact_nodes.iter().flatten().all(sound)
            && self.refilled.iter().flat_map(|r| &r.sets).all(sound)
            && self.khr.iter().flatten().all(super::khr::KhrReport::sound)
            && self.build_ms.median.is_finite()
            && self.build_rounds_check.settled()
    }
}

/// Benchmarks one triangle set with one builder, walked in one static layout; its
/// Embree anchor's runs are `anchor_runs`' where they are this case's (the case's
/// other builders and layouts), else made and kept there.
// Long: the case's measurements in order (sort steps, builds, checks, ray sets, Embree,
// exact nodes, the vendor tracer), each a call, then the report's fields, one a line.
pub fn run_case(
    ctx: &Arc<Context>,
    name: &str,
    v: &[GpuVertex],
    i: &[u32],
    opts: &Options,
    (kind, layout): (BvhKind, StaticLayout),
    (anchor_runs, tick): (&mut Option<AnchorRuns>, super::Tick<'_>),
) -> Result<CaseReport> {
    let n = (i.len() / 3) as u32;
    let triangles = UploadedTriangles::new(ctx, "bench", v, i)?;
    let geometry = triangles.geometry();
    let mut builder = LbvhBuilder::new(ctx)?;
    let bvh = Bvh::new_static_in(ctx, n, opts.bits, layout)?;
    let sort_steps_ms = time_sort_steps(ctx, (&mut builder, geometry, &bvh), opts, (kind, layout))?;
    let scratch = (kind == BvhKind::Ploc).then(|| PlocScratch::new(ctx, n)).transpose()?;
    let built = time_builds(ctx, (&builder, geometry, &bvh), scratch.as_ref(), opts.repeats, tick)?;
    let mut timing = built.timing;
    let stages_ms = PassTimes::of_scopes(&built.stages, &kind.stages());
    let staged_build_ms = built.stages.samples(BUILD).and_then(Stat::of).expect("repeats > 0");
    let build_ms = built.whole_ms;

    // Checks of the BVH as the timed builds (and refits) left it.
    let packed = bvh.read_packed()?;
    let invariants = check_bvh(&packed, v, i);
    let sah = sah_cost(&packed.nodes, i.len() / 3);
    let (cpu, cpu_sah_build_ms) = CpuCheck::new(v, i, opts.check_rays);
    let sah_cpu = cpu.bvh.sah_cost();

    let tracer = TracePass::<Lbvh>::new(ctx)?;
    let scene = TraceScene::of_static(&bvh, geometry);
    let scene_box = crate::cpu_ref::lbvh::bounds(v, i).1;
    let mut ray_set =
        |rays: &[Ray]| time_rays(&tracer, (scene, Through::Static), rays, opts.repeats, &cpu, &mut timing);
    let coherent_set = coherent_rays(scene_box.lo, scene_box.hi, opts.rays);
    let (coherent, coherent_hits) = ray_set(&coherent_set)?;
    let incoherent_set = incoherent_rays(scene_box.lo, scene_box.hi, opts.rays, 7);
    let (incoherent, incoherent_hits) = ray_set(&incoherent_set)?;
    let file_set = opts
        .file_rays
        .as_ref()
        .map(|rays| Ok::<_, crate::Error>((ray_set(rays)?, rays)));
    let file_set = file_set.transpose()?;
    let sets = [
        Some((&coherent_set[..], &coherent_hits[..], coherent.mrays_per_s, true)),
        Some((&incoherent_set[..], &incoherent_hits[..], incoherent.mrays_per_s, false)),
        file_set
            .as_ref()
            .map(|((r, h), rays)| (&rays[..], &h[..], r.mrays_per_s, false)),
    ];
    let ms = (build_ms.median, built.compact_ms.median);
    let embree = anchor((name, v, i), &sets, (opts.repeats, anchor_runs), ms)?;
    let both = [&coherent_set[..], &incoherent_set[..]];
    let exact_nodes = exact_walk((opts, layout), (&tracer, &bvh, geometry), both, &cpu, &mut timing)?;
    let refilled = refilled_walk(ctx, (opts, layout), scene, both, &cpu, &mut timing)?;
    let walk_per_ray = WalkPerRay::both(&packed, both, opts.check_rays, layout);
    let khr_case = (v, i, both);
    let khr = vendor_tracer(ctx, (opts, kind, layout), khr_case, &cpu, (&tracer, scene))?;
    let (file, kept) = match file_set {
        Some(((report, hits), rays)) => (Some(report), opts.keep_hits.then(|| (rays.clone(), hits))),
        None => (None, opts.keep_hits.then_some((incoherent_set, incoherent_hits))),
    };

    let mut report = CaseReport {
        name: name.into(),
        builder: kind,
        layout,
        triangles: n,
        morton_bits: opts.bits.bits(),
        stages_ms,
        sort_steps_ms,
        build_ms,
        staged_build_ms,
        untimed_rounds: built.untimed_rounds,
        build_rounds_check: built.rounds_check.clone(),
        mtris_per_s: n as f64 / (build_ms.median * 1e3),
        refit_ms: built.refit_ms,
        compact_ms: built.compact_ms,
        nodes_per_triangle: (n - 1).max(1) as f64 / n as f64,
        walk_per_ray,
        bytes_per_triangle: bvh.bytes() as f64 / n as f64,
        scratch_bytes_per_triangle: (bvh.sort.keys[0].size * 2 + bvh.sort.values[0].size * 2) as f64 / n as f64,
        sah,
        sah_cpu_binned: sah_cpu,
        sah_ratio: sah / sah_cpu,
        cpu_sah_build_ms,
        coherent,
        incoherent,
        exact_nodes,
        refilled,
        file,
        embree,
        khr,
        kept,
        invariants_ok: invariants.is_ok(),
        invariant_error: invariants.err(),
        timing,
        valid: false,
    };
    report.valid = report.sound();
    Ok(report)
}

/// Timer scope of a whole build.
pub const BUILD: &str = "lbvh";

/// The LBVH's stage names in build order, for tables (`BvhKind::stages` of either
/// builder).
pub const STAGES: [&str; 4] = BvhKind::Lbvh.stages();
