//! `speculum bench reflect`: how the reflection passes' time splits as the share of
//! SSR-failed (ray-traced) pixels varies. The share is swept by halving SSR's step
//! budget from the settings' value down to one step (a ray whose hit lies beyond the
//! budget fails; everything else fixed), then by rejecting every SSR hit (a confidence
//! threshold above 1), which traces every reflective pixel with SSR still run.
//! (The confidence threshold alone no longer moves the share: hits below confidence 1
//! are traced either way, to be blended.) Checked in the same run: the reflective pixel
//! count is the same at every point, the failed share never decreases along the sweep,
//! and the last point traces every reflective pixel.

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
    pub ssr_max_steps: u32,
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

/// A confidence threshold above any confidence: every SSR hit fails.
const REJECT_ALL: f32 = 1.01;

/// The sweep's (step budget, confidence threshold) points for `base`: the budget
/// halved down to 1, then every hit rejected.
pub fn sweep(base: &Settings) -> Vec<(u32, f32)> {
    let mut points: Vec<(u32, f32)> = std::iter::successors(Some(base.ssr_max_steps), |&s| (s > 1).then_some(s / 2))
        .map(|s| (s, base.ssr_min_confidence))
        .collect();
    points.push((base.ssr_max_steps, REJECT_ALL));
    points
}

pub fn run(ctx: &Arc<Context>, scene: &Scene, base: &Settings, plan: FramePlan) -> Result<SplitReport> {
    let mut points = Vec::new();
    let mut reflective = Vec::new();
    for (steps, t) in sweep(base) {
        let settings = Settings {
            mode: Mode::Hybrid,
            ssr_max_steps: steps,
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
            ssr_max_steps: steps,
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
