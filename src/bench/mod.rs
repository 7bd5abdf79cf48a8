//! Benchmarks: every figure they time, they also check (tinybvh's rule), and their
//! JSON says whether all checks passed.

pub mod anchor;
pub mod dynamic;
#[cfg(feature = "embree")]
pub mod embree;
pub mod frame;
pub mod khr;
pub mod lbvh;
pub mod modes;
pub mod rays;
pub mod rays_file;
pub mod reflect;
pub mod shadows;
pub mod suite;

use crate::error::Result;
use crate::renderer::{Renderer, FRAME};
use crate::steady::{strays, RoundsCheck, WarmUp, WarmUpReport, STRAY_TRIES};
use crate::vk::{TimerReadout, Timings};

/// Per-renderer timings of an interleaved run: every scope, and the frame times in
/// round order (to form per-round ratios, which cancel drift between rounds); how the
/// warm-up went and how the rounds held.
pub struct Interleaved {
    pub timings: Vec<Timings>,
    pub frames: Vec<Vec<f64>>,
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
}

pub use crate::headless::Tick;

/// The report of a benchmark that renders variants of each scene in interleaved
/// rounds (`bench modes`, `bench shadows`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct RoundsReport<T> {
    #[serde(flatten)]
    pub header: crate::report::Header,
    /// Measured rounds (one frame of every variant each), after the warm-up.
    pub rounds: u32,
    /// The warm-up's rule (`frames N` or `steady`); each scene says how its went.
    pub warmup: String,
    pub scenes: Vec<T>,
    /// Every scene's checks passed.
    pub valid: bool,
}

/// A renderer of `scene` for each of `variants`, rendered in `rounds` interleaved
/// rounds after the warm-up (`interleave`); `bench` names the benchmark in the error
/// for no rounds.
pub fn interleave_variants(
    ctx: &std::sync::Arc<crate::vk::Context>,
    scene: &crate::scene::Scene,
    variants: impl Iterator<Item = crate::Settings>,
    (warmup, rounds): (WarmUp, u32),
    tick: Tick<'_>,
    bench: &str,
) -> crate::Result<(Vec<Renderer>, Interleaved)> {
    if rounds == 0 {
        return Err(crate::Error::Settings(format!("{bench} needs at least one round")));
    }
    let mut renderers = variants
        .map(|s| Renderer::new(ctx, scene, &s))
        .collect::<crate::Result<Vec<_>>>()?;
    let measured = interleave(&mut renderers, warmup, rounds, tick)?;
    Ok((renderers, measured))
}

/// Renders one frame of each renderer in turn: uncounted rounds until the warm-up is
/// done (`steady`), then `rounds` measured ones, so drift in the machine's speed falls
/// on all of them alike. Rounds that stray (`steady::strays`: a clock dip) are measured
/// again, up to `STRAY_TRIES` times each; `rounds_check` says how many and whether the
/// run settled.
pub fn interleave(renderers: &mut [Renderer], warmup: WarmUp, rounds: u32, tick: Tick<'_>) -> Result<Interleaved> {
    let warmup = crate::headless::warm_up(&mut renderers.iter_mut().collect::<Vec<_>>(), warmup, tick)?;
    let (measured, rounds_check) = measure_rounds(rounds, FRAME, || {
        renderers
            .iter_mut()
            .map(|r| {
                let measured = r.render_frame_measured();
                tick();
                measured
            })
            .collect()
    })?;
    let mut timings = vec![Timings::default(); renderers.len()];
    for r in &measured {
        for (i, (t, discarded)) in r.iter().enumerate() {
            timings[i].add_measured(t, *discarded);
        }
    }
    Ok(Interleaved {
        timings,
        frames: times_of(&measured, FRAME),
        warmup,
        rounds_check,
    })
}

/// A round's readouts: one a variant, each with the failed readouts discarded before it.
pub type Round = Vec<(TimerReadout, u32)>;

/// Each variant's `scope` times over `rounds`, in round order (NaN where a readout
/// lacks it).
fn times_of(rounds: &[Round], scope: &str) -> Vec<Vec<f64>> {
    let variants = rounds.first().map_or(0, Vec::len);
    (0..variants)
        .map(|i| rounds.iter().map(|r| r[i].0.get(scope).unwrap_or(f64::NAN)).collect())
        .collect()
}

/// Measures `rounds` rounds with `round`, then measures again the rounds whose `scope`
/// times stray (`steady::strays`), up to `STRAY_TRIES` times: the rounds kept, and how
/// they held.
pub fn measure_rounds(
    rounds: u32,
    scope: &str,
    mut round: impl FnMut() -> Result<Round>,
) -> Result<(Vec<Round>, RoundsCheck)> {
    let mut measured: Vec<Round> = (0..rounds).map(|_| round()).collect::<Result<_>>()?;
    let mut check = RoundsCheck::default();
    for _ in 0..STRAY_TRIES {
        let straying = strays(&times_of(&measured, scope));
        if straying.is_empty() {
            break;
        }
        for k in straying {
            measured[k] = round()?;
            check.remeasured += 1;
        }
    }
    check.still_straying = strays(&times_of(&measured, scope)).len() as u32;
    Ok((measured, check))
}
