//! `speculum bench modes|shadows|reflect|lbvh|dynamic|suite`: GPU timing benchmarks
//! that check what they time.

use super::{cell, check_count, check_outputs, progress, GpuArgs, SettingsArgs, Text};
use anyhow::Result;
use clap::{Args, Subcommand};
use speculum::bench::lbvh::{run_case, Options, Report};
use speculum::output::Kind;
use speculum::passes::lbvh::{BvhKind, MortonBits};
use speculum::renderer::{FRAME, SCOPES};
use speculum::report::Header;
use std::path::PathBuf;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// LBVH build (per stage), refit, SAH quality and traversal throughput.
    Lbvh(LbvhArgs),
    /// Time of the reflection passes as the ray-traced share varies (every point and rt
    /// interleaved in one run).
    Reflect(ReflectArgs),
    /// Every mode timed in the same run, interleaved: per-pass medians, frame time
    /// against rt, SSIM/RMSE against rt, and whether ssr < hybrid < rt.
    Modes(ModesArgs),
    /// The shadow sources (map, hybrid, rays) timed in the same run, interleaved:
    /// per-pass medians, frame and shadow.trace time against rays, the traced share,
    /// and SSIM and sun visibility against the rays frame.
    Shadows(ModesArgs),
    /// A dynamic scene's per-frame costs as its bodies grow: simulation, transform,
    /// dynamic BVH rebuild vs refit, tracing, the frame; refit vs rebuilt traversal.
    Dynamic(DynamicArgs),
    /// The fixed, versioned suite: every built-in scene in ssr/hybrid/rt at 960x540
    /// and 1920x1080 and LBVH builds (10K/100K/1M), per pass; --baseline compares.
    Suite(SuiteArgs),
}

#[derive(Args, Clone, Debug)]
pub struct SuiteArgs {
    /// The CI-sized subset: room and drop at 480x270, LBVH 10K and 100K.
    #[arg(long)]
    pub quick: bool,
    /// Measured frames (builds) per case.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Uncounted warm-up frames per case (a dynamic scene is reset after them).
    #[arg(long, default_value_t = 2)]
    pub warmup: u32,
    /// A suite report to compare with, case by case and pass by pass.
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Compare this saved suite report with --baseline instead of running the suite.
    #[arg(long, requires = "baseline")]
    pub compare: Option<PathBuf>,
    /// The smallest relative change counted (the noise band is at least this).
    #[arg(long, default_value_t = 0.10)]
    pub threshold: f64,
    /// Exit 1 when the comparison finds a regression.
    #[arg(long, requires = "baseline")]
    pub fail_on_regression: bool,
    /// Also write the tables as Markdown to this file (`-`: stdout).
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args, Clone, Debug)]
pub struct DynamicArgs {
    /// A scene with a [spawn] table (built-in, or a scene file).
    #[arg(long, default_value = "stress")]
    pub scene: String,
    /// Body counts of a [spawn] scene, each measured in its own run (1..=4000;
    /// default 10 100 1000).
    #[arg(long, num_args = 1..)]
    pub bodies: Vec<u32>,
    /// Instead: particles per side of every cloth of a scene with cloths (2..=512),
    /// each resolution in its own run.
    #[arg(long, num_args = 1..)]
    pub cloth_res: Vec<u32>,
    /// Measured frames per body count.
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// Uncounted warm-up frames (the scene is reset after them).
    #[arg(long, default_value_t = 2)]
    pub warmup: u32,
    /// Rays traced through the rebuilt and the refit BVH at the last frame.
    #[arg(long, default_value_t = 65536)]
    pub rays: u32,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

/// What every benchmark shares: reports, quietness, the device.
#[derive(Args, Clone, Debug)]
pub struct Common {
    /// Write the report as JSON to this file (`-`: stdout; the table goes to stderr).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// No progress bar and no table (errors still go to stderr).
    #[arg(long)]
    pub quiet: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args, Clone, Debug)]
