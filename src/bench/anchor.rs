//! What a CPU anchor of `bench lbvh` reports (Embree 3, `bench/embree.rs`, cargo
//! feature `embree`): its builds and ray sets against Speculum's, and how the two
//! tracers' hits of the same rays agree. Apart from both so that the report (in
//! `lbvh.rs`) and the anchor that fills it import this, not each other.

use crate::gpu_types::{Hit, Ray};
use crate::report::Stat;
use crate::shader_defines::BVH_INVALID;
use serde::Serialize;

/// One ray set for the anchor: the rays, Speculum's hits, Speculum's Mrays/s, and
/// whether the rays are coherent (Embree's context hint).
pub type AnchorSet<'a> = (&'a [Ray], &'a [Hit], f64, bool);

/// One Embree build quality on a case (cargo feature `embree`): its build, and the
/// same ray sets traced with `rtcIntersect1` on the same CPU threads.
#[derive(Clone, Debug, Serialize)]
pub struct AnchorReport {
    /// `low` (Embree's Morton builder) or `medium` (its binned SAH).
    pub quality: &'static str,
    pub threads: u32,
    /// Wall-clock milliseconds of `rtcCommitScene`.
    pub build_ms: Stat,
    /// Speculum's build time over Embree's (> 1: Embree builds faster).
    pub build_ratio: f64,
    /// The same with `lbvh.compact` added (the static walk's nodes, part of a static
    /// tree's build).
    pub static_build_ratio: f64,
    pub coherent: AnchorRays,
    pub incoherent: AnchorRays,
    pub file: Option<AnchorRays>,
}

/// Embree on one ray set, against Speculum's hits of the same rays.
#[derive(Clone, Debug, Serialize)]
pub struct AnchorRays {
    /// Wall-clock milliseconds of tracing the set.
    pub trace_ms: Stat,
    pub mrays_per_s: f64,
    /// Speculum's rays/s over Embree's (< 1: Embree is faster).
    pub speed_ratio: f64,
    /// Rays whose hits agree: the same triangle, or both miss.
    pub agree: u32,
    /// Rays where both hit different triangles at the same distance (within 1e-4,
    /// relative): an edge or a coplanar pair, each tracer picking one.
    pub ties: u32,
    /// The rest: one tracer hit and the other missed (a ray through an edge that one
    /// of the two non-watertight tests lets through), or different distances.
    pub disagree: u32,
}

/// (agree, ties, disagree) of two tracers' hits of the same rays (see `AnchorRays`).
pub fn agreement(a: &[Hit], b: &[Hit]) -> (u32, u32, u32) {
    let (mut agree, mut ties, mut disagree) = (0, 0, 0);
    for (x, y) in a.iter().zip(b) {
        if x.prim == y.prim {
            agree += 1;
        } else if x.prim != BVH_INVALID
            && y.prim != BVH_INVALID
            && (x.t - y.t).abs() <= 1e-4 * x.t.abs().max(y.t.abs()).max(1.0)
        {
            ties += 1;
        } else {
            disagree += 1;
        }
    }
    (agree, ties, disagree)
}

/// Embree's runs of one case, made once and reported against each builder and layout
/// of the case (the same triangles and rays): per build quality, its build times and,
/// per ray set (coherent, incoherent, the file's), its hits and trace times.
#[derive(Clone, Debug)]
pub struct AnchorRuns {
    /// The case's name and its sets' ray counts, which a later report must match.
    pub case: (String, [Option<usize>; 3]),
    pub qualities: Vec<QualityRuns>,
}

/// One Embree build quality's runs on a case.
#[derive(Clone, Debug)]
pub struct QualityRuns {
    pub quality: &'static str,
    pub threads: u32,
    pub build_ms: Stat,
    pub sets: [Option<(Vec<Hit>, Stat)>; 3],
}

impl AnchorRuns {
    /// The reports against one builder's and layout's `sets` (Speculum's hits and
    /// Mrays/s of the same rays) and its (build, compaction) milliseconds.
    pub fn report(&self, sets: &[Option<AnchorSet<'_>>; 3], (build_ms, compact_ms): (f64, f64)) -> Vec<AnchorReport> {
        self.qualities
            .iter()
            .map(|q| {
                let traced: Vec<Option<AnchorRays>> = q
                    .sets
                    .iter()
                    .zip(sets)
                    .map(|(runs, set)| {
                        let ((hits, trace_ms), (rays, theirs, speculum_mrays, _)) = (runs.as_ref()?, set.as_ref()?);
                        let mrays_per_s = rays.len() as f64 / (trace_ms.median * 1e3);
                        let (agree, ties, disagree) = agreement(hits, theirs);
                        Some(AnchorRays {
                            trace_ms: *trace_ms,
                            mrays_per_s,
                            speed_ratio: speculum_mrays / mrays_per_s,
                            agree,
                            ties,
                            disagree,
                        })
                    })
                    .collect();
                let [coherent, incoherent, file]: [Option<AnchorRays>; 3] = traced.try_into().expect("three sets");
                AnchorReport {
                    quality: q.quality,
                    threads: q.threads,
                    build_ms: q.build_ms,
                    build_ratio: build_ms / q.build_ms.median,
                    static_build_ratio: (build_ms + compact_ms) / q.build_ms.median,
                    coherent: coherent.expect("a coherent set"),
                    incoherent: incoherent.expect("an incoherent set"),
                    file,
                }
            })
            .collect()
    }

    /// Whether these runs are of `case` with these sets' ray counts.
    pub fn of(&self, case: &str, sets: &[Option<AnchorSet<'_>>; 3]) -> bool {
        self.case.0 == case && self.case.1 == sets.each_ref().map(|s| s.as_ref().map(|s| s.0.len()))
    }
}
