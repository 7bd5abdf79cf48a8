//! Headless rendering: warm-up frames, measured frames, per-scope statistics, and the
//! `render --timings` report (schema: `report`).

use crate::error::{Error, Result};
use crate::metrics::{compare_rgba8, Comparison};
use crate::renderer::{Renderer, FRAME};
use crate::report::{FrameRecord, Header, PassTimes, Stat};
use crate::settings::{Mode, Settings, Shadows};
use crate::shadow_maps::ShadowsVsRays;
use crate::steady::{WarmUp, WarmUpReport};
use crate::vk::{Context, TimingCheck, Timings};
use crate::{scene::Scene, shader_defines::MAX_REFLECTION_RAYS};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Most frames (measured, or warm-up) one run renders: enough for any measurement,
/// and a typo like `--frames 4294967295` fails at once instead of running for days.
pub const MAX_FRAMES: u32 = 100_000;

/// The `render --timings` report.
#[derive(Clone, Debug, Serialize)]
pub struct TimingsReport {
    #[serde(flatten)]
    pub header: Header,
    pub scene: String,
    /// [width, height] in pixels.
    pub resolution: [u32; 2],
    /// Reflection mode of the measured frames.
    pub mode: String,
    /// The effective camera (scene file, then `--camera-*`/`--fov`): enough to render
    /// the same view again.
    pub camera: crate::scene::Camera,
    /// Unit direction towards the sun.
    pub sun_direction: [f32; 3],
    /// Frames measured (warm-up frames excluded).
    pub frames: u32,
    /// The warm-up: its rule (`frames N`, or `steady`: until the clocks settle), the
    /// frames and GPU time it took, and whether the clocks settled.
    pub warmup: WarmUpReport,
    /// Every timer scope in frame order → GPU milliseconds (`null`: not run).
    pub passes_ms: PassTimes,
    /// GPU milliseconds of the whole frame (scope `frame`).
    pub frame_ms: Stat,
    /// Pixels with a reflective surface.
    pub reflective_pixels: u64,
    /// Reflective pixels SSR failed on.
    pub ssr_failed_pixels: u64,
    /// Reflective pixels the ray tracer produced (0 in `raster` and `ssr` modes).
    pub traced_pixels: u64,
    /// traced / reflective pixels.
    pub rt_pixel_fraction: f64,
    /// Failed pixels by reason, every reason present (see `reflection_maps`).
    pub fail_reasons: BTreeMap<String, u64>,
    /// Where the shadows came from (the `shadows` setting).
    pub shadows: String,
    /// Pixels whose surface faces the sun.
    pub shadow_lit_pixels: u64,
    /// Lit pixels that got a shadow ray (0 under `map` shadows).
    pub shadow_traced_pixels: u64,
    /// shadow-traced / lit pixels.
    pub shadow_ray_fraction: f64,
    /// With `--reference` and shadows other than `rays`: the last frame against the
    /// same frame with `rays` shadows; `null` otherwise.
    pub shadows_vs_rays: Option<ShadowsVsRays>,
    /// With `--reference`: SSIM and RMSE of the last frame against the same frame in
    /// `rt` mode, and the reference's frame time; `null` without.
    pub ssim_vs_rt: Option<f64>,
    pub rmse_vs_rt: Option<f64>,
    pub rt_frame_ms: Option<Stat>,
    /// With `--reference` and glossy reflections, in a mode other than `rt`: the last
    /// frame against the same frame in `rt` mode with the same settings (the same glossy
    /// rays and filter, where the reference takes `spp` rays unfiltered), so that what
    /// the mode adds (SSR, the merge, the seam blur) reads apart from the glossy
    /// estimate's own error; `null` otherwise.
    pub vs_rt_mode: Option<Comparison>,
    /// A hybrid frame's split of the work (`hybrid_policy`); `null` in other modes.
    pub hybrid: Option<HybridSplit>,
    /// With `visibility = adaptive`: the G-buffer's ways, their frames and prices, and
    /// the one the frames take; `null` with a fixed `visibility`.
    pub visibility: Option<StageReport>,
    /// With `shadows = adaptive`: the same of the shadows' sources (`shadows` is then
    /// `adaptive`); `null` with a fixed source.
    pub shadow_ways: Option<StageReport>,
    /// With `static_ploc`: the static tree kept, PLOC's or the LBVH's, and what each
    /// took over the same rays (`renderer::static_tree`); `null` otherwise.
    pub static_tree: Option<crate::renderer::static_tree::StaticTreeChoice>,
    /// With `static_layout = fastest`: the static nodes kept, each layout's price; or `null`.
    pub static_layout: Option<crate::renderer::static_tree::StaticLayoutChoice>,
    /// The self-check of every measured frame, the reference's included (`vk::timing`).
    pub timing: TimingCheck,
}

