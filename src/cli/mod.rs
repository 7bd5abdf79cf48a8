//! Pieces every command shares: device choice and validation, the settings file with
//! flags that override it only when given, reports to a file or stdout, progress bars.

pub mod bench;
pub mod compare;
pub mod demo;
pub mod render;
pub mod tune;

use anyhow::{Context as _, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use speculum::scene::Floor;
use speculum::settings::{Shadows, Tracer, Visibility};
use speculum::vk::{Context, ContextDesc};
use speculum::Settings;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Device choice and validation, shared by every command that uses the GPU.
#[derive(Args, Clone, Debug)]
pub struct GpuArgs {
    /// Device by index or name substring (see `speculum devices`).
    #[arg(long)]
    pub device: Option<String>,
    /// Enable Vulkan validation + synchronization validation (also SPECULUM_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
}

impl GpuArgs {
    pub fn context(&self) -> Result<std::sync::Arc<Context>> {
        Ok(Context::new(&self.desc())?)
    }

    /// The context these flags ask for.
    pub fn desc(&self) -> ContextDesc {
        ContextDesc {
            validation: self.validation || validation_from_env(),
            device: self.device.clone(),
            ..Default::default()
        }
    }
}

/// The settings a frame is rendered with: a settings file, then flags that override it
/// only when they are given.
#[derive(Args, Clone, Debug, Default)]
pub struct SettingsArgs {
    /// Settings file (JSON object) with any fields of the settings struct
    /// (`speculum settings --defaults` prints them all); flags given override it.
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Width in pixels [default: 960, or the settings file's].
    #[arg(long)]
    pub width: Option<u32>,
    /// Height in pixels [default: 540, or the settings file's].
    #[arg(long)]
    pub height: Option<u32>,
    /// Where shadows come from [default: map, or the settings file's].
    #[arg(long, value_parser = choice(&Shadows::ALL, Shadows::name, Shadows::about))]
    pub shadows: Option<Shadows>,
    /// How the G-buffer is made [default: raster, or the settings file's].
    #[arg(long, value_parser = choice(&Visibility::ALL, Visibility::name, Visibility::about))]
    pub visibility: Option<Visibility>,
    /// The ray tracer [default: lbvh, or the settings file's].
    #[arg(long, value_parser = choice(&Tracer::ALL, Tracer::name, Tracer::about))]
    pub tracer: Option<Tracer>,
}

impl SettingsArgs {
    /// The effective settings, validated.
    pub fn resolve(&self) -> Result<Settings> {
        let mut s = load_settings(self.settings.as_deref())?;
        if let Some(w) = self.width {
            s.width = w;
        }
        if let Some(h) = self.height {
            s.height = h;
        }
        if let Some(tracer) = self.tracer {
            s.tracer = tracer;
        }
        if let Some(shadows) = self.shadows {
            s.shadows = shadows;
        }
        if let Some(visibility) = self.visibility {
            s.visibility = visibility;
        }
        s.validate()?;
        Ok(s)
    }
}

/// The view of a scene, set from the command line; each flag replaces the scene's value.
#[derive(Args, Clone, Debug, Default)]
pub struct ViewArgs {
    /// Camera position, x,y,z in world units.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub camera_pos: Option<glam::Vec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub camera_target: Option<glam::Vec3>,
    /// Vertical field of view in degrees (0 < fov < 180).
    #[arg(long)]
    pub fov: Option<f32>,
    /// Direction towards the sun, x,y,z (normalized).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub sun_dir: Option<glam::Vec3>,
    /// The floor a bare model (an .obj given as the scene) stands on [default: mirror].
    #[arg(long, value_parser = choice(&Floor::ALL, Floor::name, Floor::about))]
    pub floor: Option<Floor>,
    /// Bodies a scene with a [spawn] table drops (`stress`: 100 by default), 1..=4000.
    #[arg(long)]
    pub bodies: Option<u32>,
    /// The animation an animated model plays, by index or name [default: the scene
    /// file's, or the model's first].
    #[arg(long)]
    pub animation: Option<speculum::scene::animated::Choice>,
    /// The animation's time at the first frame, seconds [default: the start]: render
    /// one instant with `--frames 1`.
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<f32>,
}

/// "x,y,z" as a vector of three finite numbers.
pub fn parse_vec3(s: &str) -> std::result::Result<glam::Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Vec<f32> = parts.iter().filter_map(|p| p.parse::<f32>().ok()).collect();
    match nums[..] {
        [x, y, z] if parts.len() == 3 && nums.iter().all(|v| v.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("'{s}' is not three finite numbers x,y,z")),
    }
}

impl ViewArgs {
    /// Loads scene `name` (a bare model on `--floor`) with this view applied.
    pub fn load(&self, name: &str) -> Result<speculum::scene::Scene> {
        if self.floor.is_some() && !speculum::scene::is_model(name) {
            anyhow::bail!("--floor is for a bare model (an .obj given as the scene), not for '{name}'");
        }
        let mut scene = speculum::scene::load_with(name, self.floor.unwrap_or_default())?;
        if let Some(n) = self.bodies {
            scene.set_spawn_count(n)?;
        }
        self.apply(&mut scene)?;
        Ok(scene)
    }

    /// Applies the flags given to `scene`, checking the view they make.
    pub fn apply(&self, scene: &mut speculum::scene::Scene) -> Result<()> {
        let cam = &mut scene.camera;
        if let Some(p) = self.camera_pos {
            cam.position = p;
        }
        if let Some(t) = self.camera_target {
            cam.target = t;
        }
        if let Some(f) = self.fov {
            use speculum::scene::camera::MIN_FOV_DEG;
            if !(MIN_FOV_DEG..180.0).contains(&f) {
                anyhow::bail!("--fov {f} is outside [{MIN_FOV_DEG}, 180) degrees");
            }
            cam.fov_y_deg = f;
        }
        // The same checks as a scene file's camera and sun, with the same messages.
        cam.check()
            .map_err(|e| anyhow::anyhow!("{e} (with the --camera-*/--fov flags given)"))?;
        if let Some(d) = self.sun_dir {
            scene.light.direction = d.normalize_or_zero();
            scene.light.check().map_err(|e| anyhow::anyhow!("--sun-dir: {e}"))?;
        }
        self.apply_animation(scene)
    }

    /// `--animation` and `--time`, for a scene with an animated model.
    fn apply_animation(&self, scene: &mut speculum::scene::Scene) -> Result<()> {
        if self.animation.is_none() && self.time.is_none() {
            return Ok(());
        }
        let Some(a) = &mut scene.animated else {
            anyhow::bail!(
                "--animation and --time need a scene with an animated model; '{}' has none",
                scene.name
            );
        };
        if let Some(choice) = &self.animation {
            a.select(choice).map_err(|e| anyhow::anyhow!("--animation: {e}"))?;
        }
        if let Some(t) = self.time {
            if !t.is_finite() {
                anyhow::bail!("--time {t} is not a finite number of seconds");
            }
            a.start = t;
        }
        Ok(())
    }
}

/// Fails when validation reported anything (0 when validation is off).
pub fn check_validation(ctx: &Context) -> Result<()> {
    if ctx.validation_messages() > 0 {
        anyhow::bail!("{} validation message(s) reported", ctx.validation_messages());
    }
    Ok(())
}

pub fn validation_from_env() -> bool {
    std::env::var("SPECULUM_VALIDATION").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The settings file's values (a JSON object; missing fields take their defaults), or
/// the defaults.
pub fn load_settings(path: Option<&Path>) -> Result<Settings> {
    let Some(path) = path else {
        return Ok(Settings::default());
    };
    let text = speculum::error::read_text(path, "settings file", speculum::error::bounds::TEXT)?;
    Settings::from_json(&text).with_context(|| format!("invalid settings file '{}'", path.display()))
}

/// Checks report and image outputs (flag, path, kind) before any GPU work: each as
/// `output::check`, then that no two name the same file and none names one of the
/// run's `inputs` (flag, path).
pub fn check_outputs(
    outputs: &[(&str, Option<&Path>, speculum::output::Kind)],
    inputs: &[(&str, Option<&Path>)],
) -> Result<()> {
    for (_, path, kind) in outputs {
        if let Some(p) = path {
            speculum::output::check(p, *kind)?;
        }
    }
    let named: Vec<(&str, &Path)> = outputs.iter().filter_map(|(f, p, _)| Some((*f, (*p)?))).collect();
    let inputs: Vec<(&str, &Path)> = inputs.iter().filter_map(|(f, p)| Some((*f, (*p)?))).collect();
    speculum::output::check_distinct(&named, &inputs)?;
    Ok(())
}

/// A `--scene` (or similar) argument as an input file: the path when it names an
/// existing file, `None` for a built-in name.
pub fn input_file(arg: &str) -> Option<&Path> {
    let p = Path::new(arg);
    p.is_file().then_some(p)
}

/// Writes a JSON report to `path` (`-`: stdout), atomically.
pub fn write_report<T: serde::Serialize>(path: &Path, report: &T, text: &Text) -> Result<()> {
    speculum::output::write_atomic(path, speculum::report::to_json(report).as_bytes())?;
    if path != Path::new("-") {
        text.line(format_args!("wrote {}", path.display()));
    }
    Ok(())
}

/// Where human-readable output goes: stdout, or stderr when a report takes stdout
/// (`--json -`), or nowhere with `--quiet`.
pub struct Text {
    to_stderr: bool,
    quiet: bool,
}

impl Text {
    /// `reports` are the JSON outputs of the command; one of them may be `-`.
    pub fn new(reports: &[Option<&Path>], quiet: bool) -> Self {
        Self {
            to_stderr: reports.iter().flatten().any(|p| *p == Path::new("-")),
            quiet,
        }
    }

    pub fn line(&self, s: impl std::fmt::Display) {
        if self.quiet {
            return;
        }
        if self.to_stderr {
            eprintln!("{s}");
        } else {
            println!("{s}");
        }
    }
}

/// A progress bar on stderr for `total` steps; hidden with `--quiet` and when stdout or
/// stderr is not a terminal (output piped to a file or a program).
pub fn progress(total: u64, what: &str, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    if quiet || !std::io::stdout().is_terminal() || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, {elapsed} (ETA {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

/// Frame-count flags share one bound (`headless::MAX_FRAMES`).
pub fn check_count(flag: &str, value: u32, min: u32) -> Result<()> {
    let max = speculum::headless::MAX_FRAMES;
    if value < min || value > max {
        anyhow::bail!("{flag} {value} is outside {min}..={max}");
    }
    Ok(())
}

/// `ms` as a table cell: a median with its p10–p90 spread.
/// What a set of timings' self-check found, for text output.
pub fn timing_note(check: &speculum::vk::TimingCheck) -> String {
    match check.warning() {
        None => format!(
            "timings self-checked ({} readouts agree, {} re-measured)",
            check.checked, check.discarded
        ),
        Some(w) => format!("TIMINGS INVALID: {w}"),
    }
}

/// How a run warmed up, and how its rounds held when it has rounds (`steady`).
pub fn steady_note(w: &speculum::steady::WarmUpReport, rounds: Option<&speculum::steady::RoundsCheck>) -> String {
    let mut s = format!(
        "warm-up ({}): {} frames, {:.0} ms of GPU work, {:.1} s{}",
        w.rule,
        w.frames,
        w.gpu_ms,
        w.wall_s,
        if w.settled { "" } else { ", clocks NOT SETTLED" }
    );
    if w.pricing_rounds > 0 {
        s += &format!(", then {} rounds pricing the adaptive stages", w.pricing_rounds);
    }
    if let Some(note) = rounds.and_then(|r| r.note()) {
        s += "; ";
        s += &note;
    }
    s
}

pub fn cell(stat: Option<speculum::report::Stat>) -> String {
    match stat {
        Some(s) => format!("{:.2} ({:.2}–{:.2})", s.median, s.p10, s.p90),
        None => "-".into(),
    }
}

/// A parser for one of a library enum's values by name, each listed in `--help` with
/// its line (the library's types do not derive clap's traits: the CLI is above them).
pub fn choice<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
    about: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let values = all.iter().map(move |&v| PossibleValue::new(name(v)).help(about(v)));
    PossibleValuesParser::new(values).map(move |s| {
        let found = all.iter().copied().find(|&v| name(v) == s);
        found.expect("clap checked the value against the possible values")
    })
}
