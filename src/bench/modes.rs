//! `speculum bench modes`: every mode of one scene timed in the same run, a frame of
//! each in turn (raster, ssr, hybrid, rt, provenance, then again), so that drift in
//! the machine's speed touches every mode alike. Reports per-pass medians, each mode's
//! frame time against `rt` (the median of the per-round ratios: neighbouring frames,
//! so drift cancels), SSIM/RMSE against the `rt` image, and whether ssr < hybrid < rt.
//! With glossy reflections each mode's image is also compared with the glossy ground
//! truth (`rt` with many rays per glossy pixel, no denoiser).
//! After the modes, `hybrid` again with the other `hybrid_policy` (named
//! `hybrid_ssr_first` or `hybrid_adaptive`), interleaved with them: the two policies
//! side by side.
//! Checked in the same run: every mode sees the same reflective pixels, `rt` traces all
//! of them, `hybrid` (either policy) no more and as many as `provenance` (but with a
//! measured exchange rate, each renderer's own), `ssr` and `raster` none, and every
//! frame time is finite.

use crate::error::Result;
use crate::metrics::compare_rgba8;
use crate::report::{PassTimes, Stat};
use crate::scene::Scene;
use crate::settings::{Hybrid, HybridPolicy, Mode, Settings, GLOSSY_REFERENCE_SPP};
use crate::steady::{RoundsCheck, WarmUp, WarmUpReport};
use crate::vk::{Context, TimingCheck};
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct ModeResult {
    pub mode: String,
    /// Every timer scope in frame order → GPU milliseconds (`null`: not run).
    pub passes_ms: PassTimes,
    pub frame_ms: Stat,
    /// This mode's frame time / the `rt` frame time of the same round, over rounds.
    pub frame_over_rt: Stat,
    pub reflective_pixels: u64,
    /// Reflective pixels the ray tracer produced.
    pub traced_pixels: u64,
    /// traced / reflective pixels.
    pub rt_pixel_fraction: f64,
    /// Against the `rt` image of the same run.
    pub ssim_vs_rt: f64,
    pub rmse_vs_rt: f64,
    /// With glossy reflections: against the glossy ground truth of the same frame (`rt`
    /// with `GLOSSY_REFERENCE_SPP` rays per glossy pixel, no denoiser); `null` without.
    pub ssim_vs_reference: Option<f64>,
    pub rmse_vs_reference: Option<f64>,
    /// The self-check of this mode's measured frames (`vk::timing`).
    pub timing: TimingCheck,
}

/// Every mode of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneModes {
    pub scene: String,
    pub resolution: [u32; 2],
    pub modes: Vec<ModeResult>,
    /// ssr < hybrid < rt by frame time, judged by the per-round ratios to rt.
    pub ordered: bool,
    /// How the warm-up went and how the rounds held (`steady`): a run whose rounds kept
    /// straying is not valid.
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
    pub valid: bool,
}

/// The `bench modes` report.
pub type ModesReport = super::RoundsReport<SceneModes>;

