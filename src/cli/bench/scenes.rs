//! `speculum bench modes|shadows|frame|reflect`: a scene's frames in several settings,
//! interleaved in one run.

use super::{valid_or_fail, Common};
use crate::cli::{cell, check_count, check_outputs, progress, SettingsArgs, Text};
use anyhow::Result;
use clap::Args;
use speculum::output::Kind;
use speculum::renderer::{FRAME, SCOPES};
use speculum::report::Header;

#[derive(Args, Clone, Debug)]
pub struct ModesArgs {
    #[command(flatten)]
    pub view: crate::cli::ViewArgs,
    /// Built-in scene names or .obj paths (each timed on its own).
    #[arg(long, num_args = 1.., default_value = "room")]
    pub scene: Vec<String>,
    /// Measured rounds (one frame of every mode, or shadow source, each).
    #[arg(long, default_value_t = 7)]
    pub rounds: u32,
    /// Uncounted warm-up rounds, exactly [default: until the clocks settle: at least
    /// 250 ms of GPU work and two windows of 2 to 8 rounds (50 ms) within 5%, at most 20 s]
    #[arg(long)]
    pub warmup: Option<u32>,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args, Clone, Debug)]
pub struct ReflectArgs {
    #[command(flatten)]
    pub view: crate::cli::ViewArgs,
    /// Built-in scene name or .obj path.
    #[arg(long, default_value = "room")]
    pub scene: String,
    /// Measured rounds: one frame of every point and of rt each (after the warm-up, until
    /// the clocks settle).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

pub(super) fn reflect(args: ReflectArgs) -> Result<()> {
    let c = &args.common;
    let settings = args.frame.resolve()?;
    check_count("--frames", args.frames, 1)?;
    check_outputs(
        &[("--json", c.json.as_deref(), Kind::Json)],
        &[("--settings", args.frame.settings.as_deref())],
    )?;
    let scene = args.view.load(&args.scene)?;
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let renderers = speculum::bench::reflect::sweep(&settings).len() as u64 + 1;
    let warmup = speculum::steady::WarmUp::steady();
    let bar = progress(
        renderers * (args.frames + warmup.min_frames()) as u64,
        "bench reflect",
        c.quiet,
    );
    let mut r = speculum::bench::reflect::run(&ctx, &scene, &settings, warmup, args.frames, &mut || bar.inc(1))?;
    bar.finish_and_clear();
    r.header.refresh_validation(&ctx);
    text.line(format_args!(
        "{} on {}: {}x{}, {} reflective pixels; rt mode frame {} ms",
        r.scene,
        ctx.device_name,
        r.resolution[0],
        r.resolution[1],
        r.reflective_pixels,
        cell(Some(r.rt_frame_ms))
    ));
    let passes = [
        "ssr.hiz",
        "ssr.classify",
        "ssr.trace",
        "ssr.compact",
        "rt.reflect",
        "reflect.merge",
    ];
    text.line(format_args!(
        "  steps  min conf   traced  {}   frame (ms)  / rt",
        passes.map(|p| format!("{p:>13}")).join(" ")
    ));
    for p in &r.points {
        let ms = passes.map(|k| format!("{:>13.1}", p.passes_ms.median(k))).join(" ");
        text.line(format_args!(
            "  {:5} {:9.2} {:7.1}%  {ms} {:12.1} {:6.3}",
            p.ssr_max_steps,
            p.ssr_min_confidence,
            100.0 * p.rt_pixel_fraction,
            p.frame_ms.median,
            p.frame_over_rt.median
        ));
    }
    text.line(format_args!("  {}", crate::cli::timing_note(&r.timing)));
    text.line(format_args!(
        "  {}",
        crate::cli::steady_note(&r.warmup, Some(&r.rounds_check))
    ));
    if let Some(path) = &c.json {
        crate::cli::write_report(path, &r, &text)?;
    }
    crate::cli::check_validation(&ctx)?;
    valid_or_fail(r.valid)
}

/// What `bench modes` and `bench shadows` share: the settings, counts and outputs
/// checked and every scene loaded before any GPU work; each scene run in turn
/// (`renderers` frames a round) under one progress bar, printed as it finishes; the
/// report (`report` of the header and the results) written; exit 1 when a check failed.
fn scene_bench<R, Rep: serde::Serialize>(
    args: &ModesArgs,
    kind: &'static str,
    renderers: u64,
    run: impl Fn(
        &std::sync::Arc<speculum::vk::Context>,
        &speculum::scene::Scene,
        &speculum::Settings,
        &mut dyn FnMut(),
    ) -> speculum::Result<R>,
    print: impl Fn(&Text, &R, &str),
    valid: impl Fn(&R) -> bool,
    report: impl FnOnce(Header, Vec<R>, bool) -> Rep,
) -> Result<()> {
    let c = &args.common;
    let settings = args.frame.resolve()?;
    check_count("--rounds", args.rounds, 1)?;
    if let Some(w) = args.warmup {
        check_count("--warmup", w, 0)?;
    }
    // SSIM against the reference frame needs an image its window fits in: known
    // before any GPU work.
    speculum::metrics::check_size(settings.width, settings.height)?;
    check_outputs(
        &[("--json", c.json.as_deref(), Kind::Json)],
        &[("--settings", args.frame.settings.as_deref())],
    )?;
    // Load every scene first: a bad one fails before any GPU work.
    let scenes = args
        .scene
        .iter()
        .map(|s| args.view.load(s))
        .collect::<Result<Vec<_>>>()?;
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let warmup = speculum::steady::WarmUp::from_arg(args.warmup);
    let per_scene = renderers * (args.rounds + warmup.min_frames()) as u64;
    let bar = progress(per_scene * scenes.len() as u64, &kind.replace('.', " "), c.quiet);
    let mut results = Vec::new();
    for scene in &scenes {
        let r = run(&ctx, scene, &settings, &mut || bar.inc(1))?;
        bar.suspend(|| print(&text, &r, &ctx.device_name));
        results.push(r);
    }
    bar.finish_and_clear();
    let all_valid = results.iter().all(&valid);
    let report = report(Header::new(kind, Some(&ctx), Some(&settings)), results, all_valid);
    if let Some(path) = &c.json {
        crate::cli::write_report(path, &report, &text)?;
    }
    crate::cli::check_validation(&ctx)?;
    valid_or_fail(all_valid)
}

pub(super) fn modes(args: ModesArgs) -> Result<()> {
    use speculum::bench::modes::{run, ModesReport};
    let (warmup, rounds) = (speculum::steady::WarmUp::from_arg(args.warmup), args.rounds);
    scene_bench(
        &args,
        "bench.modes",
        speculum::settings::Mode::ALL.len() as u64,
        |ctx, scene, settings, tick| run(ctx, scene, settings, warmup, rounds, tick),
        |text, r, device| print_modes(text, r, device, rounds),
        |r| r.valid,
        |header, scenes, valid| ModesReport {
            header,
            rounds,
            warmup: warmup.rule(),
            scenes,
            valid,
        },
    )
}

fn print_modes(text: &Text, r: &speculum::bench::modes::SceneModes, device: &str, rounds: u32) {
    text.line(format_args!(
        "{} on {device}: {}x{}, median of {rounds} interleaved rounds",
        r.scene, r.resolution[0], r.resolution[1]
    ));
    // Each column as wide as its mode's name (at least 10).
    let width = |m: &speculum::bench::modes::ModeResult| m.mode.len().max(10);
    let header: String = r
        .modes
        .iter()
        .map(|m| format!(" {:>w$}", m.mode, w = width(m)))
        .collect();
    text.line(format_args!("  {:<18}{header}", "pass (ms)"));
    let row = |name: &str, f: &dyn Fn(&speculum::bench::modes::ModeResult) -> String| {
        let cells: String = r.modes.iter().map(|m| format!(" {:>w$}", f(m), w = width(m))).collect();
        text.line(format_args!("  {name:<18}{cells}"));
    };
    // Passes in frame order; the uniform upload is too small to matter.
    for p in SCOPES
        .iter()
        .filter(|&&p| p != FRAME && p != speculum::renderer::UNIFORMS)
    {
        row(p, &|m| match m.passes_ms.get(p) {
            Some(s) => format!("{:.1}", s.median),
            None => "-".into(),
        });
    }
    row("frame", &|m| format!("{:.1}", m.frame_ms.median));
    row("frame / rt", &|m| format!("{:.3}", m.frame_over_rt.median));
    row("traced %", &|m| format!("{:.1}", 100.0 * m.rt_pixel_fraction));
    row("SSIM vs rt", &|m| format!("{:.4}", m.ssim_vs_rt));
    row("RMSE vs rt", &|m| format!("{:.4}", m.rmse_vs_rt));
    if r.modes.iter().any(|m| m.ssim_vs_reference.is_some()) {
        let f = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.4}"));
        row("SSIM vs glossy ref", &|m| f(m.ssim_vs_reference));
        row("RMSE vs glossy ref", &|m| f(m.rmse_vs_reference));
    }
    text.line(format_args!(
        "  ssr < hybrid < rt: {}; checks {}",
        if r.ordered { "yes" } else { "NO" },
        if r.valid { "valid" } else { "INVALID" }
    ));
    let timing: speculum::vk::TimingCheck = r.modes.iter().map(|m| &m.timing).collect();
    text.line(format_args!("  {}", crate::cli::timing_note(&timing)));
    text.line(format_args!(
        "  {}",
        crate::cli::steady_note(&r.warmup, Some(&r.rounds_check))
    ));
}

