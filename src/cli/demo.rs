//! `speculum demo`: the window (see `speculum::demo`).

use super::{GpuArgs, SettingsArgs};
use anyhow::Result;
use clap::{Args, ValueEnum};
use speculum::demo::{script, DemoConfig};
use speculum::settings::Mode;
use std::path::PathBuf;

/// Present modes `--present` takes.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Present {
    Fifo,
    Mailbox,
    Immediate,
}

/// The key list, for `--help` (`docs/demo.md` holds the same table).
pub fn keys_help() -> String {
    let mut s = String::from("Keys:\n");
    for (key, what) in script::KEYS {
        s += &format!("  {key:<20} {what}\n");
    }
    s
}

#[derive(Args, Clone, Debug)]
#[command(after_help = keys_help())]
pub struct DemoArgs {
    #[arg(long, default_value = "room", help = super::render::scene_help())]
    pub scene: String,
    /// Reflection mode to start in [default: hybrid, or the settings file's].
    #[arg(long, value_parser = super::choice(&Mode::ALL, Mode::name, Mode::about))]
    pub mode: Option<Mode>,
    /// Present mode; MAILBOX and IMMEDIATE fall back to FIFO where the surface lacks them.
    #[arg(long, value_enum, default_value = "fifo")]
    pub present: Present,
    /// Render N frames, then quit (with --screenshot: save the last one first).
    #[arg(long)]
    pub frames: Option<u32>,
    /// With --frames: save the last frame (without the HUD) here, and its JSON beside it.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Drive the demo from a script (see "Demo scripts" in docs/demo.md); the demo quits
    /// at its end.
    #[arg(long, conflicts_with = "frames")]
    pub script: Option<PathBuf>,
    /// Folder for P screenshots and "save settings".
    #[arg(long, default_value = ".")]
    pub out_dir: PathBuf,
    /// Print each script step and each swapchain recreation as it happens.
    #[arg(long)]
    pub verbose: bool,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub view: super::ViewArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

pub fn run(args: DemoArgs) -> Result<()> {
    // Everything that can be known before a window opens is checked here.
    let mut settings = args.frame.resolve()?;
    if let Some(mode) = args.mode {
        settings.mode = mode;
    }
    let steps = match (&args.script, args.frames) {
        (Some(path), _) => {
            let text = speculum::error::read_text(path, "demo script", speculum::error::bounds::TEXT)?;
            script::parse(&text)?
        }
        (None, Some(n)) => {
            super::check_count("--frames", n, 1)?;
            let mut steps = vec![script::Step::Wait(n)];
            if let Some(path) = &args.screenshot {
                speculum::output::check(path, speculum::output::Kind::Png)?;
                steps.push(script::Step::Screenshot(path.clone()));
            }
            steps.push(script::Step::Quit);
            steps
        }
        (None, None) => Vec::new(),
    };
    if !args.out_dir.is_dir() {
        anyhow::bail!(speculum::Error::Input(format!(
            "--out-dir '{}' is not a folder",
            args.out_dir.display()
        )));
    }
    let scene = args.view.load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    use ash::vk::PresentModeKHR as P;
    let present_mode = match args.present {
        Present::Fifo => P::FIFO,
        Present::Mailbox => P::MAILBOX,
        Present::Immediate => P::IMMEDIATE,
    };
    let summary = speculum::demo::run(DemoConfig {
        scene,
        scene_name: args.scene.clone(),
        settings,
        validation: args.gpu.validation || super::validation_from_env(),
        device: args.gpu.device.clone(),
        present_mode,
        script: steps,
        out_dir: args.out_dir.clone(),
        verbose: args.verbose,
    })?;
    let median = |v: &[f64]| speculum::demo::hud::median_p95(v).0;
    let modes: Vec<String> = summary
        .mode_frame_ms
        .iter()
        .map(|(m, v)| format!("{m} {:.2} ms ({} frames)", median(v), v.len()))
        .collect();
    eprintln!(
        "demo: {} frames ({} skipped); GPU frame median by mode: {}; {} swapchain recreations, median {:.1} ms",
        summary.frames,
        summary.skipped,
        if modes.is_empty() { "-".into() } else { modes.join(", ") },
        summary.recreate_ms.len(),
        median(&summary.recreate_ms)
    );
    if summary.validation_messages > 0 {
        anyhow::bail!(
            "{} Vulkan validation message(s) (see above)",
            summary.validation_messages
        );
    }
    Ok(())
}
