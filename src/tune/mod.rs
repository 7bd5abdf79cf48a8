//! `speculum tune`: a sweep of settings (`sweep`), each point measured against the
//! `rt` reference in the same run, the Pareto front of time against quality, and the
//! fastest settings above a quality floor.
//!
//! The reference is one `rt` renderer with the sweep's base settings (the defaults,
//! the file's `[settings]`, its size): every point is compared with the same image
//! and timed against the same frame, the two rendered in turn every round so that
//! drift in the machine's speed cancels in the per-round ratio (as `bench modes`).
//! The base settings are measured too, as the point `default`.

pub mod plot;
pub mod sweep;

use crate::error::{Error, Result};
use crate::metrics::{compare_rgba8, flip_mean};
use crate::report::Stat;
use crate::scene::Scene;
use crate::settings::{Mode, Settings};
use crate::vk::Context;
use crate::Renderer;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;
use sweep::{Point, Sweep};

/// The key of the base-settings point.
pub const DEFAULT_KEY: &str = "default";

/// What one point measured on one scene.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PointResult {
    pub scene: String,
    /// `name=value;...` of the axes, or `default`.
    pub key: String,
    /// Axis values in axis order (the base settings' values for `default`).
    pub values: Vec<(String, String)>,
    pub frame_ms: Stat,
    pub rt_ms: Stat,
    /// This point's frame / the reference frame of the same round.
    pub frame_over_rt: Stat,
    pub ssim: f64,
    pub rmse: f64,
    /// Mean NVIDIA FLIP error against the reference (0: identical).
    pub flip: f64,
    /// Reflective pixels the ray tracer produced, of all reflective pixels.
    pub rt_pixel_fraction: f64,
    /// Median ms per GPU scope, in frame order.
    pub passes_ms: Vec<(String, f64)>,
    /// On the front of frame/rt against 1 - SSIM (and against FLIP) of its scene.
    pub pareto_ssim: bool,
    pub pareto_flip: bool,
    /// Why this point's (or its reference's) timings failed their self-check
    /// (`vk::timing`); absent when they passed, and for points read back from a CSV.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timing_warning: Option<String>,
}

/// Which of `points` (minimize both coordinates) no other point dominates: one as
/// good in both and better in one. Ties (equal points) are all on the front.
pub fn pareto(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(x, y)| !points.iter().any(|&(a, b)| a <= x && b <= y && (a < x || b < y)))
        .collect()
}

/// Marks the fronts of each scene's results.
pub fn mark_pareto(results: &mut [PointResult]) {
    let scenes: Vec<String> = results.iter().map(|r| r.scene.clone()).collect();
    for scene in scenes.iter().collect::<std::collections::BTreeSet<_>>() {
        let idx: Vec<usize> = (0..results.len()).filter(|&i| &results[i].scene == scene).collect();
        let ssim: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (results[i].frame_over_rt.median, 1.0 - results[i].ssim))
            .collect();
        let flip: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (results[i].frame_over_rt.median, results[i].flip))
            .collect();
        for ((&i, s), f) in idx.iter().zip(pareto(&ssim)).zip(pareto(&flip)) {
            results[i].pareto_ssim = s;
            results[i].pareto_flip = f;
        }
    }
}