pub(super) fn shadows(args: ModesArgs) -> Result<()> {
    use speculum::bench::shadows::{run, ShadowsReport};
    let (warmup, rounds) = (speculum::steady::WarmUp::from_arg(args.warmup), args.rounds);
    scene_bench(
        &args,
        "bench.shadows",
        speculum::settings::Shadows::ALL.len() as u64,
        |ctx, scene, settings, tick| run(ctx, scene, settings, warmup, rounds, tick),
        |text, r, device| print_shadows(text, r, device, rounds),
        |r| r.valid,
        |header, scenes, valid| ShadowsReport {
            header,
            rounds,
            warmup: warmup.rule(),
            scenes,
            valid,
        },
    )
}

fn print_shadows(text: &Text, r: &speculum::bench::shadows::SceneShadows, device: &str, rounds: u32) {
    use speculum::bench::shadows::ShadowResult;
    text.line(format_args!(
        "{} on {device}: {}x{}, {} reflections, median of {rounds} interleaved rounds",
        r.scene, r.resolution[0], r.resolution[1], r.mode
    ));
    let header: String = r.shadows.iter().map(|s| format!(" {:>10}", s.shadows)).collect();
    text.line(format_args!("  {:<16}{header}", "pass (ms)"));
    let row = |name: &str, f: &dyn Fn(&ShadowResult) -> String| {
        let cells: String = r.shadows.iter().map(|s| format!(" {:>10}", f(s))).collect();
        text.line(format_args!("  {name:<16}{cells}"));
    };
    let scopes = [
        "shadow.map",
        "shadow.classify",
        "shadow.compact",
        "shadow.trace",
        "light.direct",
        "rt.reflect",
    ];
    for p in scopes {
        row(p, &|s| match s.passes_ms.get(p) {
            Some(t) => format!("{:.1}", t.median),
            None => "-".into(),
        });
    }
    row("frame", &|s| format!("{:.1}", s.frame_ms.median));
    row("frame / rays", &|s| format!("{:.3}", s.frame_over_rays.median));
    row("trace / rays", &|s| {
        s.trace_over_rays.map_or("-".into(), |v| format!("{v:.3}"))
    });
    row("traced % of lit", &|s| format!("{:.1}", 100.0 * s.ray_fraction));
    row("vis. = rays %", &|s| {
        format!("{:.3}", 100.0 * s.vs_rays.visibility_agreement)
    });
    row("vis. RMSE", &|s| format!("{:.4}", s.vs_rays.visibility_rmse));
    row("SSIM vs rays", &|s| format!("{:.4}", s.vs_rays.ssim));
    text.line(format_args!("  checks {}", if r.valid { "valid" } else { "INVALID" }));
    let timing: speculum::vk::TimingCheck = r.shadows.iter().map(|s| &s.timing).collect();
    text.line(format_args!("  {}", crate::cli::timing_note(&timing)));
    text.line(format_args!(
        "  {}",
        crate::cli::steady_note(&r.warmup, Some(&r.rounds_check))
    ));
}

