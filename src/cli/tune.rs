//! `speculum tune` (a settings sweep against `rt`) and `speculum plot` (its plot
//! again, from the CSV). See `speculum::tune`.

use super::{progress, GpuArgs, Text};
use anyhow::Result;
use clap::Args;
use speculum::output::{Batch, Kind};
use speculum::tune::{self, sweep::Sweep, PointResult, DEFAULT_KEY};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

#[derive(Args, Clone, Debug)]
pub struct TuneArgs {
    /// Sweep file (TOML; see docs/tuning.md); optional with --axis.
    pub sweep: Option<PathBuf>,
    /// An axis from the command line, `field=v1,v2,...` (replaces the file's axis of
    /// that name); repeatable.
    #[arg(long)]
    pub axis: Vec<String>,
    /// Output folder (created if needed): points.csv, points.json, pareto.png, best.json.
    #[arg(long, default_value = "tune")]
    pub out: PathBuf,
    /// Quality floor for best.json: the fastest point with at least this SSIM vs rt.
    #[arg(long, default_value_t = 0.99)]
    pub min_ssim: f64,
    /// Skip the points already in OUT/points.csv (same scene and axis values).
    #[arg(long)]
    pub resume: bool,
    /// Rounds that time the best point against the base settings again, alternating,
    /// for a speedup the choice of the best does not bias (0: skip).
    #[arg(long, default_value_t = 9)]
    pub confirm: u32,
    /// No progress bar and no text output.
    #[arg(long)]
    pub quiet: bool,
    /// Scenes to sweep (built-in names, scene files or models; repeatable): they
    /// replace the file's `scenes` (default: room).
    #[arg(long)]
    pub scene: Vec<String>,
    /// Width in pixels [default: the file's, else 960].
    #[arg(long)]
    pub width: Option<u32>,
    /// Height in pixels [default: the file's, else 540].
    #[arg(long)]
    pub height: Option<u32>,
    #[command(flatten)]
    pub view: super::ViewArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args, Clone, Debug)]
pub struct PlotArgs {
    /// A points.csv written by `speculum tune`.
    pub csv: PathBuf,
    /// The plot to write.
    #[arg(long, default_value = "pareto.png")]
    pub out: PathBuf,
}

/// The settings of result `key` (the base settings with its axis values).
fn settings_of(sweep: &Sweep, results: &[PointResult], key: &str) -> Result<speculum::Settings> {
    let mut s = sweep.base.clone();
    if key != DEFAULT_KEY {
        for (n, v) in &results.iter().find(|r| r.key == key).expect("a measured key").values {
            s = s.with_field(n, v)?;
        }
    }
    Ok(s)
}

fn write_outputs(
    dir: &Path,
    axes: &[String],
    results: &mut [PointResult],
    min_ssim: f64,
    sweep: &Sweep,
) -> Result<Option<String>> {
    tune::mark_pareto(results);
    let best = tune::best(results, min_ssim);
    let mut batch = Batch::default();
    batch.add(&dir.join("points.csv"), tune::to_csv(axes, results).into_bytes());
    batch.add(
        &dir.join("points.json"),
        speculum::report::to_json(&results).into_bytes(),
    );
    batch.add(&dir.join("pareto.png"), tune::plot::pareto_png(results)?);
    if let Some(key) = &best {
        let settings = settings_of(sweep, results, key)?;
        batch.add(
            &dir.join("best.json"),
            speculum::report::to_json(&settings).into_bytes(),
        );
    }
    batch.commit()?;
    Ok(best)
}

/// The sweep (its file, `--axis`), with the command line's scenes and size in place of
/// the file's, as in every command; every value checked before any GPU work.
fn checked_sweep(args: &TuneArgs) -> Result<Sweep> {
    let (text, what) = match &args.sweep {
        Some(p) => (
            speculum::error::read_text(p, "sweep file", speculum::error::bounds::TEXT)?,
            p.display().to_string(),
        ),
        None => (String::new(), "(command line)".to_string()),
    };
    let mut sweep = Sweep::parse(&text, &what, &args.axis)?;
    // The command line's scenes and size replace the file's, as in every command.
    if !args.scene.is_empty() {
        sweep.scenes = args.scene.clone();
    }
    for (flag, field, value) in [("--width", "width", args.width), ("--height", "height", args.height)] {
        if let Some(v) = value {
            sweep.base = sweep
                .base
                .with_field(field, &v.to_string())
                .map_err(|e| speculum::Error::Input(format!("{flag}: {e}")))?;
        }
    }
    if !(0.0..=1.0).contains(&args.min_ssim) {
        anyhow::bail!(speculum::Error::Input(format!(
            "--min-ssim {} is outside 0..=1",
            args.min_ssim
        )));
    }
    for s in &sweep.scenes {
        if s.contains(',') || s.contains('"') {
            anyhow::bail!(speculum::Error::Input(format!(
                "scene '{s}': names in a sweep cannot hold commas or quotes"
            )));
        }
    }
    speculum::metrics::check_size(sweep.base.width, sweep.base.height)?;
    speculum::output::check_dir(&args.out)?;
    Ok(sweep)
}

/// The points already measured in `csv_path` with `--resume` (none without it), whose
/// axes must be this sweep's.
fn resumed(args: &TuneArgs, csv_path: &std::path::Path, axes: &[String]) -> Result<Vec<PointResult>> {
    let mut results: Vec<PointResult> = Vec::new();
    if args.resume && csv_path.exists() {
        let (old_axes, old) = tune::from_csv(&speculum::error::read_text(
            csv_path,
            "points CSV",
            speculum::error::bounds::TABLE,
        )?)?;
        if old_axes != axes {
            anyhow::bail!(speculum::Error::Input(format!(
                "--resume: {} has axes {old_axes:?}, this sweep {axes:?}",
                csv_path.display()
            )));
        }
        results = old;
    }
    Ok(results)
}

