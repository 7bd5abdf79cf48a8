//! `speculum bench reflect`: how the reflection passes' time splits as the share of
//! SSR-failed (ray-traced) pixels varies. The share is swept by raising the SSR
//! confidence threshold (everything else fixed), from SSR's own failures up to every
//! reflective pixel. Checked in the same run: the reflective pixel count is the same at
//! every step and the failed share never decreases as the threshold rises.

use crate::error::Result;
use crate::headless::{self, FramePlan};
use crate::scene::Scene;
use crate::settings::{Mode, Settings};
use crate::vk::Context;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct SplitPoint {
    pub ssr_min_confidence: f32,
    pub rt_pixel_fraction: f64,
    pub failed_pixels: u64,
    /// Pass → median GPU milliseconds.
    pub passes_ms: BTreeMap<String, f64>,
    pub frame_ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct SplitReport {
    pub device: String,
    pub scene: String,
    pub resolution: [u32; 2],
    pub reflective_pixels: u64,
    /// The `rt` mode frame for comparison.
    pub rt_frame_ms: f64,
    pub points: Vec<SplitPoint>,
    pub valid: bool,
}

/// Confidence thresholds of the sweep; above 1 every SSR hit fails.
pub const THRESHOLDS: [f32; 5] = [0.0, 0.3, 0.6, 0.9, 1.01];

pub fn run(ctx: &Arc<Context>, scene: &Scene, base: &Settings, plan: FramePlan) -> Result<SplitReport> {
    let mut points = Vec::new();
    let mut reflective = Vec::new();
    for &t in &THRESHOLDS {
        let settings = Settings {
            mode: Mode::Hybrid,
            ssr_min_confidence: t,
            ..base.clone()
        };
        let r = headless::render(
            ctx,
            scene,
            &settings,
            FramePlan {
                reference: false,
                ..plan
            },
        )?
        .report;
        reflective.push(r.reflective_pixels);
        points.push(SplitPoint {
            ssr_min_confidence: t,
            rt_pixel_fraction: r.rt_pixel_fraction,
            failed_pixels: r.failed_pixels,
            passes_ms: r.passes_ms,
            frame_ms: r.frame_ms,
        });
    }
    let rt = headless::render(
        ctx,
        scene,
        &Settings {
            mode: Mode::Rt,
            ..base.clone()
        },
        FramePlan {
            reference: false,
            ..plan
        },
    )?
    .report;
    let same_reflective = reflective.iter().all(|&r| r == rt.reflective_pixels);
    let monotonic = points.windows(2).all(|w| w[1].failed_pixels >= w[0].failed_pixels);
    let all_at_end = points.last().is_some_and(|p| p.failed_pixels == rt.reflective_pixels);
    Ok(SplitReport {
        device: ctx.device_name.clone(),
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        reflective_pixels: rt.reflective_pixels,
        rt_frame_ms: rt.frame_ms,
        points,
        valid: same_reflective && monotonic && all_at_end,
    })
}
