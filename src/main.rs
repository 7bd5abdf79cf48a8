//! The `speculum` command line: `render` (headless, the default) and `devices`.

use anyhow::{Context as _, Result};
use clap::{Args, Parser, Subcommand};
use speculum::headless;
use speculum::vk::{list_devices, Context, ContextDesc};
use speculum::Settings;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "speculum",
    version,
    about = "Hybrid SSR + GPU-ray-traced reflections on Vulkan"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene headless to a PNG and report per-pass GPU timings.
    Render(RenderArgs),
    /// List the Vulkan devices, in the order --device INDEX counts them.
    Devices,
    /// SSIM (on luma; Gaussian 11x11, sigma 1.5) and RMSE (RGB, [0, 1]) of two PNGs.
    Compare {
        a: PathBuf,
        b: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// GPU timing benchmarks (each also checks what it times).
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// LBVH build (per stage), refit, SAH quality and traversal throughput.
    Lbvh(BenchLbvhArgs),
    /// Time of ssr.classify, ssr.trace, ssr.compact and rt.reflect as the ray-traced share
    /// varies (every point and rt interleaved in one run).
    Reflect(BenchReflectArgs),
    /// Every mode timed in the same run, interleaved: per-pass medians, frame time
    /// against rt, SSIM/RMSE against rt, and whether ssr < hybrid < rt.
    Modes(BenchModesArgs),
}

#[derive(Args)]
struct BenchModesArgs {
    /// Built-in scene names or .obj paths (each timed on its own).
    #[arg(long, num_args = 1.., default_value = "room")]
    scene: Vec<String>,
    #[arg(long, default_value_t = Settings::default().width)]
    width: u32,
    #[arg(long, default_value_t = Settings::default().height)]
    height: u32,
    /// Measured rounds (one frame of every mode each).
    #[arg(long, default_value_t = 7)]
    rounds: u32,
    /// Uncounted warm-up rounds.
    #[arg(long, default_value_t = 1)]
    warmup: u32,
    /// Settings file (JSON) with any fields of the settings struct (the mode is ignored).
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Write the reports as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    gpu: GpuArgs,
}

#[derive(Args)]
struct BenchReflectArgs {
    /// Built-in scene name or .obj path.
    #[arg(long, default_value = "room")]
    scene: String,
    #[arg(long, default_value_t = Settings::default().width)]
    width: u32,
    #[arg(long, default_value_t = Settings::default().height)]
    height: u32,
    /// Measured rounds: one frame of every point and of rt each (after one warm-up round).
    #[arg(long, default_value_t = 3)]
    frames: u32,
    /// Write the report as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    gpu: GpuArgs,
}

#[derive(Args)]
struct BenchLbvhArgs {
    /// Random triangle soups of these sizes (default 10000 100000 1000000 when no
    /// --scene is given).
    #[arg(long, num_args = 1..)]
    tris: Vec<u32>,
    /// Built-in scene names or .obj paths to benchmark as well.
    #[arg(long, num_args = 1..)]
    scene: Vec<String>,
    /// Morton code width: 30 or 63 bits.
    #[arg(long, default_value = "30", value_parser = ["30", "63"])]
    bits: String,
    /// Timed repetitions of each build and trace (medians are reported).
    #[arg(long, default_value_t = 5)]
    repeats: u32,
    /// Rays per ray set (coherent and incoherent).
    #[arg(long, default_value_t = 262144)]
    rays: u32,
    /// Rays of each set checked against the CPU reference.
    #[arg(long, default_value_t = 2000)]
    check_rays: u32,
    /// Write the report as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    gpu: GpuArgs,
}

#[derive(Args, Clone)]
struct RenderArgs {
    /// Built-in scene name (room) or a path to an .obj file.
    #[arg(long, default_value = "room")]
    scene: String,
    /// Width in pixels.
    #[arg(long, default_value_t = Settings::default().width)]
    width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = Settings::default().height)]
    height: u32,
    /// Reflection mode: raster, ssr, hybrid (default), rt (every reflective pixel
    /// traced: the reference) or provenance (pixels coloured by reflection source).
    #[arg(long)]
    mode: Option<String>,
    /// Frames to measure (after the warm-up frames, which are not counted).
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Also render the same frame in `rt` mode (the reference) and report SSIM and RMSE
    /// against it; the reference image is written next to --out as *_rt.png.
    #[arg(long)]
    reference: bool,
    /// Uncounted warm-up frames (pipeline JIT, caches).
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
    /// Also write the timings as JSON to this file.
    #[arg(long)]
    timings: Option<PathBuf>,
    /// Also write the SSR fail mask as a PNG, coloured by reason (see README).
    #[arg(long)]
    fail_mask: Option<PathBuf>,
    /// Settings file (JSON) with any fields of the settings struct; flags override it.
    #[arg(long)]
    settings: Option<PathBuf>,
    #[command(flatten)]
    gpu: GpuArgs,
}