/// Times every mode of `scene` in `rounds` interleaved rounds after the warm-up.
pub fn run(
    ctx: &Arc<Context>,
    scene: &Scene,
    base: &Settings,
    warmup: WarmUp,
    rounds: u32,
    tick: super::Tick<'_>,
) -> Result<SceneModes> {
    let other = match base.hybrid_policy {
        HybridPolicy::Adaptive => HybridPolicy::SsrFirst,
        HybridPolicy::SsrFirst => HybridPolicy::Adaptive,
    };
    let names: Vec<String> = (Mode::ALL.iter().map(|m| m.name().to_string()))
        .chain([format!("hybrid_{}", other.name())])
        .collect();
    let variants = (Mode::ALL.iter().map(|&mode| Settings { mode, ..base.clone() })).chain([Settings {
        mode: Mode::Hybrid,
        hybrid_policy: other,
        ..base.clone()
    }]);
    let (renderers, measured) =
        super::interleave_variants(ctx, scene, variants, (warmup, rounds), tick, "bench modes")?;
    let super::Interleaved {
        timings,
        frames,
        warmup,
        rounds_check,
    } = measured;
    // Every renderer has rendered as many frames (a dynamic scene: as many steps).
    let rendered = warmup.frames + rounds + rounds_check.remeasured;
    let rt = Mode::ALL.iter().position(|&m| m == Mode::Rt).expect("rt is a mode");
    let rt_image = renderers[rt].read_output()?;
    let reference = match base.glossy {
        true => Some(glossy_reference(ctx, scene, base, rendered)?),
        false => None,
    };
    let mut modes = Vec::new();
    for (i, r) in renderers.iter().enumerate() {
        let stats = r.reflection_stats()?;
        let image = r.read_output()?;
        let quality = compare_rgba8(&image, &rt_image, base.width, base.height)?;
        let vs_reference = match &reference {
            Some(reference) => Some(compare_rgba8(&image, reference, base.width, base.height)?),
            None => None,
        };
        let ratios: Vec<f64> = frames[i].iter().zip(&frames[rt]).map(|(a, b)| a / b).collect();
        modes.push(ModeResult {
            mode: names[i].clone(),
            passes_ms: PassTimes::of(&timings[i]),
            frame_ms: Stat::of(&frames[i]).expect("rounds > 0"),
            frame_over_rt: Stat::of(&ratios).expect("rounds > 0"),
            reflective_pixels: stats.reflective_pixels,
            traced_pixels: stats.traced_pixels,
            rt_pixel_fraction: stats.rt_pixel_fraction(),
            ssim_vs_rt: quality.ssim,
            rmse_vs_rt: quality.rmse,
            ssim_vs_reference: vs_reference.as_ref().map(|q| q.ssim),
            rmse_vs_reference: vs_reference.as_ref().map(|q| q.rmse),
            timing: timings[i].check().clone(),
        });
    }
    let by = |m: Mode| &modes[Mode::ALL.iter().position(|&x| x == m).expect("every mode is measured")];
    // Hybrid and provenance trace the same pixels, unless each renderer measures its
    // own exchange rate (the adaptive hybrid's tiles then follow two clocks).
    let measured = Hybrid::of_policy(base) == Hybrid::Measured;
    let reflective = by(Mode::Rt).reflective_pixels;
    let valid = modes
        .iter()
        .all(|m| m.frame_ms.median.is_finite() && m.frame_ms.median > 0.0)
        && modes.iter().all(|m| m.reflective_pixels == reflective)
        && by(Mode::Rt).traced_pixels == reflective
        && by(Mode::Hybrid).traced_pixels <= reflective
        && (by(Mode::Hybrid).traced_pixels == by(Mode::Provenance).traced_pixels || measured)
        && modes[Mode::ALL.len()].traced_pixels <= reflective
        && rounds_check.settled();
    // By the per-round ratios to rt, which cancel drift between rounds.
    let ratio = |m: Mode| by(m).frame_over_rt.median;
    let ordered = ratio(Mode::Ssr) < ratio(Mode::Hybrid) && ratio(Mode::Hybrid) < 1.0;
    Ok(SceneModes {
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        modes,
        ordered,
        warmup,
        rounds_check,
        valid,
    })
}

/// The glossy ground truth of the frame the modes ended on (`Settings::glossy_reference`
/// with `GLOSSY_REFERENCE_SPP` rays, from its own sample stream): a static scene's one
/// frame, a dynamic scene's after as many frames as each mode rendered.
fn glossy_reference(ctx: &Arc<Context>, scene: &Scene, base: &Settings, frames: u32) -> Result<Vec<u8>> {
    let mut r = crate::renderer::Renderer::reference(ctx, scene, base, GLOSSY_REFERENCE_SPP)?;
    for _ in 0..if scene.is_dynamic() { frames } else { 1 } {
        r.render_frame()?;
    }
    r.read_output()
}