/// How the last hybrid frame split its reflective tiles between the march and the ray
/// tracer.
#[derive(Clone, Debug, Serialize)]
pub struct HybridSplit {
    pub policy: String,
    /// The exchange rate the tiles used (a march's cost in rays; 0: every tile
    /// SSR-first), and with `exchange_rate = 0` the running mean it was measured from.
    pub exchange_rate: f64,
    pub exchange_rate_measured: Option<f64>,
    /// Tiles (8x8 pixels) marching first, sending their pixels straight to rays, and
    /// not known yet (nothing marched there: nothing to reflect, or just seen; they
    /// march first).
    pub ssr_first_tiles: u64,
    pub rays_only_tiles: u64,
    pub unknown_tiles: u64,
    /// Changes of class since the first frame: over all tiles, and of the tile that
    /// changed most.
    pub tile_flips: u64,
    pub most_tile_flips: u64,
    /// The path until the next probe frame (`march`, `skip_march`, `trace_all`), each
    /// path's frames (by the path shown) and priced reflection rows (ms, running mean);
    /// idle, a frame in `probe_every` probes (marches to measure, shows the idle path).
    pub path: String,
    pub paths: Vec<PathReport>,
    pub probe_every: u32,
    pub probe_frames: u64,
}

/// One path of the adaptive hybrid in `HybridSplit`.
#[derive(Clone, Debug, Serialize)]
pub struct PathReport {
    pub path: String,
    pub frames: u64,
    pub ms: Option<f64>,
}

/// One adaptive stage of the frame (`renderer::stages`): `visibility = adaptive`
/// (ways `raster`, `rays`) or `shadows = adaptive` (`hybrid`, `rays`).
#[derive(Clone, Debug, Serialize)]
pub struct StageReport {
    /// The way the frames take: the cheapest once every way is priced, until then the
    /// one being priced.
    pub way: String,
    /// Each way's frames since the settings last changed, and its price (the median of
    /// its last checked times of the stage's rows, ms) once it has `stages::SAMPLES` of
    /// them.
    pub ways: Vec<WayReport>,
    /// Once every way is priced, one frame in this many takes another.
    pub recheck_every: u32,
}

impl StageReport {
    /// `stage`'s ways, named `names`, before frame `index` is recorded.
    pub fn of<const N: usize>(stage: &crate::renderer::stages::Stage<N>, names: [&str; N], index: u32) -> Self {
        let way = if stage.priced() {
            stage.chosen
        } else {
            stage.frame_way(index)
        };
        Self {
            way: names[way].to_string(),
            ways: (0..N)
                .map(|w| WayReport {
                    way: names[w].to_string(),
                    frames: stage.frames[w],
                    ms: stage.price(w),
                })
                .collect(),
            recheck_every: crate::renderer::stages::RECHECK_EVERY,
        }
    }

    /// One line: each way's frames and price, and the way the frames take.
    pub fn summary(&self) -> String {
        let ways: Vec<String> = self
            .ways
            .iter()
            .map(|w| frames_and_price(&w.way, w.frames, w.ms))
            .collect();
        format!(
            "{} (next: {}, rechecked 1 frame in {})",
            ways.join("; "),
            self.way,
            self.recheck_every
        )
    }
}

