//! The `speculum` command line: `render` (headless, the default), `demo` (the window),
//! `tune` and `plot`, `bench`, `compare`, `settings` and `devices`. Each command lives in `cli/`.

mod cli;

use anyhow::Result;
use clap::{Parser, Subcommand};
use cli::bench::BenchCommand;
use cli::compare::CompareArgs;
use cli::render::RenderArgs;
use speculum::vk::list_devices;
use speculum::Settings;

#[derive(Parser)]
#[command(
    name = "speculum",
    version,
    about = "Hybrid SSR + GPU-ray-traced reflections on Vulkan",
    after_help = "With no command, `speculum` renders the default scene (room) to frame.png."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene headless to a PNG and report per-pass GPU timings.
    Render(Box<RenderArgs>),
    /// Open a window: the scene live, with a HUD of timings and every setting.
    Demo(Box<cli::demo::DemoArgs>),
    /// Sweep settings against rt: points.csv/json, the Pareto front, pareto.png, best.json.
    Tune(Box<cli::tune::TuneArgs>),
    /// Draw a tune sweep's plot again from its points.csv.
    Plot(cli::tune::PlotArgs),
    /// List the Vulkan devices, in the order --device INDEX counts them.
    Devices,
    /// SSIM (on luma; Gaussian 11x11, sigma 1.5) and RMSE (RGB, [0, 1]) of two PNGs.
    Compare(CompareArgs),
    /// GPU timing benchmarks (each also checks what it times).
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Print settings as JSON (the defaults, or a settings file's effective values), or
    /// the settings table.
    Settings(SettingsCommand),
}

#[derive(clap::Args)]
#[group(required = true, multiple = false)]
struct SettingsCommand {
    /// Print every setting with its default value.
    #[arg(long)]
    defaults: bool,
    /// Print the settings table as Markdown: default, range, how a change applies and
    /// what each setting trades (the README's list).
    #[arg(long)]
    list: bool,
    /// Print the effective settings of this file (its values, defaults for the rest).
    file: Option<std::path::PathBuf>,
}

fn settings(cmd: SettingsCommand) -> Result<()> {
    if cmd.list {
        print!("{}", speculum::settings::markdown_table());
        return Ok(());
    }
    let s = if cmd.defaults {
        Settings::default()
    } else {
        let s = cli::load_settings(cmd.file.as_deref())?;
        s.validate()?;
        s
    };
    print!("{}", speculum::report::to_json(&s));
    Ok(())
}

fn devices() -> Result<()> {
    let list = list_devices()?;
    if list.is_empty() {
        println!("no Vulkan devices found");
    }
    for d in list {
        let usable = match (&d.usable, &d.ray_tracing_missing) {
            (Ok(()), None) => "usable; tracers lbvh and khr".to_string(),
            (Ok(()), Some(lacks)) => format!("usable; tracer lbvh (khr lacks {lacks})"),
            (Err(why), _) => format!("unusable: {why}"),
        };
        println!(
            "{}: {} ({}, Vulkan {}.{}.{}, driver {}) {usable}",
            d.index,
            d.name,
            d.kind_name(),
            ash::vk::api_version_major(d.api_version),
            ash::vk::api_version_minor(d.api_version),
            ash::vk::api_version_patch(d.api_version),
            d.driver
        );
    }
    Ok(())
}

/// One line for an error and its causes, outermost first; a cause whose text the line
/// already holds (an OS message quoted by the error that wraps it) is not repeated.
fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        None => cli::render::run(RenderArgs::defaults()),
        Some(Command::Render(args)) => cli::render::run(*args),
        Some(Command::Demo(args)) => cli::demo::run(*args),
        Some(Command::Tune(args)) => cli::tune::run(*args),
        Some(Command::Plot(args)) => cli::tune::plot(args),
        Some(Command::Devices) => devices(),
        Some(Command::Compare(args)) => cli::compare::run(args),
        Some(Command::Bench(command)) => cli::bench::run(command),
        Some(Command::Settings(cmd)) => settings(cmd),
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_line(&e));
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_line_says_a_repeated_cause_once() {
        let os = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory (os error 2)");
        let e = anyhow::Error::new(speculum::Error::Io {
            what: "OBJ file",
            path: "x.obj".into(),
            source: os,
        });
        let line = error_line(&e.context("loading the scene"));
        assert_eq!(
            line,
            "loading the scene: cannot read OBJ file 'x.obj': No such file or directory (os error 2)"
        );
    }
}