impl Default for RenderArgs {
    fn default() -> Self {
        let cli = Cli::parse_from(["speculum", "render"]);
        match cli.command {
            Some(Command::Render(a)) => a,
            _ => unreachable!("`render` parses to Render"),
        }
    }
}

/// Device choice and validation, shared by every command that uses the GPU.
#[derive(Args, Clone)]
struct GpuArgs {
    /// Device by index or name substring (see `speculum devices`).
    #[arg(long)]
    device: Option<String>,
    /// Enable Vulkan validation + synchronization validation (also SPECULUM_VALIDATION=1).
    #[arg(long)]
    validation: bool,
}

impl GpuArgs {
    fn context(&self) -> Result<std::sync::Arc<Context>> {
        let validation = self.validation || validation_from_env();
        Ok(Context::new(&ContextDesc {
            validation,
            device: self.device.clone(),
        })?)
    }
}

/// Fails when validation reported anything (0 when validation is off).
fn check_validation(ctx: &Context) -> Result<()> {
    if ctx.validation_messages() > 0 {
        anyhow::bail!("{} validation message(s) reported", ctx.validation_messages());
    }
    Ok(())
}

fn validation_from_env() -> bool {
    std::env::var("SPECULUM_VALIDATION").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The settings file's values, or the defaults.
fn load_settings(path: Option<&std::path::Path>) -> Result<Settings> {
    Ok(match path {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read settings file '{}'", path.display()))?;
            serde_json::from_str::<Settings>(&text)
                .with_context(|| format!("invalid settings file '{}'", path.display()))?
        }
        None => Settings::default(),
    })
}

fn render(args: RenderArgs) -> Result<()> {
    let mut settings = load_settings(args.settings.as_deref())?;
    settings.width = args.width;
    settings.height = args.height;
    if let Some(mode) = &args.mode {
        settings.mode = mode.parse()?;
    }
    settings.validate()?;
    let scene = speculum::scene::load(&args.scene)?;
    let ctx = args.gpu.context()?;
    let plan = headless::FramePlan {
        warmup: args.warmup,
        frames: args.frames,
        reference: args.reference,
    };
    let rendered = headless::render(&ctx, &scene, &settings, plan)?;
    headless::save_png(&args.out, &rendered.rgba, settings.width, settings.height)?;
    if let Some(reference) = &rendered.reference_rgba {
        let stem = args
            .out
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "frame".into());
        let path = args.out.with_file_name(format!("{stem}_rt.png"));
        headless::save_png(&path, reference, settings.width, settings.height)?;
        println!("wrote {}", path.display());
    }

    if let Some(path) = &args.fail_mask {
        headless::save_png(path, &rendered.fail_mask_rgba, settings.width, settings.height)?;
        println!("wrote {}", path.display());
    }

    let r = &rendered.report;
    println!(
        "{} on {}: {}x{}, median of {} frames",
        r.scene, r.device, r.resolution[0], r.resolution[1], r.frames
    );
    for (name, ms) in &r.passes_ms {
        println!("  {name:<14} {ms:8.3} ms");
    }
    println!("  {:<14} {:8.3} ms", "frame", r.frame_ms);
    println!(
        "  reflective pixels {}, ray traced {} ({:.1}%)",
        r.reflective_pixels,
        r.failed_pixels,
        100.0 * r.rt_pixel_fraction
    );
    if let (Some(ssim), Some(rmse)) = (r.ssim, r.rmse) {
        println!(
            "  vs rt reference: SSIM {ssim:.4}, RMSE {rmse:.4}; reference frame {:.3} ms",
            r.reference_frame_ms.unwrap_or(f64::NAN)
        );
    }
    if let Some(n) = r.validation_messages {
        println!("  validation messages: {n}");
    }
    println!("wrote {}", args.out.display());
    if let Some(path) = &args.timings {
        let json = serde_json::to_string_pretty(r)?;
        std::fs::write(path, json + "\n").with_context(|| format!("cannot write '{}'", path.display()))?;
        println!("wrote {}", path.display());
    }
    check_validation(&ctx)?;
    Ok(())
}

