//! Headless rendering: warm-up frames, measured frames, per-scope medians, and the
//! timings report whose field names later tools rely on.

use crate::error::{Error, Result};
use crate::metrics::compare_rgba8;
use crate::renderer::{Renderer, FRAME};
use crate::scene::Scene;
use crate::settings::Mode;
use crate::settings::Settings;
use crate::vk::{Context, Timings};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// The timings JSON. Keep these names: later tools read them.
#[derive(Clone, Debug, Serialize)]
pub struct TimingsReport {
    /// Device name.
    pub device: String,
    pub scene: String,
    /// [width, height] in pixels.
    pub resolution: [u32; 2],
    /// Frames measured (warm-up frames excluded).
    pub frames: u32,
    pub warmup_frames: u32,
    /// Timer scope → median GPU milliseconds.
    pub passes_ms: BTreeMap<String, f64>,
    /// Median GPU milliseconds of the whole frame.
    pub frame_ms: f64,
    /// Reflection mode of the measured frames.
    pub mode: String,
    /// Pixels with a reflective surface.
    pub reflective_pixels: u64,
    /// Reflective pixels SSR failed on.
    pub failed_pixels: u64,
    /// failed / reflective pixels: the share of reflections the ray tracer produced.
    pub rt_pixel_fraction: f64,
    /// Failed pixels by reason (`left_screen`, `behind_geometry`, `out_of_steps`,
    /// `back_face`, `low_confidence`, `hit_reflective`, `forced`, and `ssr_blend`: SSR
    /// hits blended with the ray tracer by their confidence, traced too).
    pub fail_reasons: BTreeMap<String, u64>,
    /// With `--reference`: SSIM and RMSE of this frame against the same frame in `rt`
    /// mode (see `metrics`), and the reference's median frame time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ssim: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rmse: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_frame_ms: Option<f64>,
    /// Validation warnings and errors so far; present when validation is on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_messages: Option<u32>,
}

/// A finished headless render.
pub struct Rendered {
    pub report: TimingsReport,
    /// The last frame, tightly packed RGBA8 (sRGB-encoded).
    pub rgba: Vec<u8>,
    /// With a reference: the `rt` mode frame.
    pub reference_rgba: Option<Vec<u8>>,
    /// The last frame's fail mask coloured by reason (`ReflectionMaps::fail_mask_rgba`).
    pub fail_mask_rgba: Vec<u8>,
}

/// Frames to render and measure.
#[derive(Clone, Copy, Debug)]
pub struct FramePlan {
    pub warmup: u32,
    pub frames: u32,
    /// Also render the frame in `rt` mode and report SSIM/RMSE against it.
    pub reference: bool,
}

fn measure(renderer: &mut Renderer, plan: FramePlan) -> Result<Timings> {
    for _ in 0..plan.warmup {
        renderer.render_frame()?;
    }
    let mut timings = Timings::default();
    for _ in 0..plan.frames {
        timings.add_frame(&renderer.render_frame()?);
    }
    Ok(timings)
}

/// Renders `plan.warmup` uncounted frames, then `plan.frames` measured ones (and the
/// `rt` reference when asked).
pub fn render(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, plan: FramePlan) -> Result<Rendered> {
    if plan.frames == 0 {
        return Err(Error::Settings("--frames must be at least 1".into()));
    }
    let mut renderer = Renderer::new(ctx, scene, settings)?;
    let timings = measure(&mut renderer, plan)?;
    let rgba = renderer.read_output()?;
    let maps = renderer.reflection_maps()?;
    let stats = maps.stats();
    let mut passes_ms: BTreeMap<String, f64> = timings.medians().into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    let frame_ms = passes_ms.remove(FRAME).unwrap_or(f64::NAN);
    let (mut ssim, mut rmse, mut reference_frame_ms, mut reference_rgba) = (None, None, None, None);
    if plan.reference {
        renderer.set_mode(Mode::Rt);
        let ref_timings = measure(&mut renderer, plan)?;
        let reference = renderer.read_output()?;
        let c = compare_rgba8(&rgba, &reference, settings.width, settings.height)?;
        ssim = Some(c.ssim);
        rmse = Some(c.rmse);
        reference_frame_ms = ref_timings.medians().get(FRAME).copied();
        reference_rgba = Some(reference);
    }
    let report = TimingsReport {
        device: ctx.device_name.clone(),
        scene: scene.name.clone(),
        resolution: [settings.width, settings.height],
        frames: plan.frames,
        warmup_frames: plan.warmup,
        passes_ms,
        frame_ms,
        mode: settings.mode.name().to_string(),
        reflective_pixels: stats.reflective_pixels,
        failed_pixels: stats.failed_pixels,
        rt_pixel_fraction: stats.rt_pixel_fraction(),
        fail_reasons: stats.fail_reasons.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        ssim,
        rmse,
        reference_frame_ms,
        validation_messages: ctx.validation_enabled().then(|| ctx.validation_messages()),
    };
    Ok(Rendered {
        report,
        rgba,
        reference_rgba,
        fail_mask_rgba: maps.fail_mask_rgba(),
    })
}

/// Writes tightly packed RGBA8 as a PNG.
pub fn save_png(path: &Path, rgba: &[u8], width: u32, height: u32) -> Result<()> {
    image::save_buffer(path, rgba, width, height, image::ExtendedColorType::Rgba8).map_err(|e| Error::Output {
        path: path.into(),
        detail: e.to_string(),
    })
}
