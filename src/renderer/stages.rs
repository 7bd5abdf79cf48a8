//! The frame's adaptive stages: a stage that can be made more than one way
//! (`visibility = adaptive`: the G-buffer rasterized or by primary rays; `shadows =
//! adaptive`: hybrid or ray-traced shadows) is priced from the frame's own
//! self-checked timestamps, as the adaptive hybrid prices its paths (`exchange`), and
//! the frames take the cheaper way.
//!
//! Each way is tried in turn until it has `SAMPLES` checked frames (the first frames
//! of a renderer, or after its settings change); its price is the median of its last
//! `KEPT` samples, so one slow frame (a cold cache, a clock still rising) does not
//! decide. Then the frames take the cheapest, and one frame in `RECHECK_EVERY` takes
//! another way, so every price stays current on a device whose balance moves (clocks,
//! a moving camera, a scene that grows). Another way is taken only once it undercuts
//! the one in use by more than `HOLD` of its price, so timing noise does not flip the
//! frames between two ways that cost the same.

use super::table::Row;
use crate::settings::{Settings, Shadows, Visibility};
use crate::vk::TimerReadout;

/// Rounds a run may render to price its adaptive stages (after a steady warm-up,
/// before a benchmark's rounds) before it goes on unpriced.
pub const PRICE_ROUNDS: u32 = 40;

/// Checked frames a way needs before it is priced.
pub const SAMPLES: u32 = 3;
/// Samples kept per way; its price is their median.
const KEPT: usize = 5;
/// While priced, one frame in this many takes another way (the others in turn).
pub const RECHECK_EVERY: u32 = 64;
/// The part of the price in use another way must undercut it by to be taken.
pub const HOLD: f64 = 1.0 / 16.0;

/// One adaptive stage with `N` ways (indices into the stage's own list of them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stage<const N: usize> {
    /// Each way's last `KEPT` samples (ms), newest at `taken % KEPT`.
    samples: [[f64; KEPT]; N],
    /// Samples each way has taken since the last reset.
    taken: [u32; N],
    /// Frames recorded on each way since the last reset.
    pub frames: [u64; N],
    /// The way the frames take once every way is priced.
    pub chosen: usize,
    /// The frame (modulo `RECHECK_EVERY`) that rechecks: stages recheck on different
    /// frames, and apart from the hybrid's (`RECHECK_EVERY - 1`).
    phase: u32,
}

impl<const N: usize> Stage<N> {
    pub fn new(phase: u32) -> Self {
        Self {
            samples: [[0.0; KEPT]; N],
            taken: [0; N],
            frames: [0; N],
            chosen: 0,
            phase: phase % RECHECK_EVERY,
        }
    }

    /// The way of frame `index`: the first way not priced yet; once all are, the
    /// chosen one but on a recheck frame.
    pub fn frame_way(&self, index: u32) -> usize {
        if let Some(unpriced) = (0..N).find(|&w| self.price(w).is_none()) {
            return unpriced;
        }
        if N > 1 && index % RECHECK_EVERY == self.phase {
            let other = (index / RECHECK_EVERY) as usize % (N - 1);
            return (self.chosen + 1 + other) % N;
        }
        self.chosen
    }

    /// Counts a frame recorded on `way`.
    pub fn count(&mut self, way: usize) {
        self.frames[way] += 1;
    }

    /// After a frame on `way`: its stage's rows' ms if its timings passed their
    /// self-check. Once every way is priced, the cheapest is chosen (held within `HOLD`).
    pub fn take(&mut self, way: usize, ms: Option<f64>) {
        let Some(ms) = ms.filter(|ms| ms.is_finite() && *ms >= 0.0) else {
            return;
        };
        self.samples[way][self.taken[way] as usize % KEPT] = ms;
        self.taken[way] += 1;
        let prices: Option<Vec<f64>> = (0..N).map(|w| self.price(w)).collect();
        let Some(prices) = prices else { return };
        let cheapest = (0..N).min_by(|&a, &b| prices[a].total_cmp(&prices[b])).expect("a way");
        if prices[cheapest] < prices[self.chosen] * (1.0 - HOLD) {
            self.chosen = cheapest;
        }
    }

    /// What `way` costs (ms, the median of its last samples), once priced.
    pub fn price(&self, way: usize) -> Option<f64> {
        let n = (self.taken[way] as usize).min(KEPT);
        if self.taken[way] < SAMPLES {
            return None;
        }
        let mut kept = self.samples[way][..n].to_vec();
        kept.sort_by(f64::total_cmp);
        Some(if n % 2 == 1 {
            kept[n / 2]
        } else {
            0.5 * (kept[n / 2 - 1] + kept[n / 2])
        })
    }

    /// Whether every way is priced (the frames take the chosen one).
    pub fn priced(&self) -> bool {
        (0..N).all(|w| self.price(w).is_some())
    }
}

/// The rows a shadow source's price covers: the map, the rays' three passes and the
/// direct light that reads their visibility (the shadow rays at reflection hits, inside
/// `rt.reflect`, are not priced: they cost alike where the reflections trace few hits).
const SHADOW_ROWS: [Row; 5] = [
    Row::ShadowMap,
    Row::ShadowClassify,
    Row::ShadowCompact,
    Row::ShadowTrace,
    Row::LightDirect,
];

/// The rows way `way` of the G-buffer (`Visibility::FIXED` order) is priced by.
const VISIBILITY_ROWS: [[Row; 1]; 2] = [[Row::GBuffer], [Row::GBufferTrace]];

/// The timer scopes way `way` of the G-buffer (`Visibility::FIXED` order) is priced by.
pub fn visibility_scopes(way: usize) -> Vec<&'static str> {
    VISIBILITY_ROWS[way]
        .iter()
        .flat_map(|r| r.scopes().iter().copied())
        .collect()
}

