//! What the adaptive hybrid measures of this device, from the frame's own self-checked
//! timestamps (`exchange_rate = 0`).
//!
//! The exchange rate: what a march costs in traced rays. Each marching frame copies
//! its counts — pixels marched (`ssr.trace`'s list) and rays traced (`rt.reflect`'s) —
//! into its slot's host-visible buffer; when the frame has finished, its timings
//! passed their self-check and most of its marches were SSR-first tiles' (not probes),
//! (`ssr.trace` ms / marched) over (`rt.reflect` ms / rays) joins a running mean (one
//! part in five). The rate the tiles use (in 1/`TILE_ONE`, 1/256 to 16 rays) takes the
//! first sample at once and then moves only once the mean has left it by more than an
//! eighth of itself (`RATE_HOLD`), so timing noise does not flip tiles from frame to
//! frame, and a GPU's march at 1/18 of a ray is held as steadily as lavapipe's at 0.86.
//!
//! The paths (`Paths`): the tiles weigh a march against a ray pixel by pixel, but
//! marching at all has a price of its own — the pyramid, the classification's SSR
//! work, the seams' blur — that no tile sees. So the frames' reflection rows are timed
//! on both paths, marching with the tiles and idle (every tile rays-only, without
//! probes: no pyramid, no march), and the frames take the cheaper. While idle, a
//! probe frame marches with the tiles to measure them and ends every marched pixel as
//! the idle path would (`FramePath::measures_only`): its image is the idle path's, and
//! the marching path's price is estimated from it (`march_estimate`).

use crate::error::Result;
use crate::shader_defines::TILE_ONE;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, TimerReadout};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Fewer marched pixels or traced rays than this in a frame say nothing of their
/// costs (a dispatch's fixed cost would dominate).
const MIN_COUNT: u32 = 1000;

/// The part of itself the measured mean must leave the rate in use by to move it.
const RATE_HOLD: f64 = 1.0 / 8.0;

/// The measured rate and the one in use (1/`TILE_ONE`; 0 until the first sample: every
/// tile SSR-first).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExchangeRate {
    pub estimate: Option<f64>,
    pub applied: u32,
}

impl ExchangeRate {
    /// Takes one frame's costs: `ssr_ms` over `marched` pixels, `rt_ms` over `rays`.
    pub fn add(&mut self, (ssr_ms, marched): (f64, u32), (rt_ms, rays): (f64, u32)) {
        if marched < MIN_COUNT || rays < MIN_COUNT || !(ssr_ms > 0.0 && rt_ms > 0.0) {
            return;
        }
        let sample = (ssr_ms / marched as f64) / (rt_ms / rays as f64);
        let estimate = self.estimate.map_or(sample, |e| 0.8 * e + 0.2 * sample);
        self.estimate = Some(estimate);
        let scaled = (estimate * TILE_ONE as f64).clamp(1.0, 16.0 * TILE_ONE as f64);
        let applied = self.applied as f64;
        // Half a unit at least: a rate that rounds to the one in use does not move it.
        if self.applied == 0 || (scaled - applied).abs() > (RATE_HOLD * applied).max(0.5) {
            self.applied = scaled.round() as u32;
        }
    }

    /// The rate in use as a fraction (a march's cost in rays).
    pub fn fraction(&self) -> f64 {
        self.applied as f64 / TILE_ONE as f64
    }
}

/// One priced frame in this many also runs an idle path (marching, each in turn;
/// idle, the other) to price it, so the idle paths' prices stay current; the frame
/// shows its own path (it pays for both: 1/64 of an idle path's reflection rows more a
/// frame on average).
pub const RECHECK_EVERY: u32 = 64;

/// The adaptive hybrid's probe frames while the frames take an idle path: one frame
/// in 7 at the most (odd, so coprime with the probes' 16 phases: each probe pixel
/// comes in turn), and while the paths are priced, fewer: as many frames as keep the
/// probe frames' extra cost over the idle path within `PROBE_BUDGET` of a frame, up
/// to one in `PROBE_EVERY_MAX`.
pub const PROBE_EVERY: u32 = 7;
pub const PROBE_EVERY_MAX: u32 = 31;
/// What staying ready to march again may cost while idle: 1% of a frame.
pub const PROBE_BUDGET: f64 = 0.01;