/// An adaptive choice's way (or the hybrid's path) in a line of text: its frames, and
/// its price where it has one (`raster 11 frames, 12.24 ms`).
pub fn frames_and_price(name: &str, frames: u64, ms: Option<f64>) -> String {
    let ms = ms.map_or(String::new(), |m| format!(", {m:.2} ms"));
    format!("{name} {frames} frames{ms}")
}

/// One way of an adaptive stage in `StageReport`.
#[derive(Clone, Debug, Serialize)]
pub struct WayReport {
    pub way: String,
    pub frames: u64,
    pub ms: Option<f64>,
}

/// A finished headless render.
pub struct Rendered {
    pub report: TimingsReport,
    /// The last frame, tightly packed RGBA8 (sRGB-encoded).
    pub rgba: Vec<u8>,
    /// With a reference: the `rt` mode frame.
    pub reference_rgba: Option<Vec<u8>>,
    /// The last frame's fail mask coloured by reason (`ReflectionMaps::fail_mask_rgba`).
    pub fail_mask_rgba: Vec<u8>,
    /// The last frame's shadows coloured by source (`ShadowMaps::sources_rgba`).
    pub shadow_sources_rgba: Vec<u8>,
}

/// Frames to render and measure.
#[derive(Clone, Copy, Debug)]
pub struct FramePlan {
    /// Uncounted frames first: a fixed count, or until the clocks settle (`steady`).
    pub warmup: WarmUp,
    pub frames: u32,
    /// Also render the frame in `rt` mode and report SSIM/RMSE against it; and, when
    /// the shadows are not `rays`, in its own mode with `rays` shadows and report how
    /// far its shadows are from them.
    pub reference: bool,
    /// Samples per glossy pixel of the `rt` reference, in one frame and not denoised
    /// (`Settings::glossy_reference`): the glossy ground truth. Unused without glossy
    /// reflections, where one mirror ray per pixel is exact.
    pub spp: u32,
}

impl FramePlan {
    /// Frames `render` draws in all, for a progress bar.
    pub fn total_frames(&self, settings: &Settings) -> u64 {
        let renderers = match (self.reference, settings.shadows) {
            (false, _) => 1,
            (true, Shadows::Rays) => 2,
            (true, _) => 3,
        };
        (self.warmup.min_frames() as u64 + self.frames as u64) * renderers
    }

    /// Checks what can be known before any GPU work: frame counts, and an image large
    /// enough for SSIM when a reference is asked for.
    pub fn validate(&self, settings: &Settings) -> Result<()> {
        if self.frames == 0 || self.frames > MAX_FRAMES {
            return Err(Error::Settings(format!(
                "--frames {} is outside 1..={MAX_FRAMES}",
                self.frames
            )));
        }
        if let WarmUp::Frames(n) = self.warmup {
            if n > MAX_FRAMES {
                return Err(Error::Settings(format!("--warmup {n} is outside 0..={MAX_FRAMES}")));
            }
        }
        if self.spp == 0 || self.spp > MAX_REFLECTION_RAYS {
            return Err(Error::Settings(format!(
                "--spp {} is outside 1..={MAX_REFLECTION_RAYS}",
                self.spp
            )));
        }
        if self.reference {
            crate::metrics::check_size(settings.width, settings.height)
                .map_err(|e| Error::Input(format!("--reference: {e}")))?;
        }
        Ok(())
    }
}

/// Called after every frame a long run renders (for a progress bar).
pub type Tick<'a> = &'a mut dyn FnMut();

/// Renders rounds of one frame of each of `renderers` until `warmup` is done (a round's
/// GPU time is its frames' together, by their timestamps; the wall time where a readout
/// lacks the frame), `tick` after every frame: what the warm-up took. After a steady
/// warm-up the adaptive stages price their ways again, at the settled clocks (the first
/// frames priced them cold: a GPU measures 4.5x slow then), in rounds until every one
/// is priced (at most `stages::PRICE_ROUNDS`); a fixed count renders exactly its frames.
pub fn warm_up(renderers: &mut [&mut Renderer], warmup: WarmUp, tick: Tick<'_>) -> Result<WarmUpReport> {
    let mut warming = warmup.start();
    while !warming.done() {
        let mut ms = 0.0;
        for r in renderers.iter_mut() {
            let start = std::time::Instant::now();
            let t = r.render_frame()?;
            ms += t.get(FRAME).unwrap_or(start.elapsed().as_secs_f64() * 1e3);
            tick();
        }
        warming.add(ms);
    }
    let mut report = warming.report();
    if matches!(warmup, WarmUp::Steady { .. }) && renderers.iter().any(|r| r.adaptive_stages()) {
        for r in renderers.iter_mut() {
            r.reprice_stages();
        }
        report.pricing_rounds = price_stages(renderers, tick)?;
    }
    Ok(report)
}

