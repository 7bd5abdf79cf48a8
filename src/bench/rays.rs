//! A ray set measured through either tracer and checked against the CPU: what `bench
//! lbvh` (the LBVH, PLOC) and its vendor-tracer figures (`khr.rs`) report of each of
//! their ray sets. Apart from both so that neither imports the other.

use crate::cpu_ref::lbvh::triangle;
use crate::cpu_ref::trace::{intersect, CpuBvh};
use crate::error::Result;
use crate::gpu_types::{GpuVertex, Hit, Ray};
use crate::passes::rt_trace::TracePass;
use crate::report::Stat;
use crate::shader_defines::{BVH_INVALID, HIT_DYNAMIC};
use crate::tracers::Tracer;
use crate::vk::{remeasure, TimingCheck};
use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct RaySetReport {
    pub rays: u32,
    /// GPU milliseconds of `rt.trace` over the repeats.
    pub trace_ms: Stat,
    /// Repeats beyond 2x the median traced again (`steady`); unsettled: not valid.
    pub rounds_check: crate::steady::RoundsCheck,
    pub mrays_per_s: f64,
    /// Fraction of rays that hit a triangle.
    pub hit_fraction: f64,
    pub checked: u32,
    /// Checked rays whose GPU hit differs from the CPU's (must be 0).
    pub mismatches: u32,
    /// Checked rays where two triangles tie at the same t and the sides picked
    /// different ones (both genuine hits at equal t).
    pub ties: u32,
    /// Rays (of all, not only the checked) whose walk failed: its stack overflowed or
    /// it overran its step bound (t = -1; must be 0).
    pub failed_walks: u32,
}

/// Which BVH a set's hits come through: their triangle ids carry the dynamic BVH's bit
/// (`HIT_DYNAMIC`) exactly when it is `Dynamic`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Through {
    Static,
    Dynamic,
}

/// Checks `sample` evenly spaced rays against the CPU BVH: (mismatches, ties). A hit
/// whose id lacks the bit `through` gives it, or has it where it should not, is a
/// mismatch.
pub(crate) fn check_hits(
    rays: &[Ray],
    gpu: &[Hit],
    cpu: &CpuBvh,
    v: &[GpuVertex],
    i: &[u32],
    (sample, through): (u32, Through),
) -> (u32, u32) {
    let step = (rays.len() / sample.max(1) as usize).max(1);
    let (mut mismatches, mut ties) = (0, 0);
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0);
    for k in (0..rays.len()).step_by(step).take(sample as usize) {
        let hit = gpu[k].prim != BVH_INVALID;
        if hit && (gpu[k].prim & HIT_DYNAMIC != 0) != (through == Through::Dynamic) {
            mismatches += 1;
            continue;
        }
        let (g, c) = (gpu[k].without_bvh_bit(), cpu.trace(&rays[k], v, i));
        if g.prim == c.prim && (g.prim == BVH_INVALID || close(g.t, c.t)) {
            continue;
        }
        let genuine_tie = g.prim != BVH_INVALID
            && c.prim != BVH_INVALID
            && close(g.t, c.t)
            && intersect(&rays[k], &triangle(v, i, g.prim as usize)).is_some_and(|h| close(h.0, c.t));
        if genuine_tie {
            ties += 1;
        } else {
            mismatches += 1;
        }
    }
    (mismatches, ties)
}

/// The CPU's answer to a case's rays: its binned-SAH BVH over the same triangles.
pub struct CpuCheck<'a> {
    pub bvh: CpuBvh,
    pub vertices: &'a [GpuVertex],
    pub indices: &'a [u32],
    /// Rays of each set checked.
    pub rays: u32,
}

impl<'a> CpuCheck<'a> {
    /// The CPU's BVH over the triangles, checking `rays` of each set; and its build's
    /// wall-clock milliseconds.
    pub fn new(vertices: &'a [GpuVertex], indices: &'a [u32], rays: u32) -> (Self, f64) {
        let t0 = std::time::Instant::now();
        let bvh = CpuBvh::build(vertices, indices);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let check = Self {
            bvh,
            vertices,
            indices,
            rays,
        };
        (check, ms)
    }
}

/// Traces `rays` through `scene` once untimed and `repeats` times timed (each readout
/// re-measured while it fails its self-check, a repeat beyond 2x the median traced
/// again: `super::measure_rounds`), and checks a sample of the hits against the CPU
/// (`through` the BVH `scene` holds: its hits' ids carry its bit, which the hits
/// returned keep).
pub fn time_rays<T: Tracer>(
    tracer: &TracePass<T>,
    (scene, through): (T::Scene<'_>, Through),
    rays: &[Ray],
    repeats: u32,
    cpu: &CpuCheck<'_>,
    timing: &mut TimingCheck,
) -> Result<(RaySetReport, Vec<Hit>)> {
    let name = crate::passes::rt_trace::NAME;
    let (mut hits, _, _) = remeasure(|| tracer.trace(rays, scene, false))?;
    let (measured, rounds_check) = super::measure_rounds(repeats, name, || {
        let (h, readout, discarded) = remeasure(|| tracer.trace(rays, scene, false))?;
        hits = h;
        Ok(vec![(readout, discarded)])
    })?;
    let mut times = Vec::new();
    for (readout, discarded) in measured.iter().map(|m| &m[0]) {
        times.push(readout.get(name).unwrap_or(f64::NAN));
        timing.add_measured(readout.problem.as_deref(), *discarded);
    }
    let trace_ms = Stat::of(&times).expect("repeats > 0");
    let (mismatches, ties) = check_hits(rays, &hits, &cpu.bvh, cpu.vertices, cpu.indices, (cpu.rays, through));
    let report = RaySetReport {
        rays: rays.len() as u32,
        trace_ms,
        rounds_check,
        mrays_per_s: rays.len() as f64 / (trace_ms.median * 1e3),
        hit_fraction: hits.iter().filter(|h| h.prim != BVH_INVALID).count() as f64 / rays.len() as f64,
        checked: cpu.rays.min(rays.len() as u32),
        mismatches,
        ties,
        failed_walks: hits.iter().filter(|h| h.t < 0.0).count() as u32,
    };
    Ok((report, hits))
}

/// Both ray sets through `tracer` and `scene` (`time_rays`, the hits' ids carrying
/// `through`'s bit).
pub fn both_sets<T: Tracer>(
    (tracer, scene, through): (&TracePass<T>, T::Scene<'_>, Through),
    sets: [&[Ray]; 2],
    repeats: u32,
    cpu: &CpuCheck<'_>,
    timing: &mut TimingCheck,
) -> Result<[RaySetReport; 2]> {
    let mut walk = |rays: &[Ray]| time_rays(tracer, (scene, through), rays, repeats, cpu, timing).map(|r| r.0);
    Ok([walk(sets[0])?, walk(sets[1])?])
}

/// Both ray sets through the walk with its lanes refilled in one shape.
#[derive(Clone, Debug, Serialize)]
pub struct RefilledReport {
    pub shape: crate::passes::rt_trace::Refill,
    /// The coherent and the incoherent set.
    pub sets: [RaySetReport; 2],
}
