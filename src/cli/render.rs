//! `speculum render`: one scene headless to a PNG, with per-pass GPU timings.

use super::{check_outputs, progress, GpuArgs, SettingsArgs, Text};
use anyhow::Result;
use clap::Args;
use speculum::output::{Batch, Kind};
use speculum::settings::Mode;
use speculum::{headless, Settings};
use std::path::PathBuf;

/// Help for `--scene`, naming every built-in scene.
pub fn scene_help() -> String {
    format!(
        "Built-in scene ({}), a scene file (NAME for assets/scenes/NAME.toml, or a path \
         to a .toml file) or a path to an .obj, .gltf, .glb or .ply model",
        speculum::scene::builtin::NAMES.join(", ")
    )
}

#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    #[arg(long, default_value = "room", help = scene_help())]
    pub scene: String,
    /// Reflection mode [default: hybrid, or the settings file's]: `rt` traces every
    /// reflective pixel (the reference), `provenance` paints pixels by source.
    #[arg(long, value_parser = super::choice(&Mode::ALL, Mode::name, Mode::about))]
    pub mode: Option<Mode>,
    /// Frames to measure (after the warm-up frames, which are not counted).
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Also render the same frame in `rt` mode (the reference) and report SSIM and RMSE
    /// against it; the reference image is written next to --out as *_rt.png.
    #[arg(long)]
    pub reference: bool,
    /// Rays per glossy pixel of the `rt` reference (`--reference`), in one frame with no
    /// denoiser: the glossy ground truth [default: 64]. In `--mode rt`, the frame itself
    /// is rendered so.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Uncounted warm-up frames (pipeline JIT, caches, a GPU's clocks), exactly
    /// [default: until the clocks settle: at least 2 frames and 250 ms of GPU work, and
    /// two windows of 2 to 8 frames (50 ms) within 5%, at most 20 s]
    #[arg(long)]
    pub warmup: Option<u32>,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    pub out: PathBuf,
    /// Also write the timings report as JSON to this file (`-`: stdout).
    #[arg(long)]
    pub timings: Option<PathBuf>,
    /// Also write the SSR fail mask as a PNG, coloured by reason (see docs/frame.md).
    #[arg(long)]
    pub fail_mask: Option<PathBuf>,
    /// Also write where each pixel's shadow came from as a PNG: grey from the shadow
    /// map, pink from a shadow ray, each lighter where the sun reaches (see docs/shadows.md).
    #[arg(long)]
    pub shadow_sources: Option<PathBuf>,
    /// Also write every measured frame to this folder (created if needed) as
    /// frame_0000.png, ..., and frames.jsonl (one JSON object per frame: its timings,
    /// dynamic triangles, traced share, and with --reference its SSIM/RMSE against rt).
    #[arg(long)]
    pub sequence: Option<PathBuf>,
    /// Also write six evenly spaced measured frames side by side as one PNG (at least
    /// 6 frames).
    #[arg(long)]
    pub contact_sheet: Option<PathBuf>,
    /// No progress bar and no text output (errors still go to stderr).
    #[arg(long)]
    pub quiet: bool,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub view: super::ViewArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

impl RenderArgs {
    /// The command with no arguments: `render` with every default.
    pub fn defaults() -> Self {
        use clap::FromArgMatches;
        let cmd = <Self as Args>::augment_args(clap::Command::new("render"));
        Self::from_arg_matches(&cmd.get_matches_from(["render"])).expect("defaults parse")
    }
}

/// Frames on a contact sheet.
const SHEET_FRAMES: u32 = 6;

/// RGBA8 images of `w` x `h`, side by side in one row.
fn side_by_side(images: &[Vec<u8>], w: u32, h: u32) -> Vec<u8> {
    let (w, h) = (w as usize, h as usize);
    let mut out = vec![0u8; images.len() * w * h * 4];
    let row = images.len() * w * 4;
    for (i, img) in images.iter().enumerate() {
        for y in 0..h {
            out[y * row + i * w * 4..][..w * 4].copy_from_slice(&img[y * w * 4..][..w * 4]);
        }
    }
    out
}