/// Renders rounds of one frame of each of `renderers` (a dynamic scene's stay in step)
/// until every adaptive stage is priced, at most `stages::PRICE_ROUNDS`, `tick` after
/// every frame: the rounds rendered.
pub fn price_stages(renderers: &mut [&mut Renderer], tick: Tick<'_>) -> Result<u32> {
    let mut rounds = 0;
    while rounds < crate::renderer::stages::PRICE_ROUNDS && !renderers.iter().all(|r| r.stages_priced()) {
        for r in renderers.iter_mut() {
            r.render_frame()?;
            tick();
        }
        rounds += 1;
    }
    Ok(rounds)
}

/// Called with every measured frame; its error ends the render.
pub type OnFrame<'a> = &'a mut dyn FnMut(FrameRecord<'_>) -> Result<()>;

/// Renders the warm-up's uncounted frames (`plan.warmup`: the frames of all its
/// renderers together count toward its GPU time), resets a dynamic scene, then renders
/// `plan.frames` measured ones; with a reference, an `rt` renderer runs in lockstep (the
/// same frame of a dynamic scene), its frame right after each measured one. `tick` is
/// called after every frame, `on_frame` (when given) with every measured frame.
pub fn render_frames(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &Settings,
    plan: FramePlan,
    tick: Tick<'_>,
    mut on_frame: Option<OnFrame<'_>>,
) -> Result<Rendered> {
    plan.validate(settings)?;
    let (mut renderer, mut others) = renderers(ctx, scene, settings, plan)?;
    let mut all: Vec<&mut Renderer> = std::iter::once(&mut renderer).chain(others.all()).collect();
    let warmup = warm_up(&mut all, plan.warmup, tick)?;
    // A dynamic scene starts over after the warm-up: measured frame k is the same
    // image whatever the warm-up (the world after k + 1 time steps).
    for r in std::iter::once(&mut renderer).chain(others.all()) {
        r.reset_simulation()?;
    }
    let Others {
        reference,
        rays_reference,
        rt_mode,
    } = &mut others;
    let (mut timings, mut ref_timings) = (Timings::default(), Timings::default());
    for index in 0..plan.frames {
        let (times, discarded) = renderer.render_frame_measured()?;
        tick();
        timings.add_measured(&times, discarded);
        if let Some(r) = reference {
            let (times, discarded) = r.render_frame_measured()?;
            ref_timings.add_measured(&times, discarded);
            tick();
        }
        for r in rays_reference.iter_mut().chain(rt_mode.iter_mut()) {
            r.render_frame()?;
            tick();
        }
        if let Some(hook) = on_frame.as_mut() {
            let rgba = renderer.read_output()?;
            let vs_rt = match &reference {
                Some(r) => Some(compare_rgba8(
                    &rgba,
                    &r.read_output()?,
                    settings.width,
                    settings.height,
                )?),
                None => None,
            };
            hook(FrameRecord {
                index,
                times: &times.scopes,
                timing_problem: times.problem.as_deref(),
                rgba: &rgba,
                dynamic_triangles: renderer.dynamic_triangles(),
                rt_pixel_fraction: renderer.reflection_stats()?.rt_pixel_fraction(),
                vs_rt,
                plan: renderer.last_plan().expect("a frame was rendered"),
            })?;
        }
    }
    let runs = Runs {
        renderer: &renderer,
        reference: reference.as_ref(),
        rays_reference: rays_reference.as_ref(),
        rt_mode: rt_mode.as_ref(),
    };
    finish(ctx, scene, settings, (plan, warmup), runs, [timings, ref_timings])
}

/// The renderers that run in lockstep with a run's own, for its comparisons.
#[derive(Default)]
struct Others {
    /// The `rt` reference (`Renderer::reference`).
    reference: Option<Renderer>,
    /// The same settings with `rays` shadows.
    rays_reference: Option<Renderer>,
    /// The same settings in `rt` mode (`TimingsReport::vs_rt_mode`).
    rt_mode: Option<Renderer>,
}

impl Others {
    fn all(&mut self) -> impl Iterator<Item = &mut Renderer> {
        (self.reference.iter_mut())
            .chain(self.rays_reference.iter_mut())
            .chain(self.rt_mode.iter_mut())
    }
}

/// The renderer of `settings`, and with a reference the `rt` renderer, (unless the
/// shadows are rays already) the renderer with `rays` shadows and (with glossy
/// reflections, in another mode than `rt`) the `rt` mode's, run in lockstep.
fn renderers(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, plan: FramePlan) -> Result<(Renderer, Others)> {
    let renderer = Renderer::new(ctx, scene, settings)?;
    let reference = if plan.reference {
        Some(Renderer::reference(ctx, scene, settings, plan.spp)?)
    } else {
        None
    };
    let rays_reference = if plan.reference && settings.shadows != Shadows::Rays {
        let rays = Settings {
            shadows: Shadows::Rays,
            ..settings.clone()
        };
        Some(Renderer::new(ctx, scene, &rays)?)
    } else {
        None
    };
    let rt_mode = if plan.reference && settings.glossy && settings.mode != Mode::Rt {
        let rt = Settings {
            mode: Mode::Rt,
            ..settings.clone()
        };
        Some(Renderer::new(ctx, scene, &rt)?)
    } else {
        None
    };
    let others = Others {
        reference,
        rays_reference,
        rt_mode,
    };
    Ok((renderer, others))
}

/// The renderers of a run after its last measured frame.
struct Runs<'a> {
    renderer: &'a Renderer,
    reference: Option<&'a Renderer>,
    rays_reference: Option<&'a Renderer>,
    rt_mode: Option<&'a Renderer>,
}