/// The part of its price by which another path must undercut the frames' path to
/// take over: paths priced within the noise do not alternate (each change of path
/// changes the image), at a cost of at most 3% of the reflection rows.
pub const PATH_HOLD: f64 = 0.03;

/// Frames between probe frames (odd, `PROBE_EVERY` to `PROBE_EVERY_MAX`) for a probe
/// frame costing `extra_ms` more than an idle one, in frames of `frame_ms`.
pub fn probe_interval(extra_ms: f64, frame_ms: f64) -> u32 {
    let frames = (extra_ms.max(0.0) / (PROBE_BUDGET * frame_ms)).ceil();
    let frames = if frames.is_finite() {
        frames.min(PROBE_EVERY_MAX as f64) as u32
    } else {
        PROBE_EVERY_MAX
    };
    (frames | 1).clamp(PROBE_EVERY, PROBE_EVERY_MAX)
}

/// Takes a finished frame into the exchange rate and the paths' prices, as `recorded`
/// says it ran: a frame whose timings passed their self-check prices its path (the sum
/// of `reflection_scopes`), a probe frame that only measured prices the marching path
/// by `march_estimate`; a marching one whose marches were mostly the SSR-first tiles'
/// prices a march in rays (the rays-only tiles' probes, a sixteenth of their pixels
/// scattered over the screen, march dearer than whole tiles do).
pub fn take_frame<'a>(
    (exchange, paths): (&mut ExchangeRate, &mut Paths),
    recorded: Recorded,
    times: &TimerReadout,
    (frame_scope, reflection_scopes): (&str, impl Iterator<Item = &'a str>),
) {
    let checked = times.problem.is_none();
    let reflection_ms = checked.then(|| reflection_scopes.filter_map(|s| times.get(s)).sum::<f64>());
    if let Some(ms) = times.get(frame_scope).filter(|_| checked) {
        paths.frame_ms = Some(running_mean(paths.frame_ms, ms));
    }
    // A recheck priced an idle path (its rows and the frame's glossy filter, which
    // every path runs alike) before the choice below.
    if let Some(idle) = recorded.path().rechecks {
        let denoise = times.get(crate::passes::reflect_denoise::NAME).unwrap_or(0.0);
        let recheck = times.get(crate::renderer::table::RECHECK).filter(|_| checked);
        paths.idled(idle, recheck.map(|ms| ms + denoise));
    }
    match recorded {
        Recorded::March {
            rate,
            priced,
            path,
            counts,
        } => {
            let [marched, rays, ssr_first, answered] = counts;
            let ms = |name| times.get(name).unwrap_or(0.0);
            let (rt_ms, merge_ms) = (
                ms(crate::passes::rt_reflect::NAME),
                ms(crate::passes::reflect_merge::NAME),
            );
            let march_ms = match path.shows {
                Path::March => {
                    if reflection_ms.is_some() {
                        paths.merge_ms = Some(running_mean(paths.merge_ms, merge_ms));
                    }
                    reflection_ms
                }
                _ => {
                    if let Some(probe) = reflection_ms {
                        paths.probe_ms = Some(running_mean(paths.probe_ms, probe));
                    }
                    reflection_ms.map(|r| march_estimate(r, (rt_ms, rays, answered), (merge_ms, paths.merge_ms)))
                }
            };
            paths.marched(ssr_first, march_ms, rate, priced);
            if checked && 2 * ssr_first as u64 >= marched as u64 {
                let ssr = (ms(crate::passes::ssr_trace::NAME), marched);
                exchange.add(ssr, (rt_ms, rays));
            }
        }
        Recorded::Idle(path) => paths.idled(path.runs, reflection_ms),
    }
}

