//! Benchmarks: every figure they time, they also check (tinybvh's rule), and their
//! JSON says whether all checks passed.

pub mod anchor;
pub mod dynamic;
#[cfg(feature = "embree")]
pub mod embree;
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
use crate::vk::Timings;

/// Per-renderer timings of an interleaved run: every scope, and the frame times in
/// round order (to form per-round ratios, which cancel drift between rounds).
pub struct Interleaved {
    pub timings: Vec<Timings>,
    pub frames: Vec<Vec<f64>>,
}

pub use crate::headless::Tick;

/// The report of a benchmark that renders variants of each scene in interleaved
/// rounds (`bench modes`, `bench shadows`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct RoundsReport<T> {
    #[serde(flatten)]
    pub header: crate::report::Header,
    /// Measured rounds (one frame of every variant each), after `warmup_rounds`.
    pub rounds: u32,
    pub warmup_rounds: u32,
    pub scenes: Vec<T>,
    /// Every scene's checks passed.
    pub valid: bool,
}

/// A renderer of `scene` for each of `variants`, rendered in `rounds` interleaved
/// rounds after `warmup` (`interleave`); `bench` names the benchmark in the error for
/// no rounds.
pub fn interleave_variants(
    ctx: &std::sync::Arc<crate::vk::Context>,
    scene: &crate::scene::Scene,
    variants: impl Iterator<Item = crate::Settings>,
    (warmup, rounds): (u32, u32),
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

/// Renders one frame of each renderer in turn, `warmup` uncounted rounds and then
/// `rounds` measured ones, so drift in the machine's speed falls on all of them alike.
pub fn interleave(renderers: &mut [Renderer], warmup: u32, rounds: u32, tick: Tick<'_>) -> Result<Interleaved> {
    let mut timings = vec![Timings::default(); renderers.len()];
    let mut frames: Vec<Vec<f64>> = vec![Vec::new(); renderers.len()];
    for round in 0..warmup + rounds {
        for (i, r) in renderers.iter_mut().enumerate() {
            let (t, discarded) = r.render_frame_measured()?;
            tick();
            if round >= warmup {
                frames[i].push(t.get(FRAME).unwrap_or(f64::NAN));
                timings[i].add_measured(&t, discarded);
            }
        }
    }
    Ok(Interleaved { timings, frames })
}