fn reference_path(out: &std::path::Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frame".into());
    out.with_file_name(format!("{stem}_rt.png"))
}

/// Everything that can be known before the GPU is touched: the settings, the frame
/// plan, the outputs (and `--reference`'s implicit `<out>_rt.png`) against the inputs.
fn check_before_gpu(args: &RenderArgs) -> Result<(Settings, headless::FramePlan, Option<PathBuf>)> {
    let mut settings: Settings = args.frame.resolve()?;
    if let Some(mode) = args.mode {
        settings.mode = mode;
    }
    let plan = headless::FramePlan {
        warmup: speculum::steady::WarmUp::from_arg(args.warmup),
        frames: args.frames,
        reference: args.reference,
        spp: args.spp.unwrap_or(speculum::settings::GLOSSY_REFERENCE_SPP),
    };
    if args.spp.is_some() && settings.mode != Mode::Rt && !args.reference {
        anyhow::bail!(speculum::error::Error::Input(format!(
            "--spp sets the rays of the rt reference (--reference) or of --mode rt; this {} run has neither",
            settings.mode.name()
        )));
    }
    if let (Some(spp), Mode::Rt) = (args.spp, settings.mode) {
        plan.validate(&settings)?;
        settings = settings.glossy_reference(spp);
    }
    plan.validate(&settings)?;
    if args.contact_sheet.is_some() && plan.frames < SHEET_FRAMES {
        anyhow::bail!(speculum::error::Error::Input(format!(
            "--contact-sheet needs at least {SHEET_FRAMES} frames, not {}",
            plan.frames
        )));
    }
    if let Some(dir) = &args.sequence {
        speculum::output::check_dir(dir)?;
    }
    let reference_out = args.reference.then(|| reference_path(&args.out));
    check_outputs(
        &[
            ("--out", Some(&args.out), Kind::Png),
            ("--reference (its <out>_rt.png)", reference_out.as_deref(), Kind::Png),
            ("--fail-mask", args.fail_mask.as_deref(), Kind::Png),
            ("--shadow-sources", args.shadow_sources.as_deref(), Kind::Png),
            ("--timings", args.timings.as_deref(), Kind::Json),
            ("--contact-sheet", args.contact_sheet.as_deref(), Kind::Png),
        ],
        &[
            ("--scene", super::input_file(&args.scene)),
            ("--settings", args.frame.settings.as_deref()),
        ],
    )?;
    Ok((settings, plan, reference_out))
}

/// What the measured frames leave for the outputs: each frame's PNG and JSON line (a
/// `--sequence`), and the frames of the contact sheet.
#[derive(Default)]
struct Captured {
    frames_png: Vec<Vec<u8>>,
    lines: String,
    sheet: Vec<Vec<u8>>,
}