/// The marching path's reflection rows (ms) from a probe frame that only measured
/// (`reflection_ms`): it traced every pixel its SSR-first tiles marched, the marching
/// path traces none that SSR answered (`answered` of its `rays`, at the frame's mean
/// cost a ray), and it blurred no seams (its `reflect.merge`, `merge.0`, replaced by
/// the marching frames' mean, `merge.1`, where there is one).
pub fn march_estimate(reflection_ms: f64, (rt_ms, rays, answered): (f64, u32, u32), merge: (f64, Option<f64>)) -> f64 {
    let saved = if rays > 0 {
        rt_ms * answered.min(rays) as f64 / rays as f64
    } else {
        0.0
    };
    (reflection_ms - saved - merge.0 + merge.1.unwrap_or(merge.0)).max(0.0)
}

/// The paths' running means: `mean` joined by `sample` one part in four (the sample
/// whole when there is no mean yet).
fn running_mean(mean: Option<f64>, sample: f64) -> f64 {
    mean.map_or(sample, |m| 0.75 * m + 0.25 * sample)
}

/// A path an adaptive hybrid frame takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The tiles split the pixels: SSR-first tiles march (`ssr.hiz`, `ssr.trace`),
    /// rays-only tiles send theirs to the rays but for their probes.
    March,
    /// No pyramid, no march: every tile as if rays-only without probes
    /// (`Classify::SkipAll`); a pixel whose own reflection weighs little is left
    /// untraced as the hybrid leaves it.
    SkipMarch,
    /// No pyramid, no march: the `rt` mode's classification (`Classify::MaskOnly`),
    /// cheaper than the tiles' but every reflective pixel traced.
    TraceAll,
}

impl Path {
    pub const ALL: [Path; 3] = [Path::March, Path::SkipMarch, Path::TraceAll];

    pub fn name(self) -> &'static str {
        match self {
            Path::March => "march",
            Path::SkipMarch => "skip_march",
            Path::TraceAll => "trace_all",
        }
    }
}

/// The path a frame runs and the one its image is: the same but for a probe frame while
/// idle, which runs the marching path to measure the tiles and shows the idle path
/// (every pixel its tiles marched ends as on that path: traced, or left untraced for
/// its block on `SkipMarch`; no seams blurred).
/// A frame may also run an idle path before its own, to price it without showing it
/// (`rechecks`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePath {
    pub runs: Path,
    pub shows: Path,
    pub rechecks: Option<Path>,
}

impl FramePath {
    /// A frame that shows the path it runs.
    pub const fn plain(path: Path) -> Self {
        Self {
            runs: path,
            shows: path,
            rechecks: None,
        }
    }

    /// A probe frame while idle on `idle`: it marches and shows `idle`.
    pub const fn probe(idle: Path) -> Self {
        Self {
            runs: Path::March,
            shows: idle,
            rechecks: None,
        }
    }

    /// A frame on `path` that also runs idle path `idle` first, to price it.
    pub const fn recheck(path: Path, idle: Path) -> Self {
        Self {
            rechecks: Some(idle),
            ..Self::plain(path)
        }
    }

    /// A probe frame while idle: it marches only to measure.
    pub fn measures_only(self) -> bool {
        self.runs != self.shows
    }
}

/// Which path the adaptive hybrid's frames take, and what each has cost. On an idle
/// path (`SkipMarch`, `TraceAll`) frames run it until the next probe frame (one in
/// `probe_every`), which marches with the tiles, shows the idle path (`FramePath`)
/// and chooses anew.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paths {
    /// The path of the frames until the next probe frame.
    pub next: Path,
    /// Each path's reflection rows, ms, a running mean (one part in four), in
    /// `Path::ALL` order. The marching path's is over frames at one exchange rate,
    /// `march_rate` (a new rate splits the tiles anew: its mean starts again).
    pub ms: [Option<f64>; 3],
    pub march_rate: u32,
    /// Frames recorded on each path since the last reset, in `Path::ALL` order (the
    /// path each frame showed), and the probe frames among the idle ones (they ran the
    /// marching path to measure).
    pub frames: [u64; 3],
    pub probes: u64,
    /// The marching frames' `reflect.merge`, ms, a running mean (one part in four): its
    /// seams' blur, which a probe frame that only measures does not run.
    pub merge_ms: Option<f64>,
    /// The probe frames' reflection rows while idle, ms, a running mean (one part in
    /// four): what a probe frame costs (it marches and traces every pixel).
    pub probe_ms: Option<f64>,
    /// Frames between probe frames while idle (`probe_interval`), and the whole
    /// frame's ms, a running mean (one part in four), it is measured against.
    pub probe_every: u32,
    pub frame_ms: Option<f64>,
    /// The index of the last frame that ran the march (a probe frame's included):
    /// while idle, the next probe frame comes `probe_every` frames after it.
    pub last_march: u32,
}

