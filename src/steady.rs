//! Timings at steady clocks. A GPU ramps its clocks under load: the first frames of a
//! run on a cold NVIDIA H200 measured 4.5x slow (room: 6.55 ms a frame after the old
//! fixed 2 warm-up frames, 1.47 ms after 100), and a clock dip can slow every pass of
//! a round ~4x in the middle of a run. Two rules, both pure (tested on the CPU):
//!
//! - `WarmUp`: warm up until the GPU has done a floor of work *and* the frame times
//!   have settled (the medians of the last two windows of frames agree), within a
//!   wall-clock cap; a run says how long that took and whether it settled. A fixed
//!   count (`--warmup N`) is still there for runs that want exactly N frames.
//! - `strays`: rounds of an interleaved benchmark whose frame times lie beyond
//!   `STRAY` of their variant's median are measured again (as a failed timer readout
//!   is), and a run whose rounds keep straying is reported unsettled, not valid.

use crate::report::Stat;
use std::time::{Duration, Instant};

/// A settling window holds as many frames as take `SETTLE_WINDOW_MS` (by the latest
/// frames' times), 2 to `SETTLE_WINDOW_MAX`: settled when the last window's median and
/// the one before it agree within `SETTLE_TOLERANCE`. A GPU's 1.5 ms frames make
/// windows of 8 (a ramp of clocks moves them apart); lavapipe's 1.4 s rounds, windows of
/// 2 (a frame that long averages itself, and ten of them took 27 s).
pub const SETTLE_WINDOW_MS: f64 = 50.0;
pub const SETTLE_WINDOW_MAX: usize = 8;
/// How close two windows' medians must be (relative) to call the clocks settled: a
/// third of the ±15% drift the benchmarks live with between rounds.
pub const SETTLE_TOLERANCE: f64 = 0.05;
/// The GPU work (ms, by the frames' own timestamps) a warm-up does at the least: long
/// enough for a GPU to leave its idle clocks (a few frames on lavapipe).
pub const WARMUP_MIN_GPU_MS: f64 = 250.0;
/// The wall-clock cap of a warm-up: a run that has not settled by then goes on and is
/// reported unsettled.
pub const WARMUP_MAX_WALL: Duration = Duration::from_secs(20);
/// A round strays when one of its frames takes more than this times its variant's
/// median, or less than its inverse: far beyond the ±15% drift between rounds and the
/// adaptive hybrid's probe frames (at most ~1.5x its idle frames), well within the 4x
/// of a clock dip.
pub const STRAY: f64 = 2.0;
/// How often a straying round is measured again before the run is called unsettled.
pub const STRAY_TRIES: u32 = 3;
/// The fewest rounds whose median is a yardstick: with fewer, no round is called a
/// stray (of two rounds, neither is the odd one out).
pub const STRAY_MIN_ROUNDS: usize = 5;

/// How a run warms up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WarmUp {
    /// Exactly this many frames (or rounds), however fast they were.
    Frames(u32),
    /// Until the floor of GPU work is done and the frame times have settled, at least
    /// `min_frames`, within the wall-clock cap.
    Steady {
        min_frames: u32,
        min_gpu_ms: f64,
        max_wall: Duration,
    },
}

impl WarmUp {
    /// The default: steady clocks, at least 2 frames.
    pub fn steady() -> Self {
        WarmUp::Steady {
            min_frames: 2,
            min_gpu_ms: WARMUP_MIN_GPU_MS,
            max_wall: WARMUP_MAX_WALL,
        }
    }

    /// `--warmup N` when given (exactly N), else `steady()`.
    pub fn from_arg(frames: Option<u32>) -> Self {
        frames.map_or(Self::steady(), WarmUp::Frames)
    }

    /// The rule's name in reports: `frames N` or `steady`.
    pub fn rule(&self) -> String {
        match *self {
            WarmUp::Frames(n) => format!("frames {n}"),
            WarmUp::Steady { .. } => "steady".to_string(),
        }
    }

    /// The fewest frames it takes (for a progress bar's length).
    pub fn min_frames(&self) -> u32 {
        match *self {
            WarmUp::Frames(n) => n,
            WarmUp::Steady { min_frames, .. } => min_frames.max(4),
        }
    }

    /// A warm-up under way.
    pub fn start(self) -> Warming {
        Warming {
            rule: self,
            times: Vec::new(),
            gpu_ms: 0.0,
            start: Instant::now(),
        }
    }
}