pub fn run(args: RenderArgs) -> Result<()> {
    let (settings, plan, reference_out) = check_before_gpu(&args)?;
    let scene = args.view.load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let text = Text::new(&[args.timings.as_deref()], args.quiet);
    let ctx = args.gpu.context()?;

    let bar = progress(plan.total_frames(&settings), "render", args.quiet);
    let (w, h) = (settings.width, settings.height);
    let mut captured = Captured::default();
    let sheet_at: Vec<u32> = (0..SHEET_FRAMES)
        .map(|i| i * (plan.frames - 1) / (SHEET_FRAMES - 1))
        .collect();
    let wants_frames = args.sequence.is_some() || args.contact_sheet.is_some();
    let mut hook = |f: speculum::report::FrameRecord<'_>| -> speculum::error::Result<()> {
        if args.sequence.is_some() {
            captured.frames_png.push(speculum::output::png_bytes(f.rgba, w, h)?);
            captured.lines += &serde_json::to_string(&speculum::report::FrameLine::of(&f)).expect("lines serialize");
            captured.lines.push('\n');
        }
        if args.contact_sheet.is_some() && sheet_at.contains(&f.index) {
            captured.sheet.push(f.rgba.to_vec());
        }
        Ok(())
    };
    let on_frame: Option<headless::OnFrame<'_>> = if wants_frames { Some(&mut hook) } else { None };
    let rendered = headless::render_frames(&ctx, &scene, &settings, plan, &mut || bar.inc(1), on_frame)?;
    bar.finish_and_clear();
    let mut r = rendered.report;
    r.header.refresh_validation(&ctx);
    let images = Images {
        rgba: &rendered.rgba,
        reference_rgba: rendered.reference_rgba.as_deref(),
        fail_mask_rgba: &rendered.fail_mask_rgba,
        shadow_sources_rgba: &rendered.shadow_sources_rgba,
        size: (w, h),
    };
    write_outputs(&args, reference_out.as_deref(), &images, &r, captured)?;
    print_report(&text, &r, &ctx.device_name);
    let written = [
        Some(&args.out),
        reference_out.as_ref(),
        args.fail_mask.as_ref(),
        args.shadow_sources.as_ref(),
        args.timings.as_ref(),
    ];
    for path in written.into_iter().flatten().filter(|p| p.as_os_str() != "-") {
        text.line(format_args!("wrote {}", path.display()));
    }
    super::check_validation(&ctx)
}

/// The images a render leaves, RGBA8 of `size`.
struct Images<'a> {
    rgba: &'a [u8],
    reference_rgba: Option<&'a [u8]>,
    fail_mask_rgba: &'a [u8],
    shadow_sources_rgba: &'a [u8],
    size: (u32, u32),
}

/// Writes every output the arguments ask for, only after the whole render succeeded:
/// all of them or none.
fn write_outputs(
    args: &RenderArgs,
    reference_out: Option<&std::path::Path>,
    images: &Images<'_>,
    r: &speculum::headless::TimingsReport,
    captured: Captured,
) -> Result<()> {
    let (w, h) = images.size;
    let mut outputs = Batch::default();
    outputs.add(&args.out, speculum::output::png_bytes(images.rgba, w, h)?);
    if let (Some(path), Some(reference)) = (reference_out, images.reference_rgba) {
        outputs.add(path, speculum::output::png_bytes(reference, w, h)?);
    }
    if let Some(path) = &args.fail_mask {
        outputs.add(path, speculum::output::png_bytes(images.fail_mask_rgba, w, h)?);
    }
    if let Some(path) = &args.shadow_sources {
        outputs.add(path, speculum::output::png_bytes(images.shadow_sources_rgba, w, h)?);
    }
    if let Some(path) = &args.timings {
        outputs.add(path, speculum::report::to_json(r).into_bytes());
    }
    if let Some(dir) = &args.sequence {
        for (k, png) in captured.frames_png.into_iter().enumerate() {
            outputs.add(&dir.join(format!("frame_{k:04}.png")), png);
        }
        outputs.add(&dir.join("frames.jsonl"), captured.lines.into_bytes());
        std::fs::create_dir_all(dir).map_err(|e| speculum::error::Error::Output {
            path: dir.clone(),
            detail: e.to_string(),
        })?;
    }
    if let Some(path) = &args.contact_sheet {
        outputs.add(
            path,
            speculum::output::png_bytes(&side_by_side(&captured.sheet, w, h), w * SHEET_FRAMES, h)?,
        );
    }
    outputs.commit()?;
    Ok(())
}

