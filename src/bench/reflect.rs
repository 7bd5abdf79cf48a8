//! `speculum bench reflect`: how the reflection passes' time splits as the share of
//! SSR-failed (ray-traced) pixels varies. The share is swept by halving SSR's step
//! budget from the settings' value down to one step (a ray whose hit lies beyond the
//! budget fails; everything else fixed), then by rejecting every SSR hit (a confidence
//! threshold above 1, which `ssr.classify` applies before any march), which traces
//! every reflective pixel. (The confidence threshold alone no longer moves the share:
//! hits below confidence 1 are traced either way, to be blended.) Every point and the
//! `rt` mode are rendered in the same run, one frame of each in turn, so drift in the
//! machine's speed spreads over all of them; each point's frame is also given against
//! `rt` as the median of per-round ratios. Checked in the same run: the reflective pixel
//! count is the same at every point, the failed share never decreases along the sweep,
//! and the last point traces every reflective pixel.

use crate::error::{Error, Result};
use crate::renderer::Renderer;
use crate::report::{Header, PassTimes, Stat};
use crate::scene::Scene;
use crate::settings::{HybridPolicy, Mode, Settings};
use crate::steady::{RoundsCheck, WarmUp, WarmUpReport};
use crate::vk::{Context, TimingCheck};
use serde::Serialize;
use std::sync::Arc;

#[derive(Clone, Debug, Serialize)]
pub struct SplitPoint {
    pub ssr_max_steps: u32,
    pub ssr_min_confidence: f32,
    /// Reflective pixels the ray tracer produced, and their share.
    pub traced_pixels: u64,
    pub rt_pixel_fraction: f64,
    /// Every timer scope in frame order → GPU milliseconds (`null`: not run).
    pub passes_ms: PassTimes,
    pub frame_ms: Stat,
    /// This point's frame time / the `rt` frame's of the same round, over rounds.
    pub frame_over_rt: Stat,
}

/// The `bench reflect` report.
#[derive(Clone, Debug, Serialize)]
pub struct SplitReport {
    #[serde(flatten)]
    pub header: Header,
    pub scene: String,
    pub resolution: [u32; 2],
    /// Measured rounds (one frame of every point and of `rt` each), after the warm-up.
    pub rounds: u32,
    /// How the warm-up went and how the rounds held (`steady`): a run whose rounds kept
    /// straying is not valid.
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
    pub reflective_pixels: u64,
    /// The `rt` mode frame for comparison.
    pub rt_frame_ms: Stat,
    pub points: Vec<SplitPoint>,
    /// The self-check of every measured frame, all renderers together (`vk::timing`).
    pub timing: TimingCheck,
    pub valid: bool,
}

/// A confidence threshold above any confidence: every SSR hit fails.
const REJECT_ALL: f32 = 1.01;

/// The sweep's (step budget, confidence threshold) points for `base`: the budget
/// halved down to 1, then every hit rejected (and every failure traced).
pub fn sweep(base: &Settings) -> Vec<(u32, f32)> {
    let mut points: Vec<(u32, f32)> = std::iter::successors(Some(base.ssr_max_steps), |&s| (s > 1).then_some(s / 2))
        .map(|s| (s, base.ssr_min_confidence))
        .collect();
    points.push((base.ssr_max_steps, REJECT_ALL));
    points
}

pub fn run(
    ctx: &Arc<Context>,
    scene: &Scene,
    base: &Settings,
    warmup: WarmUp,
    rounds: u32,
    tick: super::Tick<'_>,
) -> Result<SplitReport> {
    if rounds == 0 {
        return Err(Error::Settings("bench reflect needs at least one frame".into()));
    }
    let sweep = sweep(base);
    // The sweep's renderers, then rt's last.
    let mut renderers = sweep
        .iter()
        .map(|&(steps, t)| Settings {
            mode: Mode::Hybrid,
            // The SSR-first hybrid's split: the adaptive one would move pixels itself.
            hybrid_policy: HybridPolicy::SsrFirst,
            ssr_max_steps: steps,
            ssr_min_confidence: t,
            // The last point traces every reflective pixel through the hybrid's passes,
            // weak reflectors too (`trace_min_weight` would leave three in four).
            trace_min_weight: if t == REJECT_ALL { 0.0 } else { base.trace_min_weight },
            ..base.clone()
        })
        .chain(std::iter::once(Settings {
            mode: Mode::Rt,
            ..base.clone()
        }))
        .map(|settings| Renderer::new(ctx, scene, &settings))
        .collect::<Result<Vec<_>>>()?;
    let super::Interleaved {
        timings,
        frames,
        warmup,
        rounds_check,
    } = super::interleave(&mut renderers, warmup, rounds, tick)?;
    let rt_index = sweep.len();
    let rt_reflective = renderers[rt_index].reflection_stats()?.reflective_pixels;
    let rt_frame_ms = Stat::of(&frames[rt_index]).expect("rounds > 0");
    let mut points = Vec::new();
    let mut reflective = Vec::new();
    for (i, &(steps, t)) in sweep.iter().enumerate() {
        let stats = renderers[i].reflection_stats()?;
        reflective.push(stats.reflective_pixels);
        let ratios: Vec<f64> = frames[i].iter().zip(&frames[rt_index]).map(|(a, b)| a / b).collect();
        points.push(SplitPoint {
            ssr_max_steps: steps,
            ssr_min_confidence: t,
            traced_pixels: stats.traced_pixels,
            rt_pixel_fraction: stats.rt_pixel_fraction(),
            passes_ms: PassTimes::of(&timings[i]),
            frame_ms: Stat::of(&frames[i]).expect("rounds > 0"),
            frame_over_rt: Stat::of(&ratios).expect("rounds > 0"),
        });
    }
    let same_reflective = reflective.iter().all(|&r| r == rt_reflective);
    let monotonic = points.windows(2).all(|w| w[1].traced_pixels >= w[0].traced_pixels);
    let all_at_end = points.last().is_some_and(|p| p.traced_pixels == rt_reflective);
    Ok(SplitReport {
        header: Header::new("bench.reflect", Some(ctx), Some(base)),
        scene: scene.name.clone(),
        resolution: [base.width, base.height],
        rounds,
        warmup,
        reflective_pixels: rt_reflective,
        rt_frame_ms,
        points,
        timing: crate::vk::Timings::check_all(&timings),
        valid: same_reflective && monotonic && all_at_end && rounds_check.settled(),
        rounds_check,
    })
}