fn bench_lbvh(args: BenchLbvhArgs) -> Result<()> {
    use speculum::bench::lbvh::{run_case, Options, Report, STAGES};
    use speculum::passes::lbvh::MortonBits;
    let bits = if args.bits == "63" {
        MortonBits::Bits63
    } else {
        MortonBits::Bits30
    };
    let opts = Options {
        repeats: args.repeats.max(1),
        rays: args.rays.max(1),
        check_rays: args.check_rays,
        bits,
    };
    let mut tris = args.tris.clone();
    if tris.is_empty() && args.scene.is_empty() {
        tris = vec![10_000, 100_000, 1_000_000];
    }
    // Load every input first: a bad scene fails before any GPU work.
    let mut inputs = Vec::new();
    for &n in &tris {
        if n == 0 {
            anyhow::bail!("--tris 0: a BVH needs at least one triangle");
        }
        let (v, i) = speculum::scene::soup::random_soup(
            n as usize,
            1.0,
            speculum::scene::soup::default_size(n as usize),
            n as u64,
        );
        inputs.push((format!("soup-{n}"), v, i));
    }
    for name in &args.scene {
        let scene = speculum::scene::load(name)?;
        inputs.push((scene.name.clone(), scene.vertices, scene.indices));
    }
    let ctx = args.gpu.context()?;
    println!(
        "LBVH on {} ({}-bit Morton, median of {} runs)",
        ctx.device_name, args.bits, opts.repeats
    );
    let mut cases = Vec::new();
    for (name, v, i) in &inputs {
        let c = run_case(&ctx, name, v, i, &opts)?;
        let stages: Vec<String> = STAGES
            .iter()
            .map(|s| {
                format!(
                    "{} {:.3}",
                    s.trim_start_matches("lbvh."),
                    c.stages_ms.get(*s).copied().unwrap_or(f64::NAN)
                )
            })
            .collect();
        println!(
            "{:<14} {:>9} tris  build {:9.3} ms ({:7.2} Mtris/s) [{}]  refit {:.3} ms",
            c.name,
            c.triangles,
            c.build_ms,
            c.mtris_per_s,
            stages.join(", "),
            c.refit_ms
        );
        println!(
            "{:<14} SAH {:.2} vs CPU binned {:.2} (ratio {:.3}); {:.1} B/tri; coherent {:.2} Mrays/s, incoherent {:.2} Mrays/s; {}",
            "",
            c.sah_lbvh,
            c.sah_cpu_binned,
            c.sah_ratio,
            c.bytes_per_triangle,
            c.coherent.mrays_per_s,
            c.incoherent.mrays_per_s,
            if c.valid { "valid".to_string() } else { format!("INVALID: {:?} {} {} mismatches", c.invariant_error, c.coherent.mismatches, c.incoherent.mismatches) }
        );
        cases.push(c);
    }
    let valid = cases.iter().all(|c| c.valid);
    let report = Report {
        device: ctx.device_name.clone(),
        repeats: opts.repeats,
        cases,
        valid,
    };
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)? + "\n")
            .with_context(|| format!("cannot write '{}'", path.display()))?;
        println!("wrote {}", path.display());
    }
    check_validation(&ctx)?;
    if !valid {
        anyhow::bail!("a benchmark check failed (see the report)");
    }
    Ok(())
}

fn compare(a: &std::path::Path, b: &std::path::Path, json: bool) -> Result<()> {
    let c = speculum::metrics::compare_files(a, b)?;
    if json {
        println!("{}", serde_json::to_string(&c)?);
    } else {
        println!(
            "SSIM {:.6} (luma, Gaussian 11x11, sigma 1.5)  RMSE {:.6} (RGB in [0, 1])",
            c.ssim, c.rmse
        );
    }
    Ok(())
}

fn bench_reflect(args: BenchReflectArgs) -> Result<()> {
    let settings = Settings {
        width: args.width,
        height: args.height,
        ..Settings::default()
    };
    settings.validate()?;
    let scene = speculum::scene::load(&args.scene)?;
    let ctx = args.gpu.context()?;
    let r = speculum::bench::reflect::run(&ctx, &scene, &settings, 1, args.frames.max(1))?;
    println!(
        "{} on {}: {}x{}, {} reflective pixels; rt mode frame {:.1} ms",
        r.scene, r.device, r.resolution[0], r.resolution[1], r.reflective_pixels, r.rt_frame_ms
    );
    println!(
        "  steps  min conf   traced   ssr.classify  ssr.trace  ssr.compact  rt.reflect  reflect.merge   frame (ms)  / rt"
    );
    for p in &r.points {
        let ms = |k: &str| p.passes_ms.get(k).copied().unwrap_or(f64::NAN);
        println!(
            "  {:5} {:9.2} {:7.1}%  {:12.1} {:10.1} {:12.1} {:10.1} {:15.1} {:10.1} {:6.3}",
            p.ssr_max_steps,
            p.ssr_min_confidence,
            100.0 * p.rt_pixel_fraction,
            ms("ssr.classify"),
            ms("ssr.trace"),
            ms("ssr.compact"),
            ms("rt.reflect"),
            ms("reflect.merge"),
            p.frame_ms,
            p.frame_over_rt
        );
    }
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&r)? + "\n")
            .with_context(|| format!("cannot write '{}'", path.display()))?;
        println!("wrote {}", path.display());
    }
    check_validation(&ctx)?;
    if !r.valid {
        anyhow::bail!("a benchmark check failed (see the report)");
    }
    Ok(())
}