/// The render's text report: per-pass medians, the pixel counts, the comparisons.
fn print_report(text: &Text, r: &speculum::headless::TimingsReport, device: &str) {
    let tracer = r.header.settings.as_ref().map_or("lbvh", |s| s.tracer.name());
    text.line(format_args!(
        "{} on {}: {}x{}, {} mode, tracer {tracer}, median (p10–p90) of {} frames, GPU ms",
        r.scene, device, r.resolution[0], r.resolution[1], r.mode, r.frames
    ));
    for (name, stat) in &r.passes_ms.0 {
        if stat.is_some() {
            text.line(format_args!("  {name:<14} {}", super::cell(*stat)));
        }
    }
    text.line(format_args!("  {:<14} {}", "frame", super::cell(Some(r.frame_ms))));
    text.line(format_args!(
        "  reflective pixels {}, SSR failed on {}, ray traced {} ({:.1}%)",
        r.reflective_pixels,
        r.ssr_failed_pixels,
        r.traced_pixels,
        100.0 * r.rt_pixel_fraction
    ));
    if let Some(h) = &r.hybrid {
        let measured = h
            .exchange_rate_measured
            .map_or(String::new(), |m| format!(", measured {m:.3}"));
        text.line(format_args!(
            "  hybrid {}: exchange rate {:.3}{measured}; tiles SSR-first {}, rays-only {}, unknown {}",
            h.policy, h.exchange_rate, h.ssr_first_tiles, h.rays_only_tiles, h.unknown_tiles
        ));
        let settings = r.header.settings.as_ref();
        if settings.is_some_and(|s| speculum::settings::Hybrid::of(s).adaptive()) {
            let paths: Vec<String> = h
                .paths
                .iter()
                .map(|p| speculum::headless::frames_and_price(&p.path, p.frames, p.ms))
                .collect();
            text.line(format_args!(
                "    paths: {} (next: {}, probe frames 1 in {}, {} so far); tile flips {} (most in one tile {})",
                paths.join("; "),
                h.path,
                h.probe_every,
                h.probe_frames,
                h.tile_flips,
                h.most_tile_flips
            ));
        }
    }
    if let Some(v) = &r.visibility {
        text.line(format_args!("  visibility adaptive: {}", v.summary()));
    }
    if let Some(v) = &r.shadow_ways {
        text.line(format_args!("  shadows adaptive: {}", v.summary()));
    }
    if let Some(t) = &r.static_tree {
        text.line(format_args!("  static tree: {}", t.summary()));
    }
    if let Some(l) = &r.static_layout {
        text.line(format_args!("  static nodes: {}", l.summary()));
    }
    text.line(format_args!(
        "  {} shadows: lit pixels {}, shadow rays {} ({:.1}%)",
        r.shadows,
        r.shadow_lit_pixels,
        r.shadow_traced_pixels,
        100.0 * r.shadow_ray_fraction
    ));
    if let (Some(ssim), Some(rmse), Some(rt)) = (r.ssim_vs_rt, r.rmse_vs_rt, r.rt_frame_ms) {
        text.line(format_args!(
            "  vs rt reference: SSIM {ssim:.4}, RMSE {rmse:.4}; rt frame {}",
            super::cell(Some(rt))
        ));
    }
    if let Some(c) = &r.vs_rt_mode {
        text.line(format_args!(
            "  vs rt mode (the same glossy rays and filter): SSIM {:.4}, RMSE {:.4}",
            c.ssim, c.rmse
        ));
    }
    if let Some(v) = &r.shadows_vs_rays {
        text.line(format_args!(
            "  vs rays shadows: SSIM {:.4}, RMSE {:.4}; visibility equal on {:.2}% of {} lit pixels, RMSE {:.4}",
            v.ssim,
            v.rmse,
            100.0 * v.visibility_agreement,
            v.lit_pixels,
            v.visibility_rmse
        ));
    }
    text.line(format_args!("  {}", super::timing_note(&r.timing)));
    text.line(format_args!("  {}", super::steady_note(&r.warmup, None)));
    if let Some(n) = r.header.validation_messages {
        text.line(format_args!("  validation messages: {n}"));
    }
}