/// How a warm-up went (in reports as `warmup`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct WarmUpReport {
    /// `frames N` or `steady`.
    pub rule: String,
    pub frames: u32,
    /// The GPU work done (ms, by the frames' timestamps; wall time where a readout
    /// failed).
    pub gpu_ms: f64,
    pub wall_s: f64,
    /// Whether the frame times settled (always true for a fixed count, which does not
    /// ask).
    pub settled: bool,
    /// After a steady warm-up, the rounds that priced the adaptive stages again at the
    /// settled clocks (`renderer::stages`; 0 without one, or after a fixed count).
    pub pricing_rounds: u32,
}

/// A warm-up under way: fed each warm-up frame's time until `done`.
pub struct Warming {
    rule: WarmUp,
    times: Vec<f64>,
    gpu_ms: f64,
    start: Instant,
}

/// The frames of a settling window after `times`: as many as take `SETTLE_WINDOW_MS`
/// by the median of the last three, 2 to `SETTLE_WINDOW_MAX`.
pub fn settle_window(times: &[f64]) -> usize {
    let recent = Stat::of(&times[times.len().saturating_sub(3)..]).map_or(f64::NAN, |s| s.median);
    match recent > 0.0 {
        true => ((SETTLE_WINDOW_MS / recent).ceil() as usize).clamp(2, SETTLE_WINDOW_MAX),
        false => SETTLE_WINDOW_MAX,
    }
}

/// Whether the last two windows (`settle_window`) of `times` have medians within
/// `SETTLE_TOLERANCE`.
pub fn settled(times: &[f64]) -> bool {
    let (n, w) = (times.len(), settle_window(times));
    if n < 2 * w {
        return false;
    }
    let median = |w: &[f64]| Stat::of(w).map_or(f64::NAN, |s| s.median);
    let (before, last) = (median(&times[n - 2 * w..n - w]), median(&times[n - w..]));
    (last - before).abs() <= SETTLE_TOLERANCE * before.max(last)
}

impl Warming {
    /// Whether the warm-up is over (before any frame: whether it wants none).
    pub fn done(&self) -> bool {
        let n = self.times.len() as u32;
        match self.rule {
            WarmUp::Frames(k) => n >= k,
            WarmUp::Steady {
                min_frames,
                min_gpu_ms,
                max_wall,
            } => {
                let warm = n >= min_frames && self.gpu_ms >= min_gpu_ms && settled(&self.times);
                warm || (n >= min_frames && self.start.elapsed() >= max_wall)
            }
        }
    }

    /// Takes one warm-up frame (or round) that took `ms` of GPU time.
    pub fn add(&mut self, ms: f64) {
        self.times.push(ms);
        self.gpu_ms += ms;
    }

    /// What the warm-up did.
    pub fn report(&self) -> WarmUpReport {
        let settled = match self.rule {
            WarmUp::Frames(_) => true,
            WarmUp::Steady { .. } => settled(&self.times),
        };
        WarmUpReport {
            rule: self.rule.rule(),
            frames: self.times.len() as u32,
            gpu_ms: self.gpu_ms,
            wall_s: self.start.elapsed().as_secs_f64(),
            settled,
            pricing_rounds: 0,
        }
    }
}

/// The rounds (indices) that stray: `frames[v][k]` is variant v's frame time in round
/// k; round k strays when any variant's time there lies beyond `STRAY` of its median
/// (none with fewer than `STRAY_MIN_ROUNDS` rounds).
pub fn strays(frames: &[Vec<f64>]) -> Vec<usize> {
    let rounds = frames.first().map_or(0, Vec::len);
    if rounds < STRAY_MIN_ROUNDS {
        return Vec::new();
    }
    let medians: Vec<f64> = frames
        .iter()
        .map(|f| Stat::of(f).map_or(f64::NAN, |s| s.median))
        .collect();
    (0..rounds)
        .filter(|&k| {
            frames.iter().zip(&medians).any(|(f, &m)| {
                let t = f[k];
                m > 0.0 && !(t <= STRAY * m && t * STRAY >= m)
            })
        })
        .collect()
}

/// How an interleaved run's rounds held (in reports as `rounds_check`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RoundsCheck {
    /// Rounds that strayed and were measured again (a round counted once per try).
    pub remeasured: u32,
    /// Rounds still straying after `STRAY_TRIES` tries each: the run is unsettled.
    pub still_straying: u32,
}