/// The fastest point (by frame/rt averaged over the scenes) whose SSIM is at least
/// `min_ssim` on every scene it was measured on; its key.
pub fn best(results: &[PointResult], min_ssim: f64) -> Option<String> {
    let mut by_key: BTreeMap<&str, Vec<&PointResult>> = BTreeMap::new();
    for r in results {
        by_key.entry(&r.key).or_default().push(r);
    }
    let scenes = results
        .iter()
        .map(|r| &r.scene)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    by_key
        .into_iter()
        .filter(|(_, rs)| rs.len() == scenes && rs.iter().all(|r| r.ssim >= min_ssim))
        .map(|(k, rs)| {
            let mean = rs.iter().map(|r| r.frame_over_rt.median).sum::<f64>() / rs.len() as f64;
            (k, mean)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k.to_string())
}

/// The base settings as a point, its axis values read from them.
pub fn default_point(sweep: &Sweep) -> Point {
    let json = serde_json::to_value(&sweep.base).expect("Settings serialize");
    let values = sweep
        .axes
        .iter()
        .map(|(name, _)| {
            let v = &json[name];
            (name.clone(), v.as_str().map_or_else(|| v.to_string(), str::to_string))
        })
        .collect();
    Point {
        values,
        settings: sweep.base.clone(),
    }
}

/// A renderer for `settings`, or `r` changed in place where it can be.
fn renderer_for(ctx: &Arc<Context>, scene: &Scene, r: Option<Renderer>, settings: &Settings) -> Result<Renderer> {
    match r {
        Some(mut r) if !r.needs_new_renderer(settings) => {
            r.set_settings(settings.clone())?;
            Ok(r)
        }
        other => {
            drop(other);
            Renderer::new(ctx, scene, settings)
        }
    }
}

/// Measures `points` (the first may be the default) on `scene`, calling `done` with
/// each result as it is measured.
pub fn measure_scene(
    ctx: &Arc<Context>,
    scene: &Scene,
    name: &str,
    sweep: &Sweep,
    points: &[(String, Point)],
    done: &mut dyn FnMut(PointResult) -> Result<()>,
) -> Result<()> {
    if points.is_empty() {
        return Ok(());
    }
    let reference_settings = Settings {
        mode: Mode::Rt,
        ..sweep.base.clone()
    };
    let mut reference = Renderer::new(ctx, scene, &reference_settings)?;
    let mut renderer: Option<Renderer> = None;
    let dynamic = scene.is_dynamic();
    let mut truth = Truth::new(ctx, scene, sweep)?;
    for (key, point) in points {
        let mut r = renderer_for(ctx, scene, renderer.take(), &point.settings)?;
        let (w, h) = (point.settings.width, point.settings.height);
        let mut timings = crate::vk::Timings::default();
        let mut reference_check = crate::vk::TimingCheck::default();
        let (mut frame, mut rt, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
        let (mut ssim, mut rmse, mut flip, mut traced) = (0.0, 0.0, 0.0, 0.0);
        let mut measured = 0u32;
        let mut measure =
            |r: &mut Renderer, reference: &mut Renderer, compare: bool, truth: Option<&[u8]>| -> Result<()> {
                let (a, a_discarded) = r.render_frame_measured()?;
                let (b, b_discarded) = reference.render_frame_measured()?;
                let ms = |t: &crate::vk::TimerReadout| t.get(crate::renderer::FRAME).unwrap_or(0.0);
                frame.push(ms(&a));
                rt.push(ms(&b));
                ratio.push(ms(&a) / ms(&b).max(1e-9));
                timings.add_measured(&a, a_discarded);
                reference_check.add_measured(b.problem.as_deref(), b_discarded);
                if compare {
                    let img = r.read_output()?;
                    let reference_img = truth.map_or_else(|| reference.read_output(), |t| Ok(t.to_vec()))?;
                    let c = compare_rgba8(&img, &reference_img, w, h)?;
                    ssim += c.ssim;
                    rmse += c.rmse;
                    flip += flip_mean(&img, &reference_img, w, h)?;
                    traced += r.reflection_stats()?.rt_pixel_fraction();
                    measured += 1;
                }
                Ok(())
            };
        // Every point starts afresh: a dynamic scene's animation, and the glossy
        // sequence and history (a renderer reused from the last point carries them).
        r.reset_simulation()?;
        reference.reset_simulation()?;
        truth.reset()?;
        if dynamic {
            for _ in 0..sweep.frames[0] {
                r.render_frame()?;
                reference.render_frame()?;
                truth.advance()?;
            }
            for _ in sweep.frames[0]..sweep.frames[1] {
                let t = truth.advance()?;
                measure(&mut r, &mut reference, true, t.as_deref())?;
            }
        } else {
            for _ in 0..sweep.warmup {
                r.render_frame()?;
                reference.render_frame()?;
            }
            for round in 0..sweep.rounds {
                let last = round + 1 == sweep.rounds;
                measure(&mut r, &mut reference, last, truth.still.as_deref())?;
            }
        }
        let mut check = timings.check().clone();
        check.merge(&reference_check);
        let n = measured.max(1) as f64;
        let stat = |v: &[f64]| Stat::of(v).ok_or_else(|| Error::Input("no frames measured".into()));
        let passes_ms = median_passes(&timings);
        done(PointResult {
            scene: name.to_string(),
            key: key.clone(),
            values: point.values.clone(),
            frame_ms: stat(&frame)?,
            rt_ms: stat(&rt)?,
            frame_over_rt: stat(&ratio)?,
            ssim: ssim / n,
            rmse: rmse / n,
            flip: flip / n,
            rt_pixel_fraction: traced / n,
            passes_ms,
            pareto_ssim: false,
            pareto_flip: false,
            timing_warning: check.warning(),
        })?;
        renderer = Some(r);
    }
    Ok(())
}

/// Median ms per GPU scope, in frame order.
fn median_passes(timings: &crate::vk::Timings) -> Vec<(String, f64)> {
    crate::renderer::SCOPES
        .iter()
        .filter_map(|s| {
            timings
                .samples(s)
                .and_then(Stat::of)
                .map(|st| (s.to_string(), st.median))
        })
        .collect()
}

/// With glossy reflections a sweep's quality is judged against the glossy ground truth
/// (`rt` with many rays per glossy pixel, no denoiser; its own sample stream): rendered
/// once for a static scene (`still`), stepped in lockstep with a dynamic one. The frame
/// time is still against `rt`'s.
struct Truth {
    renderer: Option<Renderer>,
    still: Option<Vec<u8>>,
}

impl Truth {
    fn new(ctx: &Arc<Context>, scene: &Scene, sweep: &Sweep) -> Result<Self> {
        let mut t = Truth {
            renderer: None,
            still: None,
        };
        if sweep.base.glossy {
            let spp = crate::settings::GLOSSY_REFERENCE_SPP;
            t.renderer = Some(Renderer::reference(ctx, scene, &sweep.base, spp)?);
            if !scene.is_dynamic() {
                t.still = t.advance()?;
            }
        }
        Ok(t)
    }

    fn reset(&mut self) -> Result<()> {
        self.renderer.as_mut().map_or(Ok(()), |r| r.reset_simulation())
    }

    /// The next frame's ground truth, if there is one.
    fn advance(&mut self) -> Result<Option<Vec<u8>>> {
        match &mut self.renderer {
            Some(r) => {
                r.render_frame()?;
                Ok(Some(r.read_output()?))
            }
            None => Ok(None),
        }
    }
}

/// The speedup of `candidate` over the base settings on `scene`, measured again in
/// `rounds` rounds that alternate the two (after one warm-up round): per round, the
/// base settings' frame time over the candidate's. A sweep's best point is the
/// smallest of many noisy medians, so its own figure is biased low; this one is not.
/// `None` when no round's timings passed their self-check (a busy machine): nothing
/// confirmed, the sweep's figures stand as measured.
pub fn confirm(
    ctx: &Arc<Context>,
    scene: &Scene,
    sweep: &Sweep,
    candidate: &Settings,
    rounds: u32,
) -> Result<Option<Stat>> {
    let mut a = Renderer::new(ctx, scene, candidate)?;
    let mut b = Renderer::new(ctx, scene, &sweep.base)?;
    let ms = |t: &crate::vk::TimerReadout| t.get(crate::renderer::FRAME).unwrap_or(0.0);
    let mut ratios = Vec::new();
    for round in 0..=rounds {
        if scene.is_dynamic() {
            a.reset_simulation()?;
            b.reset_simulation()?;
        }
        let (ra, rb) = (a.render_frame()?, b.render_frame()?);
        let trusted = ra.problem.is_none() && rb.problem.is_none();
        let (ta, tb) = (ms(&ra), ms(&rb));
        // A round whose timings fail their self-check is left out (an error when all are).
        if round > 0 && trusted {
            ratios.push(tb / ta.max(1e-9));
        }
    }
    Ok(Stat::of(&ratios))
}

/// The fixed columns of `points.csv`, before the axes and the passes.
const HEAD: [&str; 2] = ["scene", "key"];
const STATS: [&str; 13] = [
    "frame_ms",
    "frame_p10",
    "frame_p90",
    "rt_ms",
    "frame_over_rt",
    "frame_over_rt_p10",
    "frame_over_rt_p90",
    "ssim",
    "rmse",
    "flip",
    "rt_pixel_fraction",
    "pareto_ssim",
    "pareto_flip",
];

/// `points.csv`: a row per result; the axes by name, then the statistics, then
/// `ms_<scope>` per GPU scope.
pub fn to_csv(axes: &[String], results: &[PointResult]) -> String {
    let mut out = String::new();
    let mut head: Vec<String> = HEAD.iter().map(|s| s.to_string()).collect();
    head.extend(axes.iter().cloned());
    head.extend(STATS.iter().map(|s| s.to_string()));
    head.extend(crate::renderer::SCOPES.iter().map(|s| format!("ms_{s}")));
    out += &head.join(",");
    out.push('\n');
    for r in results {
        let mut row = vec![r.scene.clone(), r.key.clone()];
        for a in axes {
            row.push(
                r.values
                    .iter()
                    .find(|(n, _)| n == a)
                    .map_or(String::new(), |(_, v)| v.clone()),
            );
        }
        let f = |v: f64| format!("{v:.6}");
        row.extend([
            f(r.frame_ms.median),
            f(r.frame_ms.p10),
            f(r.frame_ms.p90),
            f(r.rt_ms.median),
            f(r.frame_over_rt.median),
            f(r.frame_over_rt.p10),
            f(r.frame_over_rt.p90),
            f(r.ssim),
            f(r.rmse),
            f(r.flip),
            f(r.rt_pixel_fraction),
            r.pareto_ssim.to_string(),
            r.pareto_flip.to_string(),
        ]);
        for s in crate::renderer::SCOPES {
            row.push(
                r.passes_ms
                    .iter()
                    .find(|(n, _)| n == s)
                    .map_or(String::new(), |(_, v)| f(*v)),
            );
        }
        out += &row.join(",");
        out.push('\n');
    }
    out
}

/// Reads `points.csv` back (for `--resume` and `plot`): its axes and results. The
/// spreads of frame_ms are read; sample counts are not kept in the CSV (0).
pub fn from_csv(text: &str) -> Result<(Vec<String>, Vec<PointResult>)> {
    let bad = |line: usize, why: String| Error::Input(format!("points CSV line {line}: {why}"));
    let mut lines = text.lines();
    let head: Vec<&str> = lines
        .next()
        .ok_or_else(|| bad(1, "empty file".into()))?
        .split(',')
        .collect();
    if head.len() < HEAD.len() + STATS.len() || head[..2] != HEAD {
        return Err(bad(1, "not a points.csv header (scene,key,...)".into()));
    }
    let first_stat = head
        .iter()
        .position(|h| *h == STATS[0])
        .ok_or_else(|| bad(1, "no frame_ms column".into()))?;
    if head.len() < first_stat + STATS.len() || head[first_stat..first_stat + STATS.len()] != STATS {
        return Err(bad(1, format!("the statistics columns must be {}", STATS.join(","))));
    }
    let axes: Vec<String> = head[2..first_stat].iter().map(|s| s.to_string()).collect();
    let passes: Vec<&str> = head[first_stat + STATS.len()..].to_vec();
    let mut results = Vec::new();
    for (i, line) in lines.enumerate() {
        let n = i + 2;
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != head.len() {
            return Err(bad(n, format!("{} cells, the header has {}", cells.len(), head.len())));
        }
        let num = |j: usize| -> Result<f64> {
            cells[j]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(n, format!("{} '{}' is not a number", head[j], cells[j])))
        };
        let flag = |j: usize| -> Result<bool> {
            cells[j]
                .parse::<bool>()
                .map_err(|_| bad(n, format!("{} must be true or false", head[j])))
        };
        let s = first_stat;
        let stat = |m: f64, lo: f64, hi: f64| Stat {
            median: m,
            p10: lo,
            p90: hi,
            samples: 0,
        };
        results.push(PointResult {
            scene: cells[0].to_string(),
            key: cells[1].to_string(),
            values: axes
                .iter()
                .zip(&cells[2..s])
                .map(|(a, v)| (a.clone(), v.to_string()))
                .collect(),
            frame_ms: stat(num(s)?, num(s + 1)?, num(s + 2)?),
            rt_ms: stat(num(s + 3)?, num(s + 3)?, num(s + 3)?),
            frame_over_rt: stat(num(s + 4)?, num(s + 5)?, num(s + 6)?),
            ssim: num(s + 7)?,
            rmse: num(s + 8)?,
            flip: num(s + 9)?,
            rt_pixel_fraction: num(s + 10)?,
            pareto_ssim: flag(s + 11)?,
            pareto_flip: flag(s + 12)?,
            timing_warning: None,
            passes_ms: passes
                .iter()
                .zip(&cells[s + STATS.len()..])
                .filter(|(_, v)| !v.is_empty())
                .map(|(p, v)| {
                    Ok((
                        p.trim_start_matches("ms_").to_string(),
                        v.parse::<f64>().map_err(|_| bad(n, format!("{p} '{v}'")))?,
                    ))
                })
                .collect::<Result<_>>()?,
        });
    }
    Ok((axes, results))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(scene: &str, key: &str, ratio: f64, ssim: f64, flip: f64) -> PointResult {
        let st = |m| Stat {
            median: m,
            p10: m * 0.9,
            p90: m * 1.1,
            samples: 0,
        };
        PointResult {
            scene: scene.into(),
            key: key.into(),
            values: vec![("max_bounces".into(), key.len().to_string())],
            frame_ms: st(ratio * 10.0),
            rt_ms: st(10.0),
            frame_over_rt: st(ratio),
            ssim,
            rmse: 0.01,
            flip,
            rt_pixel_fraction: 0.5,
            passes_ms: vec![("gbuffer".into(), 1.5)],
            pareto_ssim: false,
            pareto_flip: false,
            timing_warning: None,
        }
    }

    #[test]
    fn pareto_against_brute_force() {
        let mut rng = 12345u64;
        let mut next = || {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((rng >> 33) % 20) as f64
        };
        for _ in 0..50 {
            let pts: Vec<(f64, f64)> = (0..30).map(|_| (next(), next())).collect();
            let front = pareto(&pts);
            for (i, &(x, y)) in pts.iter().enumerate() {
                let dominated = pts
                    .iter()
                    .enumerate()
                    .any(|(j, &(a, b))| j != i && a <= x && b <= y && (a, b) != (x, y));
                assert_eq!(front[i], !dominated, "{pts:?} point {i}");
            }
            assert!(front.iter().any(|f| *f));
        }
    }

    #[test]
    fn csv_round_trip_and_best() {
        let mut rs = vec![
            result("room", "a", 0.8, 0.995, 0.02),
            result("room", "bb", 0.6, 0.985, 0.05),
            result("room", "default", 0.9, 0.996, 0.01),
            result("room", "ccc", 0.95, 0.990, 0.03),
        ];
        mark_pareto(&mut rs);
        assert_eq!(
            rs.iter().map(|r| r.pareto_ssim).collect::<Vec<_>>(),
            [true, true, true, false]
        );
        let axes = vec!["max_bounces".to_string()];
        let csv = to_csv(&axes, &rs);
        let (axes2, back) = from_csv(&csv).unwrap();
        assert_eq!(axes2, axes);
        assert_eq!(back.len(), 4);
        for (a, b) in rs.iter().zip(&back) {
            assert_eq!(
                (&a.key, a.pareto_ssim, a.pareto_flip),
                (&b.key, b.pareto_ssim, b.pareto_flip)
            );
            assert!((a.frame_over_rt.median - b.frame_over_rt.median).abs() < 1e-6);
            assert_eq!(a.passes_ms, b.passes_ms);
        }
        assert_eq!(best(&rs, 0.99).as_deref(), Some("a"));
        assert_eq!(best(&rs, 0.98).as_deref(), Some("bb"));
        assert_eq!(best(&rs, 0.999), None);
    }

    #[test]
    fn bad_csv_is_named() {
        for (text, says) in [("", "empty"), ("a,b,c\n", "header"), ("scene,key,frame_ms\n", "header")] {
            let e = from_csv(text).unwrap_err().to_string();
            assert!(e.contains(says), "{text:?}: {e}");
        }
        let rs = vec![result("room", "a", 0.8, 0.995, 0.02)];
        let csv = to_csv(&["max_bounces".into()], &rs).replace("0.800000", "fast");
        assert!(from_csv(&csv).unwrap_err().to_string().contains("line 2"));
    }
}