impl Default for Paths {
    fn default() -> Self {
        Self {
            next: Path::March,
            ms: [None; 3],
            march_rate: 0,
            frames: [0; 3],
            probes: 0,
            merge_ms: None,
            probe_ms: None,
            probe_every: PROBE_EVERY,
            frame_ms: None,
            last_march: 0,
        }
    }
}

impl Paths {
    /// The path of frame `index`; `priced`: chosen by the paths' costs (a measured
    /// exchange rate), else idle only while no SSR-first tile marches. Priced, a frame
    /// in `RECHECK_EVERY` also runs an idle path before its own, so the idle paths'
    /// prices stay current, and shows its own: marching, each idle path in turn; idle,
    /// the other idle path (the marching path is priced by the probe frames). While
    /// idle, the frame `probe_every` frames after the last that marched is a probe
    /// frame: it runs the marching path and shows the idle one.
    pub fn frame_path(&self, index: u32, priced: bool) -> FramePath {
        let recheck = priced && index % RECHECK_EVERY == RECHECK_EVERY - 1;
        match self.next {
            Path::March if recheck => FramePath::recheck(
                Path::March,
                [Path::SkipMarch, Path::TraceAll][(index / RECHECK_EVERY % 2) as usize],
            ),
            Path::March => FramePath::plain(Path::March),
            idle if index.wrapping_sub(self.last_march) >= self.probe_every => FramePath::probe(idle),
            Path::SkipMarch if recheck => FramePath::recheck(Path::SkipMarch, Path::TraceAll),
            Path::TraceAll if recheck => FramePath::recheck(Path::TraceAll, Path::SkipMarch),
            idle => FramePath::plain(idle),
        }
    }

    /// Counts frame `index`, on `path`, among the paths taken.
    pub fn count(&mut self, path: FramePath, index: u32) {
        self.frames[path.shows as usize] += 1;
        self.probes += path.measures_only() as u64;
        if path.runs == Path::March {
            self.last_march = index;
        }
    }

    /// After a marching frame at exchange rate `rate`: the pixels its SSR-first tiles
    /// marched, and its reflection rows' ms (a probe frame's estimate of them) if its
    /// timings passed their self-check.
    /// Not priced: `SkipMarch` when no SSR-first tile marched, else `March`. Priced:
    /// an idle path not priced yet is tried (until the next probe frame; `TraceAll`
    /// first), else the cheapest path is taken (an idle one when no SSR-first tile
    /// marched), but the frames' path is kept while the cheapest undercuts it by no
    /// more than `PATH_HOLD` of its price.
    pub fn marched(&mut self, ssr_first: u32, ms: Option<f64>, rate: u32, priced: bool) {
        if let Some(ms) = ms {
            let mean = self.ms[0].filter(|_| self.march_rate == rate);
            self.ms[0] = Some(running_mean(mean, ms));
            self.march_rate = rate;
        }
        let idle_only = ssr_first == 0;
        self.next = if !priced {
            if idle_only {
                Path::SkipMarch
            } else {
                Path::March
            }
        } else if let Some(unpriced) = [Path::TraceAll, Path::SkipMarch]
            .into_iter()
            .find(|&p| self.price(p).is_none())
        {
            // The `rt` mode's path first: trying it costs nothing against `rt`.
            unpriced
        } else {
            let allowed = |p: Path| !(idle_only && p == Path::March);
            let cost = |p: Path| self.price(p).unwrap_or(f64::INFINITY);
            let cheapest = (Path::ALL.into_iter().filter(|&p| allowed(p)))
                .min_by(|&a, &b| cost(a).total_cmp(&cost(b)))
                .expect("two idle paths");
            let current = self.next;
            let holds = allowed(current) && cost(cheapest) >= (1.0 - PATH_HOLD) * cost(current);
            if holds {
                current
            } else {
                cheapest
            }
        };
        // Idle and priced: probe frames no more often than their cost allows (a probe
        // frame's own, where one has been measured, else the marching path's).
        let probe = self.probe_ms.or(self.price(Path::March));
        self.probe_every = match (self.next, probe, self.frame_ms) {
            (Path::March, ..) => PROBE_EVERY,
            (idle, Some(probe), Some(frame)) if priced => {
                probe_interval(probe - self.price(idle).unwrap_or(probe), frame)
            }
            _ => PROBE_EVERY,
        };
    }

