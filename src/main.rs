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
    /// Frames to measure (after the warm-up frames, which are not counted).
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Uncounted warm-up frames (pipeline JIT, caches).
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
    /// Also write the timings as JSON to this file.
    #[arg(long)]
    timings: Option<PathBuf>,
    /// Settings file (JSON) with any fields of the settings struct; flags override it.
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Device by index or name substring (see `speculum devices`).
    #[arg(long)]
    device: Option<String>,
    /// Enable Vulkan validation + synchronization validation (also SPECULUM_VALIDATION=1).
    #[arg(long)]
    validation: bool,
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

fn validation_from_env() -> bool {
    std::env::var("SPECULUM_VALIDATION").is_ok_and(|v| !v.is_empty() && v != "0")
}

fn render(args: RenderArgs) -> Result<()> {
    let mut settings = match &args.settings {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read settings file '{}'", path.display()))?;
            serde_json::from_str::<Settings>(&text)
                .with_context(|| format!("invalid settings file '{}'", path.display()))?
        }
        None => Settings::default(),
    };
    settings.width = args.width;
    settings.height = args.height;
    settings.validate()?;
    let scene = speculum::scene::load(&args.scene)?;
    let validation = args.validation || validation_from_env();
    let ctx = Context::new(&ContextDesc {
        validation,
        device: args.device.clone(),
    })?;
    let rendered = headless::render(&ctx, &scene, &settings, args.warmup, args.frames)?;
    headless::save_png(&args.out, &rendered.rgba, settings.width, settings.height)?;

    let r = &rendered.report;
    println!(
        "{} on {}: {}x{}, median of {} frames",
        r.scene, r.device, r.resolution[0], r.resolution[1], r.frames
    );
    for (name, ms) in &r.passes_ms {
        println!("  {name:<14} {ms:8.3} ms");
    }
    println!("  {:<14} {:8.3} ms", "frame", r.frame_ms);
    if let Some(n) = r.validation_messages {
        println!("  validation messages: {n}");
    }
    println!("wrote {}", args.out.display());
    if let Some(path) = &args.timings {
        let json = serde_json::to_string_pretty(r)?;
        std::fs::write(path, json + "\n").with_context(|| format!("cannot write '{}'", path.display()))?;
        println!("wrote {}", path.display());
    }
    if r.validation_messages.is_some_and(|n| n > 0) {
        anyhow::bail!("{} validation message(s) reported", r.validation_messages.unwrap_or(0));
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
    };
    if let Err(e) = result {
        // One line: the chain of causes, outermost first.
        let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", chain.join(": "));
        std::process::exit(1);
    }
}
