//! `speculum bench modes`: every mode of one scene timed in the same run, a frame of
//! each in turn (raster, ssr, hybrid, rt, provenance, then again), so that drift in
//! the machine's speed touches every mode alike. Reports per-pass medians, each mode's
//! frame time against `rt` (the median of the per-round ratios: neighbouring frames,
//! so drift cancels), SSIM/RMSE against the `rt` image, and whether ssr < hybrid < rt.
//! Checked in the same run: every mode sees the same reflective pixels, `rt` traces all
//! of them, `hybrid` no more, `ssr` and `raster` none, and every frame time is finite.

use crate::error::{Error, Result};
use crate::metrics::compare_rgba8;
use crate::renderer::{Renderer, FRAME};
use crate::scene::Scene;
use crate::settings::{Mode, Settings};
use crate::vk::{median, Context};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct ModeResult {
    pub mode: String,
    /// Pass → median GPU milliseconds.
    pub passes_ms: BTreeMap<String, f64>,
    pub frame_ms: f64,
    /// Median over rounds of this mode's frame time / the `rt` frame time.
    pub frame_over_rt: f64,
    pub reflective_pixels: u64,
    /// Pixels sent to the ray tracer.
    pub traced_pixels: u64,
    /// Against the `rt` image of the same run.
    pub ssim_vs_rt: f64,
    pub rmse_vs_rt: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct ModesReport {
    pub device: String,
    pub scene: String,
    pub resolution: [u32; 2],
    /// Measured rounds (one frame of every mode each), after the warm-up rounds.
    pub rounds: u32,
    pub modes: Vec<ModeResult>,
    /// ssr < hybrid < rt by frame time, judged by the per-round ratios to rt.
    pub ordered: bool,
    pub valid: bool,
}

/// Times every mode of `scene` in `rounds` interleaved rounds after `warmup` rounds.
pub fn run(ctx: &Arc<Context>, scene: &Scene, base: &Settings, warmup: u32, rounds: u32) -> Result<ModesReport> {
    if rounds == 0 {
        return Err(Error::Settings("bench modes needs at least one round".into()));
    }
    let mut renderers = Mode::ALL
        .iter()
        .map(|&mode| Renderer::new(ctx, scene, &Settings { mode, ..base.clone() }))
        .collect::<Result<Vec<_>>>()?;
    let super::Interleaved { timings, frames } = super::interleave(&mut renderers, warmup, rounds)?;
    let rt = Mode::ALL.iter().position(|&m| m == Mode::Rt).expect("rt is a mode");
    let rt_image = renderers[rt].read_output()?;
    let mut modes = Vec::new();
    for (i, r) in renderers.iter().enumerate() {
        let stats = r.reflection_stats()?;
        let quality = compare_rgba8(&r.read_output()?, &rt_image, base.width, base.height)?;
        let ratios: Vec<f64> = frames[i].iter().zip(&frames[rt]).map(|(a, b)| a / b).collect();
        let mut passes_ms: BTreeMap<String, f64> = timings[i]
            .medians()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        let frame_ms = passes_ms.remove(FRAME).unwrap_or(f64::NAN);
        modes.push(ModeResult {
            mode: Mode::ALL[i].name().to_string(),
            passes_ms,
            frame_ms,
            frame_over_rt: median(&ratios),
            reflective_pixels: stats.reflective_pixels,
            traced_pixels: match Mode::ALL[i] {
                Mode::Raster | Mode::Ssr => 0,
                _ => stats.failed_pixels,
            },
            ssim_vs_rt: quality.ssim,
            rmse_vs_rt: quality.rmse,
        });
    }
    let by = |m: Mode| &modes[Mode::ALL.iter().position(|&x| x == m).expect("every mode is measured")];
    let reflective = by(Mode::Rt).reflective_pixels;
    let valid = modes.iter().all(|m| m.frame_ms.is_finite() && m.frame_ms > 0.0)
        && modes.iter().all(|m| m.reflective_pixels == reflective)
        && by(Mode::Rt).traced_pixels == reflective
        && by(Mode::Hybrid).traced_pixels <= reflective
        && by(Mode::Hybrid).traced_pixels == by(Mode::Provenance).traced_pixels;
    // By the per-round ratios to rt, which cancel drift between rounds.
    let ordered = by(Mode::Ssr).frame_over_rt < by(Mode::Hybrid).frame_over_rt && by(Mode::Hybrid).frame_over_rt < 1.0;
    Ok(ModesReport {
        device: ctx.device_name.clone(),
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        rounds,
        modes,
        ordered,
        valid,
    })
}