    /// After a frame on idle path `path`: its reflection rows' ms if its timings
    /// passed their self-check.
    pub fn idled(&mut self, path: Path, ms: Option<f64>) {
        if let Some(ms) = ms {
            let mean = &mut self.ms[path as usize];
            *mean = Some(running_mean(*mean, ms));
        }
    }

    /// What `path` has cost (ms of the reflection rows), if measured.
    pub fn price(&self, path: Path) -> Option<f64> {
        self.ms[path as usize]
    }
}

/// What a frame slot's last frame was, for the adaptive hybrid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Recorded {
    /// A marching hybrid frame at exchange rate `rate`, `priced` by the paths' costs,
    /// on `path` (it shows `Path::March`, or an idle path: a probe frame that only
    /// measured; it may have rechecked an idle path); `counts`: pixels marched, rays
    /// traced, pixels marched in SSR-first tiles and those of them SSR answered.
    March {
        rate: u32,
        priced: bool,
        path: FramePath,
        counts: [u32; 4],
    },
    /// A frame of the adaptive hybrid on an idle path (`runs`), perhaps having
    /// rechecked the other.
    Idle(FramePath),
}

impl Recorded {
    /// The path the frame ran, showed and rechecked.
    pub fn path(&self) -> FramePath {
        match *self {
            Recorded::March { path, .. } | Recorded::Idle(path) => path,
        }
    }
}

/// One frame slot's counts, read back after its frame: pixels marched, rays traced,
/// pixels marched in SSR-first tiles (the rest were probes), and those SSR answered.
pub struct FrameCounts {
    buffer: Buffer,
    /// What the slot's last frame recorded (`counts` still to read).
    recorded: Option<Recorded>,
}

