//! The vendor tracer in `bench lbvh`: per case, the driver's bottom level built from
//! the triangles in file order and in Morton order (`tracers::khr::StaticOrder`), each
//! build and its compaction timed, and the case's ray sets (their first `khr_rays`)
//! traced through a one-instance top level with the ray-tracing pipeline, the hits
//! checked against the CPU as the LBVH's are.

use super::rays::{time_rays, CpuCheck, RaySetReport, Through};
use crate::error::Result;
use crate::gpu_types::{GpuVertex, Ray};
use crate::passes::rt_trace::TracePass;
use crate::report::Stat;
use crate::tracers::khr::{KhrScene, StaticInput, StaticOrder};
use crate::tracers::lbvh::UploadedTriangles;
use crate::tracers::{Khr, Lbvh, TraceScene};
use crate::vk::accel::{self, BUILD_SCOPE, COMPACT_SCOPE};
use crate::vk::{remeasure_readout, Context, GpuTimer, TimingCheck};
use serde::Serialize;
use std::sync::Arc;

/// One order's figures.
#[derive(Clone, Debug, Serialize)]
pub struct KhrReport {
    /// `file` or `morton`.
    pub order: &'static str,
    /// The bottom level's build (`PREFER_FAST_TRACE | ALLOW_COMPACTION`) and its
    /// compacting copy, GPU milliseconds (lavapipe builds on the CPU in the driver,
    /// inside the timed submission).
    pub build_ms: Stat,
    pub compact_ms: Stat,
    pub bytes_per_triangle: f64,
    pub uncompacted_bytes_per_triangle: f64,
    pub coherent: RaySetReport,
    pub incoherent: RaySetReport,
    pub file: Option<RaySetReport>,
    /// The case's LBVH (or PLOC) tree tracing the same rays (the sets' first
    /// `khr_rays`), Mrays/s: coherent, incoherent, file.
    pub lbvh_same_rays_mrays_per_s: [Option<f64>; 3],
    /// Ray by ray against that tree's hits, every traced ray of each set: (agree: the
    /// same triangle or both miss, ties: different triangles at the same t within 1e-4,
    /// disagree) (`anchor::agreement`).
    pub lbvh_agreement: [Option<(u32, u32, u32)>; 3],
    pub timing: TimingCheck,
}

impl KhrReport {
    /// Whether every checked hit of every set agreed with the CPU, and at least 99.9%
    /// of every set's rays with the LBVH's, ties excepted.
    pub fn sound(&self) -> bool {
        let cpu = [Some(&self.coherent), Some(&self.incoherent), self.file.as_ref()]
            .into_iter()
            .flatten()
            .all(|r| r.mismatches == 0);
        let lbvh = self
            .lbvh_agreement
            .iter()
            .flatten()
            .all(|&(agree, ties, disagree)| disagree as u64 * 1000 <= (agree + ties + disagree) as u64);
        cpu && lbvh
    }
}

/// The vendor tracer's figures for a case (`None` without ray tracing on the device,
/// or with `khr_rays` 0): `sets` are the case's coherent, incoherent and file rays.
pub(super) fn reports(
    ctx: &Arc<Context>,
    (v, i): (&[GpuVertex], &[u32]),
    sets: [Option<&[Ray]>; 3],
    (repeats, khr_rays, cpu): (u32, u32, &CpuCheck<'_>),
    lbvh: (&TracePass<Lbvh>, TraceScene<'_>),
) -> Result<Option<Vec<KhrReport>>> {
    if ctx.ray_tracing.is_none() || khr_rays == 0 {
        return Ok(None);
    }
    let subset = |rays: &'_ [Ray]| -> Vec<Ray> { rays[..rays.len().min(khr_rays as usize)].to_vec() };
    let mut lbvh_timing = TimingCheck::default();
    let mut lbvh_same = [None; 3];
    let mut lbvh_hits: [Vec<crate::gpu_types::Hit>; 3] = Default::default();
    for (k, set) in sets.iter().enumerate() {
        if let Some(rays) = set {
            let (r, hits) = time_rays(
                lbvh.0,
                (lbvh.1, Through::Static),
                &subset(rays),
                repeats,
                cpu,
                &mut lbvh_timing,
            )?;
            lbvh_same[k] = Some(r.mrays_per_s);
            lbvh_hits[k] = hits.into_iter().map(crate::gpu_types::Hit::without_bvh_bit).collect();
        }
    }
    let triangles = UploadedTriangles::new(ctx, "bench.khr", v, i)?;
    let tracer = TracePass::<Khr>::new(ctx)?;
    let n = (i.len() / 3).max(1) as f64;
    let mut out = Vec::new();
    for order in [StaticOrder::File, StaticOrder::Morton] {
        let input = StaticInput::new(triangles.geometry(), v, i, order);
        let ordered_buf =
            crate::tracers::lbvh::index_buffer(ctx, "bench.khr.ordered", Default::default(), &input.ordered)?;
        let t = crate::tracers::khr::triangles(
            triangles.geometry().vertices,
            v.len() as u32,
            &ordered_buf,
            (0, (i.len() / 3) as u32),
        );
        let mut timer = GpuTimer::new(ctx, 2)?;
        let (mut builds, mut compacts, mut timing) = (Vec::new(), Vec::new(), lbvh_timing.clone());
        let (mut bytes, mut full_bytes) = (0u64, 0u64);
        for rep in 0..=repeats {
            let mut made = None;
            let (readouts, discarded) = remeasure_readout(|| {
                let (blas, [b, c], full) = accel::static_blas_timed(ctx, "bench.khr", &t, &mut timer)?;
                made = Some((blas.buffer.size, full));
                Ok(merge(b, c))
            })?;
            (bytes, full_bytes) = made.expect("built");
            if rep > 0 {
                builds.push(readouts.get(BUILD_SCOPE).unwrap_or(f64::NAN));
                compacts.push(readouts.get(COMPACT_SCOPE).unwrap_or(f64::NAN));
                timing.add_measured(readouts.problem.as_deref(), discarded);
            }
        }
        let scene = KhrScene::new_static(ctx, &input)?;
        let tracing = scene.trace(triangles.geometry(), None);
        let mut agreement = [None; 3];
        let mut set = |k: usize, rays: &[Ray]| {
            let (r, hits) = time_rays(
                &tracer,
                (tracing, Through::Static),
                &subset(rays),
                repeats,
                cpu,
                &mut timing,
            )?;
            agreement[k] = Some(super::anchor::agreement(&hits, &lbvh_hits[k]));
            Ok::<_, crate::Error>(r)
        };
        let coherent = set(0, sets[0].expect("a coherent set"))?;
        let incoherent = set(1, sets[1].expect("an incoherent set"))?;
        let file = sets[2].map(|rays| set(2, rays)).transpose()?;
        out.push(KhrReport {
            order: order.name(),
            build_ms: Stat::of(&builds).expect("repeats > 0"),
            compact_ms: Stat::of(&compacts).expect("repeats > 0"),
            bytes_per_triangle: bytes as f64 / n,
            uncompacted_bytes_per_triangle: full_bytes as f64 / n,
            coherent,
            incoherent,
            file,
            lbvh_same_rays_mrays_per_s: lbvh_same,
            lbvh_agreement: agreement,
            timing,
        });
    }
    Ok(Some(out))
}

/// Two readouts as one: the first's scopes and the second's, either's problem.
fn merge(mut a: crate::vk::TimerReadout, b: crate::vk::TimerReadout) -> crate::vk::TimerReadout {
    a.scopes.extend(b.scopes);
    a.problem = a.problem.or(b.problem);
    a
}