/// The report and images of a run after its last measured frame: the frame and its
/// maps, and the comparisons with the references.
fn finish(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &Settings,
    (plan, warmup): (FramePlan, WarmUpReport),
    runs: Runs<'_>,
    [timings, ref_timings]: [Timings; 2],
) -> Result<Rendered> {
    let Runs {
        renderer,
        reference,
        rays_reference,
        rt_mode,
    } = runs;
    let rgba = renderer.read_output()?;
    let maps = renderer.reflection_maps()?;
    let stats = maps.stats();
    let shadow_maps = renderer.shadow_maps()?;
    let shadow_stats = shadow_maps.stats();
    let vs_rays = match rays_reference {
        Some(r) => Some(ShadowsVsRays::of(
            (&rgba, &shadow_maps),
            (&r.read_output()?, &r.shadow_maps()?),
            [settings.width, settings.height],
        )?),
        None => None,
    };
    let frame_stat = |t: &Timings| t.samples(FRAME).and_then(Stat::of).expect("every frame is timed");
    let (mut ssim, mut rmse, mut rt_frame_ms, mut reference_rgba) = (None, None, None, None);
    if let Some(r) = reference {
        let reference = r.read_output()?;
        let c = compare_rgba8(&rgba, &reference, settings.width, settings.height)?;
        ssim = Some(c.ssim);
        rmse = Some(c.rmse);
        rt_frame_ms = Some(frame_stat(&ref_timings));
        reference_rgba = Some(reference);
    }
    let (visibility, shadow_ways) = stage_reports(renderer, settings);
    let report = TimingsReport {
        header: Header::new("render", Some(ctx), Some(settings)),
        scene: scene.name.clone(),
        resolution: [settings.width, settings.height],
        mode: settings.mode.name().to_string(),
        camera: scene.camera,
        sun_direction: scene.light.direction.to_array(),
        frames: plan.frames,
        warmup,
        passes_ms: PassTimes::of(&timings),
        frame_ms: frame_stat(&timings),
        reflective_pixels: stats.reflective_pixels,
        ssr_failed_pixels: stats.ssr_failed_pixels,
        traced_pixels: stats.traced_pixels,
        rt_pixel_fraction: stats.rt_pixel_fraction(),
        fail_reasons: stats.fail_reasons.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        shadows: settings.shadows.name().to_string(),
        shadow_lit_pixels: shadow_stats.lit_pixels,
        shadow_traced_pixels: shadow_stats.traced_pixels,
        shadow_ray_fraction: shadow_stats.ray_fraction(),
        shadows_vs_rays: vs_rays,
        ssim_vs_rt: ssim,
        rmse_vs_rt: rmse,
        rt_frame_ms,
        vs_rt_mode: match rt_mode {
            Some(r) => Some(compare_rgba8(
                &rgba,
                &r.read_output()?,
                settings.width,
                settings.height,
            )?),
            None => None,
        },
        hybrid: hybrid_split(renderer, settings)?,
        visibility,
        shadow_ways,
        static_tree: renderer.static_tree.clone(),
        static_layout: renderer.static_layout.clone(),
        timing: Timings::check_all(&[timings, ref_timings]),
    };
    Ok(Rendered {
        report,
        rgba,
        reference_rgba,
        fail_mask_rgba: maps.fail_mask_rgba(),
        shadow_sources_rgba: shadow_maps.sources_rgba(),
    })
}