/// The best point's line, and with `--confirm` its frame time against the default's
/// in alternating rounds on every scene.
fn report_best(
    out: &Text,
    ctx: &std::sync::Arc<speculum::vk::Context>,
    (args, sweep): (&TuneArgs, &Sweep),
    scenes: &[(String, speculum::scene::Scene)],
    results: &[PointResult],
    best: Option<&str>,
) -> Result<()> {
    let ratio = |key: &str| {
        let rs: Vec<&PointResult> = results.iter().filter(|r| r.key == key).collect();
        rs.iter().map(|r| r.frame_over_rt.median).sum::<f64>() / rs.len().max(1) as f64
    };
    match best {
        Some(key) => {
            out.line(format_args!(
                "best with SSIM >= {}: {key} (frame/rt {:.3}; default {:.3}) -> {}",
                args.min_ssim,
                ratio(key),
                ratio(DEFAULT_KEY),
                args.out.join("best.json").display()
            ));
            if args.confirm > 0 && key != DEFAULT_KEY {
                let candidate = settings_of(sweep, results, key)?;
                for (name, scene) in scenes {
                    match tune::confirm(ctx, scene, sweep, &candidate, args.confirm)? {
                        Some(s) => out.line(format_args!(
                            "  confirmed on {name} ({} alternating rounds): default / best frame time {:.3} (p10 {:.3}, p90 {:.3})",
                            s.samples, s.median, s.p10, s.p90
                        )),
                        None => out.line(format_args!(
                            "  warning: not confirmed on {name}: no round's timings passed their self-check (a busy machine)"
                        )),
                    }
                }
            }
        }
        None => out.line(format_args!("no point reaches SSIM {} (no best.json)", args.min_ssim)),
    }
    Ok(())
}

pub fn run(args: TuneArgs) -> Result<()> {
    // Everything that can be known before the GPU is touched is checked here.
    let sweep = checked_sweep(&args)?;
    let points = sweep.points()?;
    let axes: Vec<String> = sweep.axes.iter().map(|(n, _)| n.clone()).collect();
    let csv_path = args.out.join("points.csv");
    let mut results = resumed(&args, &csv_path, &axes)?;
    let scenes: Vec<_> = sweep
        .scenes
        .iter()
        .map(|s| args.view.load(s).map(|scene| (s.clone(), scene)))
        .collect::<Result<_>>()?;
    let mut todo: Vec<(String, Vec<(String, tune::sweep::Point)>)> = Vec::new();
    let done: HashSet<(String, String)> = results.iter().map(|r| (r.scene.clone(), r.key.clone())).collect();
    for (name, _) in &scenes {
        let mut list = vec![(DEFAULT_KEY.to_string(), tune::default_point(&sweep))];
        list.extend(points.iter().map(|p| (p.key(), p.clone())));
        list.retain(|(k, _)| !done.contains(&(name.clone(), k.clone())));
        todo.push((name.clone(), list));
    }
    let total: usize = todo.iter().map(|(_, l)| l.len()).sum();
    let out = Text::new(&[], args.quiet);
    out.line(format_args!(
        "tune: {} points x {} scene(s) (+ default), {} to measure, {}x{}; {} already in {}",
        points.len(),
        scenes.len(),
        total,
        sweep.base.width,
        sweep.base.height,
        results.len(),
        csv_path.display()
    ));
    let ctx = args.gpu.context()?;
    std::fs::create_dir_all(&args.out).map_err(|e| speculum::Error::Output {
        path: args.out.clone(),
        detail: e.to_string(),
    })?;
    let bar = progress(total as u64, "tune", args.quiet);
    for ((name, scene), (_, list)) in scenes.iter().zip(&todo) {
        tune::measure_scene(&ctx, scene, name, &sweep, list, &mut |r| {
            bar.inc(1);
            if let Some(w) = &r.timing_warning {
                bar.suspend(|| eprintln!("warning: {} point {}: {w}", r.scene, r.key));
            }
            results.push(r);
            // The CSV is rewritten after every point, so an interrupted sweep resumes.
            speculum::output::write_atomic(&csv_path, tune::to_csv(&axes, &results).as_bytes())
        })?;
    }
    bar.finish_and_clear();
    let best = write_outputs(&args.out, &axes, &mut results, args.min_ssim, &sweep)?;
    let front = results.iter().filter(|r| r.pareto_ssim).count();
    out.line(format_args!(
        "{} points measured on {}; {front} on the time/SSIM front",
        results.len(),
        ctx.device_name
    ));
    report_best(&out, &ctx, (&args, &sweep), &scenes, &results, best.as_deref())?;
    out.line(format_args!("wrote {}", args.out.display()));
    super::check_validation(&ctx)
}

pub fn plot(args: PlotArgs) -> Result<()> {
    speculum::output::check(&args.out, Kind::Png)?;
    let text = speculum::error::read_text(&args.csv, "points CSV", speculum::error::bounds::TABLE)?;
    let (_, results) = tune::from_csv(&text)?;
    speculum::output::write_atomic(&args.out, &tune::plot::pareto_png(&results)?)?;
    println!("wrote {}", args.out.display());
    Ok(())
}
