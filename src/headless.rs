//! Headless rendering: warm-up frames, measured frames, per-scope medians, and the
//! timings report whose field names later tools rely on.

use crate::error::{Error, Result};
use crate::renderer::{Renderer, FRAME};
use crate::scene::Scene;
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
    /// Validation warnings and errors so far; present when validation is on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_messages: Option<u32>,
}

/// A finished headless render.
pub struct Rendered {
    pub report: TimingsReport,
    /// The last frame, tightly packed RGBA8 (sRGB-encoded).
    pub rgba: Vec<u8>,
}

/// Renders `warmup` uncounted frames and then `frames` measured ones.
pub fn render(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, warmup: u32, frames: u32) -> Result<Rendered> {
    if frames == 0 {
        return Err(Error::Settings("--frames must be at least 1".into()));
    }
    let mut renderer = Renderer::new(ctx, scene, settings)?;
    for _ in 0..warmup {
        renderer.render_frame()?;
    }
    let mut timings = Timings::default();
    for _ in 0..frames {
        timings.add_frame(&renderer.render_frame()?);
    }
    let rgba = renderer.read_output()?;
    let mut passes_ms: BTreeMap<String, f64> = timings.medians().into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    let frame_ms = passes_ms.remove(FRAME).unwrap_or(f64::NAN);
    let report = TimingsReport {
        device: ctx.device_name.clone(),
        scene: scene.name.clone(),
        resolution: [settings.width, settings.height],
        frames,
        warmup_frames: warmup,
        passes_ms,
        frame_ms,
        validation_messages: ctx.validation_enabled().then(|| ctx.validation_messages()),
    };
    Ok(Rendered { report, rgba })
}

/// Writes tightly packed RGBA8 as a PNG.
pub fn save_png(path: &Path, rgba: &[u8], width: u32, height: u32) -> Result<()> {
    image::save_buffer(path, rgba, width, height, image::ExtendedColorType::Rgba8).map_err(|e| Error::Output {
        path: path.into(),
        detail: e.to_string(),
    })
}