pub struct ModesArgs {
    #[command(flatten)]
    pub view: super::ViewArgs,
    /// Built-in scene names or .obj paths (each timed on its own).
    #[arg(long, num_args = 1.., default_value = "room")]
    pub scene: Vec<String>,
    /// Measured rounds (one frame of every mode, or shadow source, each).
    #[arg(long, default_value_t = 7)]
    pub rounds: u32,
    /// Uncounted warm-up rounds.
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args, Clone, Debug)]
pub struct ReflectArgs {
    #[command(flatten)]
    pub view: super::ViewArgs,
    /// Built-in scene name or .obj path.
    #[arg(long, default_value = "room")]
    pub scene: String,
    /// Measured rounds: one frame of every point and of rt each (after one warm-up round).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args, Clone, Debug)]
pub struct LbvhArgs {
    /// Random triangle soups of these sizes (default 10000 100000 1000000 when no
    /// --scene is given).
    #[arg(long, num_args = 1..)]
    pub tris: Vec<u32>,
    /// Built-in scene names or .obj paths to benchmark as well.
    #[arg(long, num_args = 1..)]
    pub scene: Vec<String>,
    /// Morton code width in bits.
    #[arg(long, default_value = "30", value_parser = super::choice(&MortonBits::ALL, MortonBits::name, MortonBits::about))]
    pub bits: MortonBits,
    /// The trees to build of each case.
    #[arg(long, num_args = 1.., default_values = ["lbvh", "ploc"], value_parser = super::choice(&BvhKind::ALL, BvhKind::name, BvhKind::about))]
    pub builder: Vec<BvhKind>,
    /// Timed repetitions of each build and trace (medians are reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
    /// Rays per ray set (coherent and incoherent).
    #[arg(long, default_value_t = 262144)]
    pub rays: u32,
    /// Rays of each set checked against the CPU reference.
    #[arg(long, default_value_t = 2000)]
    pub check_rays: u32,
    /// Also trace (time and check) these rays: 32 bytes each, little-endian f32
    /// ox,oy,oz,dx,dy,dz,tmin,tmax, no header.
    #[arg(long)]
    pub rays_file: Option<PathBuf>,
    /// Write the traced rays in that format (the --rays-file rays, else the
    /// incoherent set), to trace them with another tracer; needs a single case.
    #[arg(long)]
    pub dump_rays: Option<PathBuf>,
    /// Write their hits: 8 bytes each, f32 t and u32 triangle (in file order after fan
    /// triangulation), a miss as (+inf, 0xFFFFFFFF); needs a single case.
    #[arg(long)]
    pub dump_hits: Option<PathBuf>,
    #[command(flatten)]
    pub common: Common,
}

pub fn run(command: BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Lbvh(a) => lbvh(a),
        BenchCommand::Reflect(a) => reflect(a),
        BenchCommand::Modes(a) => modes(a),
        BenchCommand::Shadows(a) => shadows(a),
        BenchCommand::Dynamic(a) => dynamic(a),
        BenchCommand::Suite(a) => suite(a),
    }
}