/// The timer scopes a shadow source is priced by.
pub fn shadow_scopes() -> Vec<&'static str> {
    SHADOW_ROWS.iter().flat_map(|r| r.scopes().iter().copied()).collect()
}

/// The frame's adaptive stages, besides the hybrid's paths: the G-buffer's ways
/// (`Visibility::FIXED`) and the shadows' (`Shadows::ADAPTIVE`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stages {
    pub visibility: Stage<2>,
    pub shadows: Stage<2>,
}

/// The ways one frame took in its adaptive stages (`None`: that stage is fixed), to
/// price once the frame has finished.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Taken {
    pub visibility: Option<usize>,
    pub shadows: Option<usize>,
}

impl Default for Stages {
    fn default() -> Self {
        // Each stage rechecks on its own frame of the 64, apart from the hybrid's
        // probe (the last one).
        Self {
            visibility: Stage::new(31),
            shadows: Stage::new(47),
        }
    }
}

impl Stages {
    /// Frame `index`'s G-buffer and shadows under `st`: each stage's way where it is
    /// adaptive (counted as taken), else the setting's.
    pub fn frame_ways(&mut self, st: &Settings, index: u32) -> (Visibility, Shadows, Taken) {
        let mut taken = Taken::default();
        let visibility = match st.visibility {
            Visibility::Adaptive => {
                let way = self.visibility.frame_way(index);
                self.visibility.count(way);
                taken.visibility = Some(way);
                Visibility::FIXED[way]
            }
            fixed => fixed,
        };
        let shadows = match st.shadows {
            Shadows::Adaptive => {
                let way = self.shadows.frame_way(index);
                self.shadows.count(way);
                taken.shadows = Some(way);
                Shadows::ADAPTIVE[way]
            }
            fixed => fixed,
        };
        (visibility, shadows, taken)
    }

    /// Whether every stage `st` makes adaptive is priced.
    pub fn priced(&self, st: &Settings) -> bool {
        (st.visibility != Visibility::Adaptive || self.visibility.priced())
            && (st.shadows != Shadows::Adaptive || self.shadows.priced())
    }

    /// After a frame that took `taken`: each adaptive stage's rows' time, where the
    /// frame's timings passed their self-check.
    pub fn take(&mut self, taken: Taken, times: &TimerReadout) {
        let ms = |rows: &[Row]| {
            let scopes = rows.iter().flat_map(|r| r.scopes().iter());
            times
                .problem
                .is_none()
                .then(|| scopes.filter_map(|&n| times.get(n)).sum::<f64>())
        };
        if let Some(way) = taken.visibility {
            self.visibility.take(way, ms(&VISIBILITY_ROWS[way]));
        }
        if let Some(way) = taken.shadows {
            self.shadows.take(way, ms(&SHADOW_ROWS));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each way is tried until priced (a slow first frame does not price it), then the
    /// cheaper is taken, and one frame in `RECHECK_EVERY` takes the other.
    #[test]
    fn ways_are_tried_then_the_cheaper_taken_and_rechecked() {
        let mut s = Stage::<2>::new(31);
        assert_eq!((s.frame_way(0), s.price(0)), (0, None));
        for ms in [40.0, 10.0] {
            s.take(0, Some(ms));
            assert_eq!(s.frame_way(2), 0, "not priced after one or two frames");
        }
        s.take(0, Some(11.0));
        assert_eq!(s.price(0), Some(11.0), "the median, not the cold first frame");
        assert_eq!(s.frame_way(3), 1, "the next way's turn");
        s.take(1, None);
        s.take(1, Some(f64::NAN));
        assert_eq!(s.price(1), None, "unchecked frames say nothing");
        for ms in [5.0, 6.0, 7.0] {
            s.take(1, Some(ms));
        }
        assert_eq!((s.chosen, s.price(1)), (1, Some(6.0)));
        assert!(s.priced());
        assert_eq!(s.frame_way(30), 1);
        assert_eq!(s.frame_way(31), 0, "the recheck frame");
        assert_eq!(s.frame_way(31 + RECHECK_EVERY), 0);
        assert_eq!(s.frame_way(32), 1);
        // The way in use grows dearer: the median follows within a few frames.
        for ms in [12.0, 12.0] {
            s.take(1, Some(ms));
            assert_eq!(s.chosen, 1, "{s:?}");
        }
        s.take(1, Some(12.0));
        assert_eq!((s.price(1), s.chosen), (Some(12.0), 0));
    }

    /// Within `HOLD` the way in use stays; beyond it the cheaper is taken; three ways
    /// are rechecked in turn.
    #[test]
    fn noise_does_not_flip_the_choice() {
        let mut s = Stage::<2>::new(0);
        for _ in 0..3 {
            s.take(0, Some(10.0));
            s.take(1, Some(10.3));
        }
        assert_eq!(s.chosen, 0);
        for ms in [9.6, 9.7, 9.5, 9.6, 9.7] {
            s.take(1, Some(ms));
            assert_eq!(s.chosen, 0, "within a sixteenth: held");
        }
        for _ in 0..3 {
            s.take(1, Some(9.2));
        }
        assert_eq!(s.chosen, 1, "{s:?}");
        let mut t = Stage::<3>::new(5);
        for w in 0..3 {
            for _ in 0..3 {
                t.take(w, Some([3.0, 1.0, 2.0][w]));
            }
        }
        assert_eq!(t.chosen, 1);
        let rechecked: Vec<usize> = (0..4).map(|k| t.frame_way(5 + k * RECHECK_EVERY)).collect();
        assert_eq!(rechecked, [2, 0, 2, 0]);
    }
}
