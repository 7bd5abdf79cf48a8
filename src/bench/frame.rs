//! `speculum bench frame`: every way the frame can find what each pixel sees
//! (`visibility`: raster, rays, adaptive) with every shadow source (`shadows`: map,
//! rays, hybrid, adaptive), one scene's renderers timed in the same run, a frame of
//! each in turn, so that drift in the machine's speed touches each alike. Reports
//! per-pass medians, each variant's frame time against the raster frame with the same
//! shadows (the median of the per-round ratios), SSIM/RMSE against that frame, and for
//! the adaptive variants what they chose and their frame time over the cheapest fixed
//! variant they choose among (the floor of issue "the frame that measures itself":
//! at most 1.02).
//!
//! Before the warm-up, every renderer renders rounds until every adaptive stage is
//! priced (at most `stages::PRICE_ROUNDS`; a dynamic scene's renderers stay in step),
//! and a steady warm-up prices them again at the settled clocks: the measured rounds
//! time the frames the adaptive ones take once they have chosen, their recheck frames
//! included where a round falls on one.
//! Checked in the same run: every frame time is finite, every adaptive stage priced,
//! and the rounds settled.

use crate::error::Result;
use crate::headless::StageReport;
use crate::metrics::compare_rgba8;
use crate::renderer::stages::{shadow_scopes, visibility_scopes, Stages, HOLD, RECHECK_EVERY};
use crate::report::{PassTimes, Stat};
use crate::scene::Scene;
use crate::settings::{Settings, Shadows, Visibility};
use crate::steady::{RoundsCheck, WarmUp, WarmUpReport};
use crate::vk::{Context, TimingCheck};
use serde::Serialize;
use std::sync::Arc;

/// The variants, in the order they are rendered: every visibility with every shadow
/// source.
pub fn variants() -> Vec<(Visibility, Shadows)> {
    Visibility::ALL
        .iter()
        .flat_map(|&v| Shadows::ALL.map(|s| (v, s)))
        .collect()
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameVariant {
    pub visibility: String,
    pub shadows: String,
    /// Every timer scope in frame order → GPU milliseconds (`null`: not run).
    pub passes_ms: PassTimes,
    pub frame_ms: Stat,
    /// This variant's frame time / the frame time of the raster variant with the same
    /// shadows in the same round, over rounds.
    pub frame_over_raster: Stat,
    /// Against the last frame of the raster variant with the same shadows.
    pub ssim_vs_raster: f64,
    pub rmse_vs_raster: f64,
    /// An adaptive variant's frame time over the cheapest fixed variant among those it
    /// chooses from (the largest of the medians of its per-round ratios to each), and
    /// that variant (`visibility/shadows`); `null` for a fixed variant.
    pub over_cheapest_fixed: Option<f64>,
    pub cheapest_fixed: Option<String>,
    /// The adaptive stages after the run (`null` where fixed).
    pub visibility_ways: Option<StageReport>,
    pub shadow_ways: Option<StageReport>,
    /// An adaptive variant: whether each adaptive stage chose the way whose rows the
    /// fixed variants measured cheapest in this run (or one within `stages::HOLD` of
    /// it), and what its recheck frames cost a frame on average (each stage's price
    /// difference over `RECHECK_EVERY`, by its own prices, ms): once priced, an
    /// adaptive frame records its choice's rows and nothing else, so its frame is the
    /// chosen fixed variant's plus this. `null` for a fixed variant.
    pub chose_cheapest: Option<bool>,
    pub recheck_ms: Option<f64>,
    /// The self-check of this variant's measured frames (`vk::timing`).
    pub timing: TimingCheck,
}

/// Every variant of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneFrame {
    pub scene: String,
    pub resolution: [u32; 2],
    /// The reflection mode every variant was rendered in.
    pub mode: String,
    pub variants: Vec<FrameVariant>,
    /// The largest `over_cheapest_fixed` of the adaptive variants (their frame times
    /// against fixed ones of the same rounds: the noise of one frame against another
    /// is in it), whether every adaptive stage chose the cheapest way, and the largest
    /// `recheck_ms` over the frame time of its variant.
    pub adaptive_over_cheapest: f64,
    pub adaptive_chose_cheapest: bool,
    pub adaptive_recheck_share: f64,
    /// How the warm-up went and how the rounds held (`steady`): a run whose rounds kept
    /// straying is not valid.
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
    pub valid: bool,
}