pub(super) fn frame(args: ModesArgs) -> Result<()> {
    use speculum::bench::frame::{run, variants, FrameReport};
    let (warmup, rounds) = (speculum::steady::WarmUp::from_arg(args.warmup), args.rounds);
    scene_bench(
        &args,
        "bench.frame",
        variants().len() as u64,
        |ctx, scene, settings, tick| run(ctx, scene, settings, warmup, rounds, tick),
        |text, r, device| print_frame(text, r, device, rounds),
        |r| r.valid,
        |header, scenes, valid| FrameReport {
            header,
            rounds,
            warmup: warmup.rule(),
            scenes,
            valid,
        },
    )
}

fn print_frame(text: &Text, r: &speculum::bench::frame::SceneFrame, device: &str, rounds: u32) {
    text.line(format_args!(
        "{} on {device}: {}x{}, {} mode, median of {rounds} interleaved rounds, GPU ms",
        r.scene, r.resolution[0], r.resolution[1], r.mode
    ));
    text.line(format_args!(
        "  {:<10} {:<9} {:>8} {:>8} {:>8} {:>8} {:>8}  {:>7} {:>8}  adaptive: over the cheapest fixed; chose",
        "visibility", "shadows", "gbuffer", "g.trace", "shadow", "frame", "/raster", "SSIM", "RMSE"
    ));
    let shadow_scopes = speculum::renderer::stages::shadow_scopes();
    for v in &r.variants {
        let ms = |p: &str| {
            v.passes_ms
                .get(p)
                .map_or("-".to_string(), |s| format!("{:.2}", s.median))
        };
        let shadow: f64 = shadow_scopes
            .iter()
            .filter_map(|&p| v.passes_ms.get(p))
            .map(|s| s.median)
            .sum();
        let chose = |w: &Option<speculum::headless::StageReport>| w.as_ref().map(|w| w.way.clone());
        let choices: Vec<String> = [chose(&v.visibility_ways), chose(&v.shadow_ways)]
            .into_iter()
            .flatten()
            .collect();
        let adaptive = match (v.over_cheapest_fixed, &v.cheapest_fixed, v.chose_cheapest, v.recheck_ms) {
            (Some(over), Some(fixed), Some(cheapest), Some(recheck)) => format!(
                "{over:.3} of {fixed}; chose {}{}, rechecks {recheck:.2} ms",
                choices.join(", "),
                if cheapest { "" } else { " (NOT the cheapest)" }
            ),
            _ => String::new(),
        };
        text.line(format_args!(
            "  {:<10} {:<9} {:>8} {:>8} {:>8.2} {:>8.2} {:>8.3}  {:>7.4} {:>8.4}  {adaptive}",
            v.visibility,
            v.shadows,
            ms("gbuffer"),
            ms("gbuffer.trace"),
            shadow,
            v.frame_ms.median,
            v.frame_over_raster.median,
            v.ssim_vs_raster,
            v.rmse_vs_raster
        ));
    }
    text.line(format_args!(
        "  adaptive: chose the cheapest ways {}; rechecks at most {:.2}% of a frame; frame over the cheapest fixed at most {:.3} (frame-to-frame noise in it); checks {}",
        if r.adaptive_chose_cheapest { "yes" } else { "NO" },
        100.0 * r.adaptive_recheck_share,
        r.adaptive_over_cheapest,
        if r.valid { "valid" } else { "INVALID" }
    ));
    let timing: speculum::vk::TimingCheck = r.variants.iter().map(|v| &v.timing).collect();
    text.line(format_args!("  {}", crate::cli::timing_note(&timing)));
    text.line(format_args!(
        "  {}",
        crate::cli::steady_note(&r.warmup, Some(&r.rounds_check))
    ));
}
