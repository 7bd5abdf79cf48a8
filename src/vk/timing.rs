//! GPU timing by named scope. A scope writes a timestamp at its start and its end and
//! opens a debug label of the same name, so the profiler, the command-buffer labels
//! and the timings JSON all say the same thing. No slot numbers leave this file.
//!
//! Every timestamp is followed by an execution barrier (all commands before it, all
//! commands after it), so that a timestamp marks its place in the command stream on
//! every device:
//! - on a GPU, the work recorded after a `begin` cannot start before its timestamp is
//!   written (without it, it may overlap the stamp and read short);
//! - on lavapipe (Mesa 22.3.6 and 25.0.7 alike), a timestamp is binned into llvmpipe's
//!   rasterizer scene and takes its value at the *next* flush, while compute dispatches
//!   run at once without flushing: a scope whose first command is a dispatch (as
//!   `ssr.trace`'s indirect one) read its `begin` after its own work, ~0.1 ms for ~60 ms
//!   of work, and the work fell into the gap before the scope. A barrier flushes
//!   (`finish_fence`), so each stamp resolves where it was recorded.
//!
//! The barriers order only what the frame's passes already order with their own
//! barriers, so on a GPU they cost little. Lavapipe pays for each stamp's flush: an
//! LBVH build of four stages timed stage by stage took 0.5-0.7 ms more than the same
//! build timed as one scope at 1,000 and 30,000 triangles, 1.5-4.5 ms at 200,000
//! (`bench lbvh`, which therefore times its builds whole as well:
//! `GpuTimer::outermost_only`).
//!
//! Every readout is self-checked (`check_spans`): scopes nest inside their parent and
//! follow each other in order, a parent's children cover it to within
//! `GAP_MARGIN_MS` + `GAP_MARGIN_REL` of its time, and, given the wall clock from
//! submit to fence, the outermost scope is no longer than it (on every device) and no
//! shorter by more than `WALL_MARGIN_MS` + `WALL_MARGIN_REL` (on a CPU device, where
//! nothing but the commands runs between the two). A readout that fails says why in
//! `TimerReadout::problem`. A run that can be repeated exactly (a build, a batch of
//! rays, a frame of a static scene) is measured again when its readout fails
//! (`remeasure`, at most `MEASURE_TRIES` runs): a readout spoiled by the machine (a
//! process taking the core between two stamps) is discarded and counted, and a report
//! is invalid only when every try of some run failed, the machine staying busy.

use super::barrier;
use super::context::Context;
use crate::error::{Result, VkContext};
use ash::vk;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Time outside every child that a parent scope may hold: this many ms, plus
/// `GAP_MARGIN_REL` of the parent (timestamp writes and the barriers between scopes).
pub const GAP_MARGIN_MS: f64 = 0.5;
pub const GAP_MARGIN_REL: f64 = 0.05;
/// How far the outermost scope may fall short of the wall clock from submit to fence on
/// a CPU device (submission, queue thread wake-up and fence signalling), and exceed it
/// on any device (clock rounding): this many ms plus `WALL_MARGIN_REL` of the wall time.
pub const WALL_MARGIN_MS: f64 = 2.0;
pub const WALL_MARGIN_REL: f64 = 0.10;
/// Runs of one measurement at most, the first included, before its failed self-check
/// stands (`remeasure`): a busy spell of a second or two spoils a readout or two; a
/// machine busy through four runs in a row makes the report invalid.
pub const MEASURE_TRIES: u32 = 4;
/// Slack for rounding when comparing two timestamps (ms).
const EPS_MS: f64 = 0.01;

/// One scope's interval in a readout: ms from the first timestamp, and its nesting depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub name: &'static str,
    pub begin: f64,
    pub end: f64,
    pub depth: u32,
}

/// The wall clock a readout is checked against.
#[derive(Clone, Copy, Debug)]
pub struct Wall {
    /// ms from just before the submit to just after the fence wait.
    pub ms: f64,
    /// The outermost scope must also fill the wall time: a CPU device (lavapipe) whose
    /// submission holds little but that scope (a frame).
    pub tight: bool,
}