fn bench_modes(args: BenchModesArgs) -> Result<()> {
    let mut settings = load_settings(args.settings.as_deref())?;
    settings.width = args.width;
    settings.height = args.height;
    settings.validate()?;
    // Load every scene first: a bad one fails before any GPU work.
    let scenes = args
        .scene
        .iter()
        .map(|s| speculum::scene::load(s))
        .collect::<speculum::Result<Vec<_>>>()?;
    let ctx = args.gpu.context()?;
    let mut reports = Vec::new();
    for scene in &scenes {
        let r = speculum::bench::modes::run(&ctx, scene, &settings, args.warmup, args.rounds)?;
        println!(
            "{} on {}: {}x{}, median of {} interleaved rounds",
            r.scene, r.device, r.resolution[0], r.resolution[1], r.rounds
        );
        let passes: std::collections::BTreeSet<&String> = r.modes.iter().flat_map(|m| m.passes_ms.keys()).collect();
        print!("  {:<14}", "pass (ms)");
        for m in &r.modes {
            print!(" {:>10}", m.mode);
        }
        println!();
        for p in passes.iter().filter(|p| p.as_str() != "uniforms") {
            print!("  {p:<14}");
            for m in &r.modes {
                match m.passes_ms.get(*p) {
                    Some(ms) => print!(" {ms:>10.1}"),
                    None => print!(" {:>10}", "-"),
                }
            }
            println!();
        }
        let row = |name: &str, f: &dyn Fn(&speculum::bench::modes::ModeResult) -> String| {
            print!("  {name:<14}");
            for m in &r.modes {
                print!(" {:>10}", f(m));
            }
            println!();
        };
        row("frame", &|m| format!("{:.1}", m.frame_ms));
        row("frame / rt", &|m| format!("{:.3}", m.frame_over_rt));
        row("traced %", &|m| {
            format!(
                "{:.1}",
                100.0 * m.traced_pixels as f64 / m.reflective_pixels.max(1) as f64
            )
        });
        row("SSIM vs rt", &|m| format!("{:.4}", m.ssim_vs_rt));
        row("RMSE vs rt", &|m| format!("{:.4}", m.rmse_vs_rt));
        println!(
            "  ssr < hybrid < rt: {}; checks {}",
            if r.ordered { "yes" } else { "NO" },
            if r.valid { "valid" } else { "INVALID" }
        );
        reports.push(r);
    }
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&reports)? + "\n")
            .with_context(|| format!("cannot write '{}'", path.display()))?;
        println!("wrote {}", path.display());
    }
    check_validation(&ctx)?;
    if reports.iter().any(|r| !r.valid) {
        anyhow::bail!("a benchmark check failed (see the report)");
    }
    Ok(())
}

fn devices() -> Result<()> {
    let list = list_devices()?;
    if list.is_empty() {
        println!("no Vulkan devices found");
    }
    for d in list {
        let usable = match &d.usable {
            Ok(()) => "usable".to_string(),
            Err(why) => format!("unusable: {why}"),
        };
        println!(
            "{}: {} ({}, Vulkan {}.{}) {usable}",
            d.index,
            d.name,
            d.kind_name(),
            ash::vk::api_version_major(d.api_version),
            ash::vk::api_version_minor(d.api_version)
        );
    }
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        None => render(RenderArgs::default()),
        Some(Command::Render(args)) => render(args),
        Some(Command::Devices) => devices(),
        Some(Command::Compare { a, b, json }) => compare(&a, &b, json),
        Some(Command::Bench(BenchCommand::Lbvh(args))) => bench_lbvh(args),
        Some(Command::Bench(BenchCommand::Reflect(args))) => bench_reflect(args),
        Some(Command::Bench(BenchCommand::Modes(args))) => bench_modes(args),
    };
    if let Err(e) = result {
        // One line: the chain of causes, outermost first.
        let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", chain.join(": "));
        std::process::exit(1);
    }
}