fn suite(args: SuiteArgs) -> Result<()> {
    use speculum::bench::suite::{self, SuiteReport};
    let c = &args.common;
    check_count("--frames", args.frames, 1)?;
    if !(args.threshold.is_finite() && (0.0..10.0).contains(&args.threshold)) {
        anyhow::bail!(speculum::Error::Input(format!(
            "--threshold {} is outside 0..10",
            args.threshold
        )));
    }
    check_outputs(
        &[
            ("--json", c.json.as_deref(), Kind::Json),
            ("--markdown", args.markdown.as_deref(), Kind::Json),
        ],
        &[
            ("--baseline", args.baseline.as_deref()),
            ("--compare", args.compare.as_deref()),
        ],
    )?;
    let read = |p: &PathBuf, what: &'static str| -> Result<suite::Baseline> {
        let text = speculum::error::read_text(p, what, speculum::error::bounds::TABLE)?;
        Ok(suite::read_baseline(&text, &p.display().to_string())?)
    };
    let baseline = args.baseline.as_ref().map(|p| read(p, "baseline")).transpose()?;
    if let (Some(new), Some(old)) = (&args.compare, &baseline) {
        // Two saved reports: no GPU work.
        let cmp = suite::compare(&read(new, "suite report")?, old, args.threshold);
        let md = suite::markdown_comparison(&cmp);
        let text = Text::new(&[args.markdown.as_deref()], c.quiet);
        text.line(format_args!("{md}"));
        if let Some(path) = &args.markdown {
            // `-` is standard output (write_atomic's rule).
            speculum::output::write_atomic(path, md.as_bytes())?;
        }
        return regressions(&cmp, args.fail_on_regression);
    }
    let cases = suite::cases(args.quick);
    let text = Text::new(&[c.json.as_deref(), args.markdown.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let bar = progress(
        cases.len() as u64 * (args.warmup + args.frames) as u64,
        "suite",
        c.quiet,
    );
    let mut results = Vec::new();
    for case in &cases {
        results.push(suite::run_case(&ctx, case, args.warmup, args.frames, &mut || {
            bar.inc(1)
        })?);
    }
    bar.finish_and_clear();
    let mut report = SuiteReport {
        header: Header::new("bench.suite", Some(&ctx), None),
        suite_version: suite::SUITE_VERSION,
        quick: args.quick,
        warmup: args.warmup,
        frames: args.frames,
        cases: results,
    };
    report.header.refresh_validation(&ctx);
    let comparison = baseline
        .as_ref()
        .map(|b| suite::compare(&suite::as_baseline(&report.cases), b, args.threshold));
    if let Some(b) = &baseline {
        let missing: Vec<&str> = report
            .cases
            .iter()
            .filter(|c| !b.contains_key(&c.id))
            .map(|c| c.id.as_str())
            .collect();
        if !missing.is_empty() {
            text.line(format_args!("not in the baseline (new cases): {}", missing.join(", ")));
        }
    }
    let md = suite::markdown(&report, comparison.as_deref());
    text.line(format_args!("{md}"));
    if let Some(path) = &c.json {
        super::write_report(path, &report, &text)?;
    }
    if let Some(path) = &args.markdown {
        // `-` is standard output (write_atomic's rule).
        speculum::output::write_atomic(path, md.as_bytes())?;
    }
    super::check_validation(&ctx)?;
    match &comparison {
        Some(cmp) => regressions(cmp, args.fail_on_regression),
        None => Ok(()),
    }
}

/// Says which passes regressed; an error with `fail`.
fn regressions(cmp: &[speculum::bench::suite::Comparison], fail: bool) -> Result<()> {
    use speculum::bench::suite::Verdict;
    let list: Vec<String> = cmp
        .iter()
        .filter(|c| c.verdict == Verdict::Regression)
        .map(|c| format!("{} {} ({:.2}x)", c.case, c.pass, c.ratio))
        .collect();
    if !list.is_empty() {
        let line = format!("{} regression(s): {}", list.len(), list.join(", "));
        if fail {
            anyhow::bail!(line);
        }
        eprintln!("warning: {line}");
    }
    Ok(())
}

fn dynamic(args: DynamicArgs) -> Result<()> {
    use speculum::bench::dynamic::{run_point, DynamicReport};
    let c = &args.common;
    let settings = args.frame.resolve()?;
    check_count("--frames", args.frames, 1)?;
    check_count("--warmup", args.warmup, 0)?;
    check_count("--rays", args.rays, 1)?;
    check_outputs(
        &[("--json", c.json.as_deref(), Kind::Json)],
        &[("--settings", args.frame.settings.as_deref())],
    )?;
    // Every body count's scene first: a bad one fails before any GPU work.
    if !args.bodies.is_empty() && !args.cloth_res.is_empty() {
        anyhow::bail!("give --bodies or --cloth-res, not both");
    }
    let by_cloth = !args.cloth_res.is_empty();
    let scenes = if !by_cloth {
        let counts = if args.bodies.is_empty() {
            vec![10, 100, 1000]
        } else {
            args.bodies.clone()
        };
        counts
            .iter()
            .map(|&n| {
                let mut s = speculum::scene::load(&args.scene)?;
                s.set_spawn_count(n)?;
                Ok(s)
            })
            .collect::<Result<Vec<_>>>()?
    } else {
        args.cloth_res
            .iter()
            .map(|&n| {
                let mut s = speculum::scene::load(&args.scene)?;
                if s.cloths.is_empty() {
                    anyhow::bail!(
                        "--cloth-res needs a scene with cloths (such as cloth); '{}' has none",
                        s.name
                    );
                }
                for c in &mut s.cloths {
                    c.resolution = n;
                }
                s.validate()?;
                Ok(s)
            })
            .collect::<Result<Vec<_>>>()?
    };
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let per = (args.frames + args.warmup) as u64;
    let bar = progress(per * scenes.len() as u64, "bench dynamic", c.quiet);
    let mut points = Vec::new();
    for scene in &scenes {
        points.push(run_point(
            &ctx,
            scene,
            &settings,
            args.warmup,
            args.frames,
            args.rays,
            &mut || bar.inc(1),
        )?);
    }
    bar.finish_and_clear();
    let (first, last) = (&points[0], &points[points.len() - 1]);
    let report = DynamicReport {
        header: Header::new("bench.dynamic", Some(&ctx), Some(&settings)),
        scene: args.scene.clone(),
        resolution: [settings.width, settings.height],
        frames: args.frames,
        warmup_frames: args.warmup,
        rebuild_growth: last.rebuild_ms.median / first.rebuild_ms.median,
        triangle_growth: last.dynamic_triangles as f64 / first.dynamic_triangles as f64,
        valid: points.iter().all(|p| p.valid),
        points,
    };
    // Which rebuild the bodies get (the renderer's rule).
    let rigid = scenes
        .iter()
        .all(|s| speculum::passes::lbvh::rigid::applies(s, settings.rigid_order));
    let rebuild = match (by_cloth, rigid) {
        (true, _) => "",
        (false, true) => "; bodies rebuilt in their own order, rigid_order",
        (false, false) => "; every triangle sorted at each rebuild",
    };
    text.line(format_args!(
        "{} on {}: {}x{}, median of {} frames per body count (ms; sim.rigid is CPU{rebuild})",
        report.scene, ctx.device_name, settings.width, settings.height, args.frames
    ));
    text.line(format_args!(
        "  {:>6} {:>9} {:>9} {:>13} {:>9} {:>8} {:>7} {:>10} {:>9} {:>9} {:>9}",
        if by_cloth { "cloth" } else { "bodies" },
        "tris",
        "sim.rigid",
        if by_cloth { "sim.cloth" } else { "sim.transform" },
        "rebuild",
        "refit",
        "ratio",
        "rt.reflect",
        "frame",
        "trace new",
        "trace old"
    ));
    for p in &report.points {
        text.line(format_args!(
            "  {:>6} {:>9} {:>9.2} {:>13.2} {:>9.2} {:>8.2} {:>7.3} {:>10.1} {:>9.1} {:>9.2} {:>9.2}",
            if by_cloth { p.cloth_resolution } else { p.bodies },
            p.dynamic_triangles,
            p.sim_rigid_ms.median,
            if by_cloth {
                p.sim_cloth_ms.median
            } else {
                p.sim_transform_ms.median
            },
            p.rebuild_ms.median,
            p.refit_ms.median,
            p.refit_over_rebuild,
            p.rt_reflect_ms.median,
            p.frame_ms.median,
            p.trace_rebuilt_ms,
            p.trace_refit_ms
        ));
    }
    text.line(format_args!(
        "  rebuild grows {:.2}x for {:.2}x the triangles; checks {}",
        report.rebuild_growth,
        report.triangle_growth,
        if report.valid { "valid" } else { "INVALID" }
    ));
    let timing: speculum::vk::TimingCheck = report.points.iter().map(|p| &p.timing).collect();
    text.line(format_args!("  {}", super::timing_note(&timing)));
    if let Some(path) = &c.json {
        super::write_report(path, &report, &text)?;
    }
    super::check_validation(&ctx)?;
    valid_or_fail(report.valid)
}

fn valid_or_fail(valid: bool) -> Result<()> {
    if !valid {
        anyhow::bail!("a benchmark check failed (see the report)");
    }
    Ok(())
}

/// A benchmark case's triangles: its name, vertices and indices.
type Case = (String, Vec<speculum::gpu_types::GpuVertex>, Vec<u32>);

fn lbvh(args: LbvhArgs) -> Result<()> {
    let c = &args.common;
    check_count("--repeats", args.repeats, 1)?;
    if args.rays == 0 {
        anyhow::bail!(speculum::Error::Input(
            "--rays 0: each ray set needs at least one ray".into()
        ));
    }
    let file_rays = match &args.rays_file {
        Some(p) => {
            let bytes = speculum::error::read_file(p, "rays file", speculum::error::bounds::RAYS)?;
            Some(speculum::bench::rays_file::read_rays(&bytes, &p.display().to_string())?)
        }
        None => None,
    };
    let dumping = args.dump_rays.is_some() || args.dump_hits.is_some();
    for p in [&args.dump_rays, &args.dump_hits].into_iter().flatten() {
        if p.as_os_str() == "-" {
            anyhow::bail!(speculum::Error::Input(
                "--dump-rays/--dump-hits write binary files: give a path, not -".into()
            ));
        }
        speculum::output::check(p, Kind::Json)?;
    }
    let opts = Options {
        repeats: args.repeats,
        rays: args.rays,
        check_rays: args.check_rays,
        bits: args.bits,
        builders: args.builder.clone(),
        file_rays,
        keep_hits: dumping,
    };
    let mut inputs = vec![("--rays-file", args.rays_file.as_deref())];
    inputs.extend(args.scene.iter().map(|s| ("--scene", super::input_file(s))));
    check_outputs(
        &[
            ("--json", c.json.as_deref(), Kind::Json),
            ("--dump-rays", args.dump_rays.as_deref(), Kind::Json),
            ("--dump-hits", args.dump_hits.as_deref(), Kind::Json),
        ],
        &inputs,
    )?;
    let cases = lbvh_cases(&args)?;
    if dumping && cases.len() * args.builder.len() != 1 {
        anyhow::bail!(speculum::Error::Input(format!(
            "--dump-rays/--dump-hits need a single case (one --tris or one --scene, one --builder), not {}",
            cases.len() * args.builder.len()
        )));
    }
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    text.line(format_args!(
        "LBVH on {} ({}-bit Morton, median (p10–p90) of {} runs, GPU ms)",
        ctx.device_name,
        args.bits.bits(),
        opts.repeats
    ));
    let runs = (cases.len() * opts.builders.len()) as u64;
    let bar = progress(runs * (opts.repeats as u64 + 1), "bench lbvh", c.quiet);
    let mut results = Vec::new();
    for (name, v, i) in &cases {
        for &kind in &opts.builders {
            let case = run_case(&ctx, name, v, i, &opts, kind, &mut || bar.inc(1))?;
            bar.suspend(|| print_lbvh_case(&text, &case));
            results.push(case);
        }
    }
    bar.finish_and_clear();
    if let Some(kept) = results.first().and_then(|c| c.kept.as_ref()) {
        dump_rays(&args, kept)?;
    }
    let valid = results.iter().all(|c| c.valid);
    let report = Report {
        header: Header::new("bench.lbvh", Some(&ctx), None),
        options: opts,
        cases: results,
        valid,
    };
    if let Some(path) = &c.json {
        super::write_report(path, &report, &text)?;
    }
    super::check_validation(&ctx)?;
    valid_or_fail(valid)
}

/// `--dump-rays` and `--dump-hits`: the single case's rays and hits, written together.
fn dump_rays(
    args: &LbvhArgs,
    (rays, hits): &(Vec<speculum::gpu_types::Ray>, Vec<speculum::gpu_types::Hit>),
) -> Result<()> {
    let mut out = speculum::output::Batch::default();
    if let Some(p) = &args.dump_rays {
        out.add(p, speculum::bench::rays_file::write_rays(rays));
    }
    if let Some(p) = &args.dump_hits {
        out.add(p, speculum::bench::rays_file::write_hits(hits));
    }
    Ok(out.commit()?)
}

/// Every case's triangles, loaded before any GPU work (a bad scene fails first): the
/// soups of `--tris` (10K, 100K, 1M without `--tris` or `--scene`), then the scenes.
fn lbvh_cases(args: &LbvhArgs) -> Result<Vec<Case>> {
    let mut tris = args.tris.clone();
    if tris.is_empty() && args.scene.is_empty() {
        tris = vec![10_000, 100_000, 1_000_000];
    }
    let mut cases = Vec::new();
    for &n in &tris {
        if n == 0 {
            anyhow::bail!("--tris 0: a BVH needs at least one triangle");
        }
        if n > speculum::passes::lbvh::MAX_TRIANGLES {
            anyhow::bail!(
                "--tris {n}: more than the LBVH's {} triangles",
                speculum::passes::lbvh::MAX_TRIANGLES
            );
        }
        let size = speculum::scene::soup::default_size(n as usize);
        let (v, i) = speculum::scene::soup::random_soup(n as usize, 1.0, size, n as u64);
        cases.push((format!("soup-{n}"), v, i));
    }
    for name in &args.scene {
        // The model alone: a floor would be triangles the benchmark did not ask for.
        let scene = speculum::scene::load_with(name, speculum::scene::Floor::None)?;
        cases.push((scene.name.clone(), scene.vertices, scene.indices));
    }
    Ok(cases)
}

/// One case's lines: the build and its stages, tree quality and trace rates with the
/// checks, and the rays file's trace when there is one.
fn print_lbvh_case(text: &Text, case: &speculum::bench::lbvh::CaseReport) {
    let stages: Vec<String> = case
        .builder
        .stages()
        .iter()
        .map(|s| format!("{} {:.3}", s.trim_start_matches("lbvh."), case.stages_ms.median(s)))
        .collect();
    let untimed = match case.untimed_rounds {
        0 => String::new(),
        r => format!(" (+{r} rounds untimed)"),
    };
    text.line(format_args!(
        "{:<14} {:>9} tris  build {}{untimed} ({:7.2} Mtris/s) [{}]  refit {}  compact {}",
        format!("{} {}", case.name, case.builder.name()),
        case.triangles,
        cell(Some(case.build_ms)),
        case.mtris_per_s,
        stages.join(", "),
        cell(Some(case.refit_ms)),
        cell(Some(case.compact_ms))
    ));
    let checks = if case.valid {
        format!("valid; {}", super::timing_note(&case.timing))
    } else {
        format!(
            "INVALID: {:?} {} {} mismatches",
            case.invariant_error, case.coherent.mismatches, case.incoherent.mismatches
        )
    };
    text.line(format_args!(
        "{:<14} SAH {:.2} vs CPU binned {:.2} (ratio {:.3}); {:.1} B/tri; coherent {:.2} Mrays/s, incoherent {:.2} Mrays/s; {checks}",
        "",
        case.sah,
        case.sah_cpu_binned,
        case.sah_ratio,
        case.bytes_per_triangle,
        case.coherent.mrays_per_s,
        case.incoherent.mrays_per_s,
    ));
    if let Some(f) = &case.file {
        text.line(format_args!(
            "{:<14} rays file: {} rays, {} ({:.1} Mrays/s), {:.1}% hit, {} of {} checked differ",
            "",
            f.rays,
            cell(Some(f.trace_ms)),
            f.mrays_per_s,
            100.0 * f.hit_fraction,
            f.mismatches,
            f.checked
        ))
    }
    for a in case.embree.iter().flatten() {
        let sets = [
            ("coherent", Some(&a.coherent)),
            ("incoherent", Some(&a.incoherent)),
            ("file", a.file.as_ref()),
        ];
        let rays: Vec<String> = sets
            .iter()
            .filter_map(|(name, r)| {
                r.map(|r| {
                    format!(
                        "{name} {:.2} Mrays/s (Speculum {:.2}x; hits {} agree, {} ties, {} differ)",
                        r.mrays_per_s, r.speed_ratio, r.agree, r.ties, r.disagree
                    )
                })
            })
            .collect();
        text.line(format_args!(
            "{:<14} Embree {} ({} CPU threads, wall ms): build {} (Speculum {:.2}x its time); {}",
            "",
            a.quality.to_uppercase(),
            a.threads,
            cell(Some(a.build_ms)),
            a.build_ratio,
            rays.join(", ")
        ));
    }
}

fn reflect(args: ReflectArgs) -> Result<()> {
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
    let bar = progress(renderers * (args.frames as u64 + 1), "bench reflect", c.quiet);
    let mut r = speculum::bench::reflect::run(&ctx, &scene, &settings, 1, args.frames, &mut || bar.inc(1))?;
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
    text.line(format_args!("  {}", super::timing_note(&r.timing)));
    if let Some(path) = &c.json {
        super::write_report(path, &r, &text)?;
    }
    super::check_validation(&ctx)?;
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
    check_count("--warmup", args.warmup, 0)?;
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
    let per_scene = renderers * (args.rounds + args.warmup) as u64;
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
        super::write_report(path, &report, &text)?;
    }
    super::check_validation(&ctx)?;
    valid_or_fail(all_valid)
}

