//! `speculum bench shadows`: the three shadow sources of one scene timed in the same
//! run, a frame of each in turn (map, rays, hybrid, then again) in the settings'
//! reflection mode, so that drift in the machine's speed touches each alike. Reports
//! per-pass medians, each source's frame time against `rays` (the median of the
//! per-round ratios), its `shadow.trace` against the rays' and, against the rays frame,
//! SSIM/RMSE of the images and the agreement of the sun's visibility. Checked in the
//! same run: every source sees the same lit pixels, `rays` traces all of them, `hybrid`
//! fewer and exactly the rays' visibility where it traces, `map` none, and every frame
//! time is finite.

use crate::error::Result;
use crate::report::{PassTimes, Stat};
use crate::scene::Scene;
use crate::settings::{Settings, Shadows};
use crate::shadow_maps::ShadowsVsRays;
use crate::steady::{RoundsCheck, WarmUp, WarmUpReport};
use crate::vk::{Context, TimingCheck};
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct ShadowResult {
    pub shadows: String,
    /// Every timer scope in frame order → GPU milliseconds (`null`: not run).
    pub passes_ms: PassTimes,
    pub frame_ms: Stat,
    /// This source's frame time / the `rays` frame time of the same round, over rounds.
    pub frame_over_rays: Stat,
    /// Median `shadow.trace` / the rays' median (`null` under `map`, which traces none).
    pub trace_over_rays: Option<f64>,
    /// Pixels whose surface faces the sun.
    pub lit_pixels: u64,
    /// Lit pixels a shadow ray answered.
    pub traced_pixels: u64,
    /// traced / lit pixels.
    pub ray_fraction: f64,
    /// Against the rays frame of the same run.
    pub vs_rays: ShadowsVsRays,
    /// The self-check of this source's measured frames (`vk::timing`).
    pub timing: TimingCheck,
}

/// Every shadow source of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneShadows {
    pub scene: String,
    pub resolution: [u32; 2],
    /// The reflection mode every source was rendered in.
    pub mode: String,
    pub shadows: Vec<ShadowResult>,
    /// How the warm-up went and how the rounds held (`steady`): a run whose rounds kept
    /// straying is not valid.
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
    pub valid: bool,
}

/// The `bench shadows` report.
pub type ShadowsReport = super::RoundsReport<SceneShadows>;

/// Times every shadow source of `scene` in `rounds` interleaved rounds after the
/// warm-up, in `base`'s reflection mode.
pub fn run(
    ctx: &Arc<Context>,
    scene: &Scene,
    base: &Settings,
    warmup: WarmUp,
    rounds: u32,
    tick: super::Tick<'_>,
) -> Result<SceneShadows> {
    let variants = Shadows::ALL.iter().map(|&shadows| Settings {
        shadows,
        ..base.clone()
    });
    let (renderers, measured) =
        super::interleave_variants(ctx, scene, variants, (warmup, rounds), tick, "bench shadows")?;
    let (timings, frames) = (&measured.timings, &measured.frames);
    let at = |s: Shadows| {
        Shadows::ALL
            .iter()
            .position(|&x| x == s)
            .expect("every source is measured")
    };
    let rays = at(Shadows::Rays);
    let rays_maps = renderers[rays].shadow_maps()?;
    let rays_image = renderers[rays].read_output()?;
    let trace = |i: usize| {
        PassTimes::of(&timings[i])
            .get(crate::passes::shadow_trace::NAME)
            .map(|s| s.median)
    };
    let mut results = Vec::new();
    let mut exact_where_traced = true;
    for (i, r) in renderers.iter().enumerate() {
        let maps = r.shadow_maps()?;
        let stats = maps.stats();
        exact_where_traced &= (0..maps.lit.len())
            .filter(|&k| maps.lit[k] && maps.mask[k] != 0)
            .all(|k| maps.visibility[k] == rays_maps.visibility[k]);
        let vs_rays = ShadowsVsRays::of(
            (&r.read_output()?, &maps),
            (&rays_image, &rays_maps),
            [base.width, base.height],
        )?;
        let ratios: Vec<f64> = frames[i].iter().zip(&frames[rays]).map(|(a, b)| a / b).collect();
        results.push(ShadowResult {
            shadows: Shadows::ALL[i].name().to_string(),
            passes_ms: PassTimes::of(&timings[i]),
            frame_ms: Stat::of(&frames[i]).expect("rounds > 0"),
            frame_over_rays: Stat::of(&ratios).expect("rounds > 0"),
            trace_over_rays: trace(i).zip(trace(rays)).map(|(a, b)| a / b),
            lit_pixels: stats.lit_pixels,
            traced_pixels: stats.traced_pixels,
            ray_fraction: stats.ray_fraction(),
            vs_rays,
            timing: timings[i].check().clone(),
        });
    }
    let by = |s: Shadows| &results[at(s)];
    let lit = by(Shadows::Rays).lit_pixels;
    let valid = exact_where_traced
        && results
            .iter()
            .all(|s| s.frame_ms.median.is_finite() && s.frame_ms.median > 0.0)
        && results.iter().all(|s| s.lit_pixels == lit)
        && by(Shadows::Rays).traced_pixels == lit
        && by(Shadows::Hybrid).traced_pixels <= lit
        && by(Shadows::Map).traced_pixels == 0
        && measured.rounds_check.settled();
    Ok(SceneShadows {
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        mode: base.mode.name().to_string(),
        shadows: results,
        warmup: measured.warmup,
        rounds_check: measured.rounds_check,
        valid,
    })
}