/// The `bench frame` report.
pub type FrameReport = super::RoundsReport<SceneFrame>;

/// The fixed ways an adaptive setting chooses among (a fixed one: itself).
fn fixed_visibility(v: Visibility) -> Vec<Visibility> {
    match v {
        Visibility::Adaptive => Visibility::FIXED.to_vec(),
        fixed => vec![fixed],
    }
}

fn fixed_shadows(s: Shadows) -> Vec<Shadows> {
    match s {
        Shadows::Adaptive => Shadows::ADAPTIVE.to_vec(),
        fixed => vec![fixed],
    }
}

/// Times every variant of `scene` in `rounds` interleaved rounds after the warm-up, in
/// `base`'s mode and other settings.
pub fn run(
    ctx: &Arc<Context>,
    scene: &Scene,
    base: &Settings,
    warmup: WarmUp,
    rounds: u32,
    tick: super::Tick<'_>,
) -> Result<SceneFrame> {
    if rounds == 0 {
        return Err(crate::Error::Settings("bench frame needs at least one round".into()));
    }
    let ways = variants();
    let settings = |&(visibility, shadows): &(Visibility, Shadows)| Settings {
        visibility,
        shadows,
        ..base.clone()
    };
    let mut renderers = ways
        .iter()
        .map(|w| crate::Renderer::new(ctx, scene, &settings(w)))
        .collect::<Result<Vec<_>>>()?;
    crate::headless::price_stages(&mut renderers.iter_mut().collect::<Vec<_>>(), &mut || {})?;
    let measured = super::interleave(&mut renderers, warmup, rounds, tick)?;
    let (timings, frames) = (&measured.timings, &measured.frames);
    let at = |w: (Visibility, Shadows)| ways.iter().position(|&x| x == w).expect("every variant is measured");
    let images = renderers
        .iter()
        .map(crate::Renderer::read_output)
        .collect::<Result<Vec<_>>>()?;
    let ratio = |i: usize, j: usize| {
        let r: Vec<f64> = frames[i].iter().zip(&frames[j]).map(|(a, b)| a / b).collect();
        Stat::of(&r).expect("rounds > 0")
    };
    let mut variants = Vec::new();
    for (i, &(v, s)) in ways.iter().enumerate() {
        let raster = at((Visibility::Raster, s));
        let quality = compare_rgba8(&images[i], &images[raster], base.width, base.height)?;
        let adaptive = v == Visibility::Adaptive || s == Shadows::Adaptive;
        let cheapest = adaptive.then(|| {
            fixed_visibility(v)
                .into_iter()
                .flat_map(|fv| fixed_shadows(s).into_iter().map(move |fs| (fv, fs)))
                .map(|w| (ratio(i, at(w)).median, w))
                // The cheapest fixed variant is the one this variant's time is the
                // largest ratio of.
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .expect("a fixed variant")
        });
        let (stages, index) = (renderers[i].stages(), renderers[i].frame_index());
        let rows_ms = |w: (Visibility, Shadows), scopes: &[&str]| -> f64 {
            let passes = PassTimes::of(&timings[at(w)]);
            scopes.iter().filter_map(|&n| passes.get(n)).map(|s| s.median).sum()
        };
        let judged = adaptive.then(|| judge(&stages, (v, s), rows_ms));
        variants.push(FrameVariant {
            visibility: v.name().to_string(),
            shadows: s.name().to_string(),
            passes_ms: PassTimes::of(&timings[i]),
            frame_ms: Stat::of(&frames[i]).expect("rounds > 0"),
            frame_over_raster: ratio(i, raster),
            ssim_vs_raster: quality.ssim,
            rmse_vs_raster: quality.rmse,
            over_cheapest_fixed: cheapest.map(|c| c.0),
            cheapest_fixed: cheapest.map(|(_, (fv, fs))| format!("{}/{}", fv.name(), fs.name())),
            visibility_ways: (v == Visibility::Adaptive)
                .then(|| StageReport::of(&stages.visibility, Visibility::FIXED.map(Visibility::name), index)),
            shadow_ways: (s == Shadows::Adaptive)
                .then(|| StageReport::of(&stages.shadows, Shadows::ADAPTIVE.map(Shadows::name), index)),
            chose_cheapest: judged.map(|j| j.0),
            recheck_ms: judged.map(|j| j.1),
            timing: timings[i].check().clone(),
        });
    }
    let (adaptive_over_cheapest, adaptive_chose_cheapest, adaptive_recheck_share) = adaptive_summary(&variants);
    let priced = renderers.iter().all(crate::Renderer::stages_priced);
    let valid = priced
        && variants
            .iter()
            .all(|v| v.frame_ms.median.is_finite() && v.frame_ms.median > 0.0)
        && measured.rounds_check.settled();
    Ok(SceneFrame {
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        mode: base.mode.name().to_string(),
        variants,
        adaptive_over_cheapest,
        adaptive_chose_cheapest,
        adaptive_recheck_share,
        warmup: measured.warmup,
        rounds_check: measured.rounds_check,
        valid,
    })
}