fn modes(args: ModesArgs) -> Result<()> {
    use speculum::bench::modes::{run, ModesReport};
    let (warmup, rounds) = (args.warmup, args.rounds);
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
            warmup_rounds: warmup,
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
    let header: String = r.modes.iter().map(|m| format!(" {:>10}", m.mode)).collect();
    text.line(format_args!("  {:<14}{header}", "pass (ms)"));
    let row = |name: &str, f: &dyn Fn(&speculum::bench::modes::ModeResult) -> String| {
        let cells: String = r.modes.iter().map(|m| format!(" {:>10}", f(m))).collect();
        text.line(format_args!("  {name:<14}{cells}"));
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
    text.line(format_args!(
        "  ssr < hybrid < rt: {}; checks {}",
        if r.ordered { "yes" } else { "NO" },
        if r.valid { "valid" } else { "INVALID" }
    ));
    let timing: speculum::vk::TimingCheck = r.modes.iter().map(|m| &m.timing).collect();
    text.line(format_args!("  {}", super::timing_note(&timing)));
}

fn shadows(args: ModesArgs) -> Result<()> {
    use speculum::bench::shadows::{run, ShadowsReport};
    let (warmup, rounds) = (args.warmup, args.rounds);
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
            warmup_rounds: warmup,
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
    text.line(format_args!("  {}", super::timing_note(&timing)));
}