/// `render_frames` without a per-frame hook.
pub fn render(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &Settings,
    plan: FramePlan,
    tick: Tick<'_>,
) -> Result<Rendered> {
    render_frames(ctx, scene, settings, plan, tick, None)
}

/// The adaptive stages' reports (`None` where the setting is fixed): the G-buffer's
/// and the shadows'.
pub(crate) fn stage_reports(renderer: &Renderer, settings: &Settings) -> (Option<StageReport>, Option<StageReport>) {
    use crate::settings::{Shadows, Visibility};
    let stages = renderer.stages();
    let index = renderer.frame_index();
    let visibility = (settings.visibility == Visibility::Adaptive)
        .then(|| StageReport::of(&stages.visibility, Visibility::FIXED.map(Visibility::name), index));
    let shadows = (settings.shadows == Shadows::Adaptive)
        .then(|| StageReport::of(&stages.shadows, Shadows::ADAPTIVE.map(Shadows::name), index));
    (visibility, shadows)
}

/// The last frame's `HybridSplit`, in the modes that have one (`hybrid`, `provenance`).
pub(crate) fn hybrid_split(renderer: &Renderer, settings: &Settings) -> Result<Option<HybridSplit>> {
    use crate::settings::Hybrid;
    if !(settings.mode.marches() && settings.mode.traces()) {
        return Ok(None);
    }
    let tiles = renderer.tile_census()?;
    let paths = renderer.hybrid_paths();
    let hybrid = Hybrid::of(settings);
    let rate = renderer.exchange_rate();
    let exchange_rate = match hybrid {
        Hybrid::None => 0.0,
        Hybrid::Measured => rate.fraction(),
        Hybrid::Fixed(_) => settings.exchange_rate as f64,
    };
    let measured = hybrid == Hybrid::Measured;
    Ok(Some(HybridSplit {
        policy: settings.hybrid_policy.name().to_string(),
        exchange_rate,
        exchange_rate_measured: rate.estimate.filter(|_| measured),
        ssr_first_tiles: tiles.ssr_first,
        rays_only_tiles: tiles.rays_only,
        unknown_tiles: tiles.unknown,
        tile_flips: tiles.flips,
        most_tile_flips: tiles.most_flips,
        path: paths.next.name().to_string(),
        probe_every: paths.probe_every,
        probe_frames: paths.probes,
        paths: crate::renderer::exchange::Path::ALL
            .iter()
            .map(|&p| PathReport {
                path: p.name().to_string(),
                frames: paths.frames[p as usize],
                ms: paths.price(p).filter(|_| measured),
            })
            .collect(),
    }))
}