/// An adaptive variant `(v, s)`'s stages judged by the run's fixed variants
/// (`rows_ms`: a variant's median time of some scopes): whether each stage chose the
/// way whose rows they measured cheapest (or one within `HOLD`), and its recheck
/// frames' cost a frame (ms, by the stage's own prices). A stage is judged with the
/// other stage at its setting, or at the way that one chose.
fn judge(
    stages: &Stages,
    (v, s): (Visibility, Shadows),
    rows_ms: impl Fn((Visibility, Shadows), &[&str]) -> f64,
) -> (bool, f64) {
    let vis_now = match v {
        Visibility::Adaptive => Visibility::FIXED[stages.visibility.chosen],
        fixed => fixed,
    };
    let sh_now = match s {
        Shadows::Adaptive => Shadows::ADAPTIVE[stages.shadows.chosen],
        fixed => fixed,
    };
    let mut judged = Vec::new();
    if v == Visibility::Adaptive {
        let measured: Vec<f64> = (0..2)
            .map(|w| rows_ms((Visibility::FIXED[w], sh_now), &visibility_scopes(w)))
            .collect();
        judged.push((stages.visibility, measured));
    }
    if s == Shadows::Adaptive {
        let measured: Vec<f64> = Shadows::ADAPTIVE
            .iter()
            .map(|&fs| rows_ms((vis_now, fs), &shadow_scopes()))
            .collect();
        judged.push((stages.shadows, measured));
    }
    let chose_cheapest = judged.iter().all(|(stage, measured)| {
        let cheapest = measured.iter().copied().fold(f64::INFINITY, f64::min);
        measured[stage.chosen] * (1.0 - HOLD) <= cheapest
    });
    let recheck_ms = judged
        .iter()
        .map(|(stage, _)| {
            let chosen = stage.price(stage.chosen).unwrap_or(0.0);
            let others: f64 = (0..2)
                .filter(|&w| w != stage.chosen)
                .filter_map(|w| stage.price(w))
                .map(|p| p - chosen)
                .sum();
            others / RECHECK_EVERY as f64
        })
        .sum();
    (chose_cheapest, recheck_ms)
}

/// Over the adaptive variants: the largest `over_cheapest_fixed`, whether every one
/// chose the cheapest ways, and the largest recheck cost over its frame time.
fn adaptive_summary(variants: &[FrameVariant]) -> (f64, bool, f64) {
    let over = variants
        .iter()
        .filter_map(|v| v.over_cheapest_fixed)
        .fold(0.0, f64::max);
    let chose = variants.iter().all(|v| v.chose_cheapest != Some(false));
    let recheck = variants
        .iter()
        .filter_map(|v| v.recheck_ms.map(|ms| ms / v.frame_ms.median))
        .fold(0.0, f64::max);
    (over, chose, recheck)
}