impl FrameCounts {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        Ok(Self {
            buffer: Buffer::new(ctx, "frame.counts", 16, usage, MemoryLocation::GpuToCpu)?,
            recorded: None,
        })
    }

    /// Notes a frame on idle path `path.runs` (nothing to copy), and its recheck.
    pub fn record_idle(&mut self, path: FramePath) {
        self.recorded = Some(Recorded::Idle(path));
    }

    /// Records the copies of the march list's length (word 3 of `march_args`), the ray
    /// list's (word 3 of `ray_args`), the SSR-first tiles' marches and answers (words 0
    /// and 1 of `ssr_first`), after the passes that wrote them; the words end free for
    /// the next frame's writers and visible to the host. `path`: the path the frame's
    /// image is, and the one it rechecked.
    pub fn record(
        &mut self,
        (device, cmd): (&ash::Device, vk::CommandBuffer),
        [march_args, ray_args, ssr_first]: [&Buffer; 3],
        (rate, priced, path): (u32, bool, FramePath),
    ) {
        barrier::global(device, cmd, access::COMPUTE_WRITE, access::TRANSFER_READ);
        for (src, from, at, size) in [(march_args, 12, 0, 4), (ray_args, 12, 4, 4), (ssr_first, 0, 8, 8)] {
            let region = vk::BufferCopy::default().src_offset(from).dst_offset(at).size(size);
            // SAFETY: both buffers are live and large enough; the barrier above orders the copy.
            unsafe { device.cmd_copy_buffer(cmd, src.raw, self.buffer.raw, &[region]) };
        }
        barrier::record(
            device,
            cmd,
            &[
                barrier::memory(access::TRANSFER_READ, access::ALL_READ_WRITE),
                barrier::memory(access::TRANSFER_WRITE, access::HOST_READ),
            ],
            &[],
        );
        self.recorded = Some(Recorded::March {
            rate,
            priced,
            path,
            counts: [0; 4],
        });
    }

    /// What the slot's finished frame recorded, its counts read.
    pub fn take(&mut self) -> Option<Recorded> {
        match self.recorded.take()? {
            Recorded::March { rate, priced, path, .. } => {
                let words: Vec<u32> = bytemuck::pod_collect_to_vec(&self.buffer.mapped()?[..16]);
                let counts = [words[0], words[1], words[2], words[3]];
                Some(Recorded::March {
                    rate,
                    priced,
                    path,
                    counts,
                })
            }
            idle => Some(idle),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Probe frames come one in 7 at the most, fewer as they cost more against the
    /// idle path (within 1% of a frame), odd, and one in 31 at the least.
    #[test]
    fn probe_frames_thin_out_as_they_cost_more() {
        assert_eq!(probe_interval(0.0, 100.0), 7);
        assert_eq!(probe_interval(-3.0, 100.0), 7);
        assert_eq!(probe_interval(10.0, 100.0), 11, "10 frames, made odd");
        assert_eq!(probe_interval(14.5, 100.0), 15);
        assert_eq!(probe_interval(50.0, 100.0), 31);
        assert_eq!(probe_interval(1.0, 0.0), 31);
        let mut p = Paths {
            ms: [Some(60.0), Some(45.0), Some(50.0)],
            frame_ms: Some(100.0),
            ..Paths::default()
        };
        p.marched(500, None, 0, true);
        assert_eq!((p.next, p.probe_every), (Path::SkipMarch, 15));
        let probe = FramePath::probe(Path::SkipMarch);
        assert!(p.frame_path(15, true) == probe && p.frame_path(7, true) == FramePath::plain(Path::SkipMarch));
        assert!(probe.measures_only() && !FramePath::plain(Path::March).measures_only());
        p.marched(500, None, 0, false);
        assert_eq!((p.next, p.probe_every), (Path::March, PROBE_EVERY));
        // A probe frame's own cost, once measured, sets the interval: 70 ms against
        // SkipMarch's 45 is 25 frames of 1%.
        p.probe_ms = Some(70.0);
        p.marched(500, None, 0, true);
        assert_eq!((p.next, p.probe_every), (Path::SkipMarch, 25));
    }

    /// Priced, the paths are tried (`TraceAll` first, each until the next probe frame)
    /// and the cheapest taken; marching, one frame in `RECHECK_EVERY` takes an idle
    /// path; a new rate starts the march's mean again; without a march to pay for
    /// (no SSR-first tile) the marching path is not taken however cheap it was.
    #[test]
    fn the_paths_are_tried_then_the_cheapest_taken() {
        let mut p = Paths::default();
        assert_eq!(p.frame_path(1, true).runs, Path::March);
        p.marched(500, Some(30.0), 64, true);
        assert_eq!(p.next, Path::TraceAll, "untried: the rt mode's path first");
        assert_eq!(
            (p.frame_path(1, true).runs, p.frame_path(PROBE_EVERY, true)),
            (Path::TraceAll, FramePath::probe(Path::TraceAll))
        );
        p.idled(Path::TraceAll, Some(20.0));
        p.marched(500, Some(30.0), 64, true);
        assert_eq!(p.next, Path::SkipMarch);
        p.idled(Path::SkipMarch, Some(25.0));
        p.marched(500, Some(30.0), 64, true);
        assert_eq!((p.next, p.price(Path::March)), (Path::TraceAll, Some(30.0)));
        // Marching gets cheaper (a running mean): 30 -> 23.75, still dearer than
        // TraceAll's 20, then 19.06.
        p.marched(500, Some(5.0), 64, true);
        assert_eq!(p.next, Path::TraceAll, "{p:?}");
        p.marched(500, Some(5.0), 64, true);
        assert_eq!(p.next, Path::March, "{p:?}");
        let recheck = RECHECK_EVERY - 1;
        let path = |k| p.frame_path(k, true).rechecks;
        assert_eq!(path(recheck - 1), None);
        assert_ne!(path(recheck), path(recheck + RECHECK_EVERY));
        assert!([path(recheck), path(recheck + RECHECK_EVERY)].contains(&Some(Path::SkipMarch)));
        let f = p.frame_path(recheck, true);
        assert_eq!(
            (f.runs, f.shows),
            (Path::March, Path::March),
            "a recheck shows the march"
        );
        assert_eq!(
            p.frame_path(recheck, false),
            FramePath::plain(Path::March),
            "not priced: no recheck"
        );
        // No SSR-first tile marched: idle, however cheap marching was.
        p.marched(0, Some(5.0), 64, true);
        assert_eq!(p.next, Path::TraceAll);
        // A new rate: the march's mean starts again from its sample.
        p.marched(500, Some(40.0), 96, true);
        assert_eq!(
            (p.price(Path::March), p.march_rate, p.next),
            (Some(40.0), 96, Path::TraceAll)
        );
        // Not priced: idle only without SSR-first marches, and then without the march.
        let mut q = Paths::default();
        q.marched(500, None, 0, false);
        assert_eq!(q.next, Path::March);
        q.marched(0, None, 0, false);
        assert_eq!(
            (q.next, q.frame_path(1, false).runs),
            (Path::SkipMarch, Path::SkipMarch)
        );
    }

    /// While idle, a probe frame comes `probe_every` frames after the last frame that
    /// marched, however the interval changed: two probe frames never come closer (by
    /// the frame index's multiples, a probe frame at 25 that set the interval to 27
    /// was followed by one at 27).
    #[test]
    fn probe_frames_come_an_interval_after_the_last_march() {
        let mut p = Paths {
            next: Path::SkipMarch,
            probe_every: 27,
            ..Paths::default()
        };
        let probe = FramePath::probe(Path::SkipMarch);
        p.count(probe, 25);
        let probes: Vec<u32> = (26..60).filter(|&k| p.frame_path(k, true).measures_only()).collect();
        assert_eq!(probes.first(), Some(&52));
        p.count(FramePath::plain(Path::SkipMarch), 26);
        assert_eq!(p.last_march, 25, "an idle frame does not count");
    }

    /// Priced, an idle frame in `RECHECK_EVERY` rechecks the other idle path (a probe
    /// frame due comes first); a marching one each idle path in turn; not priced, none.
    #[test]
    fn idle_frames_recheck_the_other_idle_path() {
        let recheck = RECHECK_EVERY - 1;
        for (idle, other) in [(Path::SkipMarch, Path::TraceAll), (Path::TraceAll, Path::SkipMarch)] {
            let p = Paths {
                next: idle,
                probe_every: PROBE_EVERY_MAX,
                last_march: recheck - 2,
                ..Paths::default()
            };
            assert_eq!(p.frame_path(recheck, true), FramePath::recheck(idle, other));
            assert_eq!(p.frame_path(recheck, false), FramePath::plain(idle));
            assert_eq!(p.frame_path(recheck - 1, true), FramePath::plain(idle));
            let due = Paths { last_march: 0, ..p };
            assert_eq!(due.frame_path(recheck, true), FramePath::probe(idle), "the probe first");
        }
    }

    /// The frames' path is kept while another undercuts it by `PATH_HOLD` of its
    /// price or less, so paths priced within the noise do not alternate; a path it may
    /// not take (marching without an SSR-first tile) holds nothing.
    #[test]
    fn a_path_is_kept_until_another_undercuts_it_by_the_hold() {
        let priced = |next, ms| Paths {
            next,
            ms,
            ..Paths::default()
        };
        let mut p = priced(Path::SkipMarch, [Some(120.0), Some(100.0), Some(97.5)]);
        p.marched(500, None, 0, true);
        assert_eq!(p.next, Path::SkipMarch, "TraceAll 2.5% cheaper: held");
        p.ms[2] = Some(96.9);
        p.marched(500, None, 0, true);
        assert_eq!(p.next, Path::TraceAll, "3.1% cheaper: taken");
        let mut q = priced(Path::March, [Some(100.0), Some(98.0), Some(99.0)]);
        q.marched(500, None, 0, true);
        assert_eq!(q.next, Path::March, "the march held against 2%");
        q.marched(0, None, 0, true);
        assert_eq!(q.next, Path::SkipMarch, "no march to pay for: the cheapest idle path");
    }

    /// A probe frame that only measured prices the marching path without the rays
    /// SSR would have answered (at the frame's mean cost a ray) and with the marching
    /// frames' merge (their seams' blur) for its own.
    #[test]
    fn a_probe_frame_estimates_the_march() {
        // 40 ms of rows, 20 of them 10,000 rays, 2,500 of which SSR answered: 5 ms.
        assert_eq!(march_estimate(40.0, (20.0, 10_000, 2_500), (1.0, None)), 35.0);
        assert_eq!(march_estimate(40.0, (20.0, 10_000, 2_500), (1.0, Some(3.0))), 37.0);
        assert_eq!(march_estimate(40.0, (20.0, 0, 0), (1.0, None)), 40.0, "no rays");
        assert_eq!(march_estimate(4.0, (20.0, 100, 900), (1.0, None)), 0.0, "never below 0");
        // Counted as the idle path it showed, and as a probe.
        let mut p = Paths::default();
        p.count(FramePath::probe(Path::TraceAll), 7);
        p.count(FramePath::plain(Path::March), 8);
        assert_eq!((p.frames, p.probes), ([1, 0, 1], 1));
    }

    /// The rate follows the samples' running mean, holds within an eighth of it, and
    /// ignores frames with too little of either.
    #[test]
    fn the_rate_is_smoothed_and_held() {
        let mut r = ExchangeRate::default();
        r.add((1.0, 500), (1.0, 5000));
        assert_eq!(r, ExchangeRate::default(), "too few marched");
        // A march costing 0.86 of a ray: applied at once, 220/256.
        r.add((8.6, 10_000), (10.0, 10_000));
        assert_eq!(r.applied, 220);
        // Noise of a few percent moves the mean, not the rate.
        for k in 0..20 {
            let ms = if k % 2 == 0 { 8.2 } else { 9.0 };
            r.add((ms, 10_000), (10.0, 10_000));
            assert_eq!(r.applied, 220, "sample {k}");
        }
        // A new device's costs pull it over within a few frames.
        for _ in 0..20 {
            r.add((1.0, 10_000), (10.0, 10_000));
        }
        let e = r.estimate.unwrap();
        assert!(e < 0.12 && (r.fraction() - e).abs() <= e / 8.0, "{r:?}");
    }

    /// Every measured rate from 0.01 to 16 rays a march is applied (the first GPU run
    /// measured 0.0546, which a 1/16 hysteresis around the unset 0 never let in) within
    /// an eighth of itself or half a unit, and held under 5% noise; the tiles then take
    /// it: a tile SSR never answers turns rays-only at every rate, one SSR always
    /// answers stays SSR-first while a march costs less than a ray.
    #[test]
    fn every_rate_from_a_hundredth_to_sixteen_is_applied() {
        use crate::cpu_ref::ssr::tile_update;
        use crate::shader_defines::TILE_RAYS_ONLY;
        for rate in [0.01, 0.0546, 0.1, 0.3, 0.86, 1.0, 2.5, 16.0] {
            let mut r = ExchangeRate::default();
            let mut held = None;
            for k in 0..30 {
                let noise = if k % 2 == 0 { 0.95 } else { 1.05 };
                r.add((rate * noise * 10.0, 10_000), (10.0, 10_000));
                if k >= 10 {
                    assert_eq!(
                        *held.get_or_insert(r.applied),
                        r.applied,
                        "rate {rate}: moved under noise"
                    );
                }
            }
            let f = r.fraction();
            assert!(r.applied > 0, "rate {rate}: not applied");
            assert!(
                (f - rate).abs() <= (rate / 8.0).max(0.5 / TILE_ONE as f64),
                "rate {rate}: applied {f}"
            );
            let (never, always) = (tile_update(0, 64, 0, r.applied), tile_update(0, 64, 64, r.applied));
            let again = |s| tile_update(s, 64, 0, r.applied);
            assert!(
                again(never) & TILE_RAYS_ONLY != 0,
                "rate {rate}: a tile SSR never answers"
            );
            assert_eq!(
                always & TILE_RAYS_ONLY != 0,
                rate > 1.0,
                "rate {rate}: a tile SSR always answers"
            );
        }
    }
}