impl RoundsCheck {
    pub fn settled(&self) -> bool {
        self.still_straying == 0
    }

    /// One line for a run's text output, when there is something to say.
    pub fn note(&self) -> Option<String> {
        (self.remeasured > 0).then(|| {
            format!(
                "{} round(s) strayed beyond {STRAY}x their medians and were measured again{}",
                self.remeasured,
                if self.settled() {
                    String::new()
                } else {
                    format!("; {} still did: UNSETTLED (not valid)", self.still_straying)
                }
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed count takes exactly that many frames and calls itself settled.
    #[test]
    fn a_fixed_count_is_exact() {
        let mut w = WarmUp::Frames(3).start();
        for k in 0..3 {
            assert!(!w.done(), "frame {k}");
            w.add(100.0);
        }
        assert!(w.done());
        let r = w.report();
        assert_eq!((r.rule.as_str(), r.frames, r.settled), ("frames 3", 3, true));
        assert!(WarmUp::Frames(0).start().done());
    }

    /// A cold GPU (frames 4.5x slow, ramping down to their steady time over 40 frames):
    /// the steady warm-up runs until the ramp is over and the times agree, not 2
    /// frames; a GPU that is warm already stops once the floor of work is done and two
    /// windows agree.
    #[test]
    fn the_warm_up_waits_for_the_clocks() {
        let ramp = |k: usize| 1.47 * (1.0 + 3.5 * (1.0 - k as f64 / 40.0).max(0.0));
        let mut w = WarmUp::steady().start();
        let mut k = 0;
        while !w.done() {
            w.add(ramp(k));
            k += 1;
            assert!(k < 10_000, "never done");
        }
        let r = w.report();
        assert!(r.settled && r.gpu_ms >= WARMUP_MIN_GPU_MS, "{r:?}");
        // Done only near the end of the ramp: the last window within 5% of the steady time.
        assert!(k >= 36, "stopped at frame {k}, time {}", ramp(k));
        assert!(
            ramp(k - 1) <= 1.47 * 1.05 * 1.1,
            "stopped at frame {k}, time {}",
            ramp(k - 1)
        );
        // Warm already: 100 ms frames reach the floor in 3, and two windows of 2 agree
        // after 4.
        let mut w = WarmUp::steady().start();
        let mut k = 0;
        while !w.done() {
            w.add(if k % 2 == 0 { 100.0 } else { 104.0 });
            k += 1;
        }
        assert_eq!(k, 4);
        // Windows hold what takes 50 ms: 8 frames of 1.5 ms, 2 of 1.4 s, 3 of 20 ms.
        let windows = [1.5, 1400.0, 20.0].map(|ms| settle_window(&[ms; 9]));
        assert_eq!(windows, [8, 2, 3]);
    }

    /// Frame times that never settle (each 10% slower than the one before) end at the
    /// wall-clock cap, reported unsettled.
    #[test]
    fn a_warm_up_that_cannot_settle_ends_at_its_cap_unsettled() {
        let mut w = WarmUp::Steady {
            min_frames: 2,
            min_gpu_ms: 0.0,
            max_wall: Duration::from_millis(50),
        }
        .start();
        let mut ms = 1.0;
        while !w.done() {
            w.add(ms);
            ms *= 1.1;
            std::thread::sleep(Duration::from_millis(1));
        }
        let r = w.report();
        assert!(!r.settled && r.wall_s >= 0.05, "{r:?}");
    }

    /// A round 4x slow in every variant (a clock dip) strays, as does one variant's
    /// frame at half its median; the ±15% drift and a probe frame's 1.5x do not.
    #[test]
    fn rounds_beyond_their_spread_stray() {
        let base = [1.0, 1.1, 0.9, 1.05, 0.95, 1.0, 1.15, 0.87];
        let mut a: Vec<f64> = base.to_vec();
        let mut b: Vec<f64> = base.iter().map(|t| 3.0 * t).collect();
        assert!(strays(&[a.clone(), b.clone()]).is_empty());
        b[2] *= 1.5; // a probe frame
        assert!(strays(&[a.clone(), b.clone()]).is_empty());
        a[5] *= 4.0;
        b[5] *= 4.0; // a clock dip
        a[7] = 0.45;
        assert_eq!(strays(&[a.clone(), b.clone()]), vec![5, 7]);
        // Two rounds are no yardstick for each other.
        assert!(strays(&[a[4..6].to_vec(), b[4..6].to_vec()]).is_empty());
    }
}