/// Scope times of one submission, and what its self-check found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimerReadout {
    /// Milliseconds per scope, in the order they were opened.
    pub scopes: Vec<(&'static str, f64)>,
    /// Why the timestamps cannot be trusted; `None` when every check passed.
    pub problem: Option<String>,
}

impl TimerReadout {
    /// The milliseconds of scope `name` (the first, if it ran more than once).
    pub fn get(&self, name: &str) -> Option<f64> {
        self.scopes.iter().find(|(n, _)| *n == name).map(|s| s.1)
    }
}

impl std::ops::Deref for TimerReadout {
    type Target = [(&'static str, f64)];
    fn deref(&self) -> &Self::Target {
        &self.scopes
    }
}

/// Checks that `spans` (in the order they were opened) nest, follow each other and
/// add up, and agree with the wall clock of their submission; returns the first
/// disagreement, naming the scopes and the times.
pub fn check_spans(spans: &[Span], wall: Option<Wall>) -> Option<String> {
    for (i, s) in spans.iter().enumerate() {
        // NaN fails too: a stamp that is no number cannot be trusted.
        if s.end.is_nan() || s.begin.is_nan() || s.end < s.begin - EPS_MS {
            return Some(format!(
                "scope {} ends {:.3} ms before it begins",
                s.name,
                s.begin - s.end
            ));
        }
        // The parent: the last scope opened before this one, one level up.
        let parent = spans[..i].iter().rev().find(|p| p.depth + 1 == s.depth);
        if let Some(p) = parent {
            if s.begin < p.begin - EPS_MS || s.end > p.end + EPS_MS {
                return Some(format!(
                    "scope {} ({:.3}..{:.3} ms) lies outside its parent {} ({:.3}..{:.3} ms)",
                    s.name, s.begin, s.end, p.name, p.begin, p.end
                ));
            }
        }
    }
    for (i, p) in spans.iter().enumerate() {
        // Direct children: the scopes after it one level down, until its level recurs.
        let children: Vec<&Span> = spans[i + 1..]
            .iter()
            .take_while(|c| c.depth > p.depth)
            .filter(|c| c.depth == p.depth + 1)
            .collect();
        if children.is_empty() {
            continue;
        }
        // Gaps: before the first child, between siblings, after the last child.
        let mut edge = (p.begin, "the start of ".to_string() + p.name);
        let (mut gaps, mut largest) = (0.0, (0.0, String::new()));
        for c in &children {
            if c.begin < edge.0 - EPS_MS {
                return Some(format!(
                    "scope {} begins {:.3} ms before {} ends",
                    c.name,
                    edge.0 - c.begin,
                    edge.1
                ));
            }
            let gap = (c.begin - edge.0).max(0.0);
            gaps += gap;
            if gap > largest.0 {
                largest = (gap, format!("before {}", c.name));
            }
            edge = (c.end, c.name.to_string());
        }
        let tail = (p.end - edge.0).max(0.0);
        gaps += tail;
        if tail > largest.0 {
            largest = (tail, format!("after {}", edge.1));
        }
        let duration = p.end - p.begin;
        if gaps > GAP_MARGIN_MS + GAP_MARGIN_REL * duration {
            return Some(format!(
                "{gaps:.3} ms of scope {} ({duration:.3} ms) fall outside its {} inner scopes \
                 (the most, {:.3} ms, {}): a timestamp did not mark its place",
                p.name,
                children.len(),
                largest.0,
                largest.1
            ));
        }
    }
    if let (Some(w), Some(root)) = (wall, spans.first()) {
        let duration = root.end - root.begin;
        let margin = WALL_MARGIN_MS + WALL_MARGIN_REL * w.ms;
        if duration > w.ms + margin {
            return Some(format!(
                "scope {} reads {duration:.3} ms, longer than the {:.3} ms from submit to fence",
                root.name, w.ms
            ));
        }
        if w.tight && duration < w.ms - margin {
            return Some(format!(
                "scope {} reads {duration:.3} ms of the {:.3} ms from submit to fence on a CPU device",
                root.name, w.ms
            ));
        }
    }
    None
}

/// Timestamp queries for one command buffer in flight.
pub struct GpuTimer {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    capacity: u32,
    /// (name, first query, depth) of every scope recorded since the last reset.
    scopes: Vec<(&'static str, u32, u32)>,
    /// The open scopes' indices in `scopes`, `UNTIMED` for one not stamped.
    open: Vec<usize>,
    /// Only the outermost scopes are stamped (`outermost_only`).
    outermost_only: bool,
}

/// An open scope that writes no timestamps (`GpuTimer::outermost_only`).
const UNTIMED: usize = usize::MAX;

impl GpuTimer {
    /// Room for `max_scopes` scopes per frame.
    pub fn new(ctx: &Arc<Context>, max_scopes: u32) -> Result<Self> {
        let capacity = max_scopes * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(pool, "timer.queries");
        Ok(Self {
            ctx: ctx.clone(),
            pool,
            capacity,
            scopes: Vec::new(),
            open: Vec::new(),
            outermost_only: false,
        })
    }

    /// Whether scopes opened inside another are stamped from now on (they are by
    /// default): a work timed whole without its stages' stamps (and their barriers),
    /// which cost a CPU device as much as a small stage.
    pub fn outermost_only(&mut self, on: bool) {
        self.outermost_only = on;
    }

    /// Starts a frame: forgets earlier scopes and resets the queries on the GPU.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.scopes.clear();
        self.open.clear();
        unsafe { self.ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
    }

    /// Opens scope `name` (scopes nest).
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &'static str) {
        if self.outermost_only && !self.open.is_empty() {
            self.open.push(UNTIMED);
            return;
        }
        let first = self.scopes.len() as u32 * 2;
        assert!(
            first + 2 <= self.capacity,
            "GpuTimer: more than {} scopes in a frame",
            self.capacity / 2
        );
        if let Some(du) = &self.ctx.debug_utils {
            let cname = std::ffi::CString::new(name).expect("scope names have no NUL");
            let label = vk::DebugUtilsLabelEXT::default().label_name(&cname);
            unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
        }
        self.stamp(cmd, first);
        let depth = self.open.len() as u32;
        self.open.push(self.scopes.len());
        self.scopes.push((name, first, depth));
    }

    /// Closes the innermost scope, which must be `name`.
    pub fn end(&mut self, cmd: vk::CommandBuffer, name: &'static str) {
        let i = self.open.pop().expect("GpuTimer::end without begin");
        if i == UNTIMED {
            return;
        }
        assert_eq!(self.scopes[i].0, name, "GpuTimer scopes closed out of order");
        self.stamp(cmd, self.scopes[i].1 + 1);
        if let Some(du) = &self.ctx.debug_utils {
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Writes timestamp `query` once every earlier command has finished, and keeps every
    /// later command from starting before it (see the module docs for why both).
    fn stamp(&self, cmd: vk::CommandBuffer, query: u32) {
        let all = (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::NONE);
        unsafe {
            self.ctx
                .device
                .cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, query)
        };
        // Execution only: the stamp resolves here, and nothing later overlaps it.
        barrier::global(&self.ctx.device, cmd, all, all);
    }

    /// Records `record` inside scope `name`.
    pub fn scope<R>(&mut self, cmd: vk::CommandBuffer, name: &'static str, record: impl FnOnce() -> R) -> R {
        self.begin(cmd, name);
        let r = record();
        self.end(cmd, name);
        r
    }

    /// Records `record` after a reset of the queries into a one-time command buffer,
    /// submits it and waits, and reads the scopes back, checked against the wall clock
    /// of the whole call as an upper bound (for builds, refits and ray batches).
    pub fn one_shot(&mut self, record: impl FnOnce(vk::CommandBuffer, &mut GpuTimer)) -> Result<TimerReadout> {
        let ctx = self.ctx.clone();
        let start = std::time::Instant::now();
        ctx.one_shot(|cmd| {
            self.reset(cmd);
            record(cmd, self);
        })?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        self.read(Some(Wall { ms, tight: false }))
    }

    /// Milliseconds of every scope of the last frame; call after its fence signalled.
    pub fn results(&self) -> Result<Vec<(&'static str, f64)>> {
        Ok(self.read(None)?.scopes)
    }

    /// Every scope of the last submission and its self-check (`check_spans`), against
    /// `wall` when given; call after its fence signalled.
    pub fn read(&self, wall: Option<Wall>) -> Result<TimerReadout> {
        let n = self.scopes.len() * 2;
        if n == 0 {
            return Ok(TimerReadout::default());
        }
        let mut raw = vec![0u64; n];
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let bits = self.ctx.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let period = self.ctx.timestamp_period_ns;
        // Only the low `bits` bits count; differences wrap modulo 2^bits, so every time is
        // taken relative to the first stamp.
        let ms = |q: u32| ((raw[q as usize] & mask).wrapping_sub(raw[0] & mask) & mask) as f64 * period * 1e-6;
        let spans: Vec<Span> = self
            .scopes
            .iter()
            .map(|&(name, q, depth)| Span {
                name,
                begin: ms(q),
                end: ms(q + 1),
                depth,
            })
            .collect();
        Ok(TimerReadout {
            scopes: spans.iter().map(|s| (s.name, s.end - s.begin)).collect(),
            problem: check_spans(&spans, wall),
        })
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}

/// Runs `run`, a measurement that does the same work each time, until its readout
/// passes the self-check or `MEASURE_TRIES` runs were made; returns the last run's
/// value and readout, and how many failed readouts were discarded before it.
pub fn remeasure<T>(mut run: impl FnMut() -> Result<(T, TimerReadout)>) -> Result<(T, TimerReadout, u32)> {
    let mut discarded = 0;
    loop {
        let (value, readout) = run()?;
        if readout.problem.is_none() || discarded + 1 >= MEASURE_TRIES {
            return Ok((value, readout, discarded));
        }
        discarded += 1;
    }
}

/// `remeasure` for a measurement that yields only its readout: the last readout, and
/// how many failed readouts were discarded before it.
pub fn remeasure_readout(mut run: impl FnMut() -> Result<TimerReadout>) -> Result<(TimerReadout, u32)> {
    let ((), readout, discarded) = remeasure(|| Ok(((), run()?)))?;
    Ok((readout, discarded))
}

/// Per-scope samples over many frames; reports medians.
#[derive(Default, Debug, Clone)]
pub struct Timings {
    samples: BTreeMap<&'static str, Vec<f64>>,
    check: TimingCheck,
}

/// The self-check of every readout behind a set of timings, as reports carry it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TimingCheck {
    /// No readout failed (`check_spans`): the timings may be published.
    pub valid: bool,
    /// Readouts checked, and how many of them failed (after their re-measurements).
    pub checked: u32,
    pub failed: u32,
    /// Readouts that failed the self-check and were measured again (`remeasure`),
    /// not counted in `checked`: how busy the machine was.
    pub discarded: u32,
    /// The first failure's reason; `null` when valid.
    pub reason: Option<String>,
}

impl Default for TimingCheck {
    fn default() -> Self {
        Self {
            valid: true,
            checked: 0,
            failed: 0,
            discarded: 0,
            reason: None,
        }
    }
}

impl TimingCheck {
    /// Counts one readout's check.
    pub fn add(&mut self, problem: Option<&str>) {
        self.checked += 1;
        if let Some(p) = problem {
            self.failed += 1;
            self.valid = false;
            self.reason.get_or_insert_with(|| p.to_string());
        }
    }

    /// Counts one readout measured with `remeasure`: its check, and the failed
    /// readouts discarded before it.
    pub fn add_measured(&mut self, problem: Option<&str>, discarded: u32) {
        self.add(problem);
        self.discarded += discarded;
    }

    /// Both checks together.
    pub fn merge(&mut self, other: &TimingCheck) {
        self.checked += other.checked;
        self.failed += other.failed;
        self.discarded += other.discarded;
        self.valid &= other.valid;
        if self.reason.is_none() {
            self.reason = other.reason.clone();
        }
    }

    /// One line for text output: `None` when valid.
    pub fn warning(&self) -> Option<String> {
        (!self.valid).then(|| {
            format!(
                "timings invalid on {} of {} frames ({} re-measured first): {}",
                self.failed,
                self.checked,
                self.discarded,
                self.reason.as_deref().unwrap_or("?")
            )
        })
    }
}

/// Several checks as one (a report's cases or modes, renderers run together).
impl<'a> FromIterator<&'a TimingCheck> for TimingCheck {
    fn from_iter<I: IntoIterator<Item = &'a TimingCheck>>(checks: I) -> Self {
        checks.into_iter().fold(TimingCheck::default(), |mut all, c| {
            all.merge(c);
            all
        })
    }
}

impl Timings {
    /// Adds one checked readout: its scopes (as `add_frame`) and its self-check.
    pub fn add(&mut self, readout: &TimerReadout) {
        self.add_measured(readout, 0);
    }

    /// `add` for a readout of `remeasure`, with the failed readouts discarded before it.
    pub fn add_measured(&mut self, readout: &TimerReadout, discarded: u32) {
        self.add_frame(&readout.scopes);
        self.check.add_measured(readout.problem.as_deref(), discarded);
    }

    /// The self-check of every readout added with `add`.
    pub fn check(&self) -> &TimingCheck {
        &self.check
    }

    /// The self-checks of several runs' timings together.
    pub fn check_all(timings: &[Timings]) -> TimingCheck {
        timings.iter().map(Timings::check).collect()
    }

    /// Adds one frame's scopes (a scope seen twice in a frame is summed), unchecked.
    pub fn add_frame(&mut self, frame: &[(&'static str, f64)]) {
        let mut sums: BTreeMap<&'static str, f64> = BTreeMap::new();
        for &(name, ms) in frame {
            *sums.entry(name).or_default() += ms;
        }
        for (name, ms) in sums {
            self.samples.entry(name).or_default().push(ms);
        }
    }

    /// The samples of scope `name` (milliseconds, in frame order), if it was timed.
    pub fn samples(&self, name: &str) -> Option<&[f64]> {
        self.samples.get(name).map(|v| v.as_slice())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remeasure_discards_failed_readouts_up_to_its_tries() {
        let readout = |ok: bool| TimerReadout {
            scopes: vec![("a", 1.0)],
            problem: (!ok).then(|| "gap".to_string()),
        };
        // Fails twice, then passes: the third run's value, two discarded.
        let mut runs = 0;
        let (v, r, discarded) = remeasure(|| {
            runs += 1;
            Ok((runs, readout(runs > 2)))
        })
        .unwrap();
        assert_eq!((v, r.problem, discarded), (3, None, 2));
        // Never passes: MEASURE_TRIES runs, the failure stands.
        let mut runs = 0;
        let (v, r, discarded) = remeasure(|| {
            runs += 1;
            Ok((runs, readout(false)))
        })
        .unwrap();
        assert_eq!((v, discarded), (MEASURE_TRIES, MEASURE_TRIES - 1));
        assert!(r.problem.is_some());
        let mut check = TimingCheck::default();
        check.add_measured(r.problem.as_deref(), discarded);
        check.add_measured(None, 1);
        assert_eq!(
            (check.valid, check.checked, check.failed, check.discarded),
            (false, 2, 1, MEASURE_TRIES)
        );
    }

    #[test]
    fn timings_sum_repeated_scopes_within_a_frame() {
        let mut t = Timings::default();
        t.add_frame(&[("a", 1.0), ("b", 2.0), ("a", 0.5)]);
        t.add_frame(&[("a", 3.0), ("b", 4.0)]);
        t.add_frame(&[("a", 2.0), ("b", 3.0)]);
        assert_eq!(t.samples("a"), Some(&[1.5, 3.0, 2.0][..]));
        assert_eq!(t.samples("b"), Some(&[2.0, 4.0, 3.0][..]));
        assert_eq!(t.samples("c"), None);
    }
}
