//! `speculum bench dynamic`: a dynamic scene's per-frame costs as its bodies, its
//! cloths or a skinned mesh grow.

use super::{valid_or_fail, Common};
use crate::cli::{check_count, check_outputs, progress, SettingsArgs, Text};
use anyhow::Result;
use clap::Args;
use speculum::output::Kind;
use speculum::report::Header;

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
    /// Instead: a generated skinned tube of about this many triangles (1000..=4000000;
    /// 16 joints swaying, on a mirror floor), each size in its own run (`--scene` is
    /// not read).
    #[arg(long, num_args = 1..)]
    pub skinned: Vec<u32>,
    /// Measured frames per body count.
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// Uncounted warm-up frames, exactly (the scene is reset after them) [default:
    /// until the clocks settle, as `render`]
    #[arg(long)]
    pub warmup: Option<u32>,
    /// Rays traced through the rebuilt and the refit BVH at the last frame.
    #[arg(long, default_value_t = 65536)]
    pub rays: u32,
    #[command(flatten)]
    pub frame: SettingsArgs,
    #[command(flatten)]
    pub common: Common,
}

pub(super) fn dynamic(args: DynamicArgs) -> Result<()> {
    use speculum::bench::dynamic::{run_point, DynamicReport};
    let c = &args.common;
    let settings = args.frame.resolve()?;
    check_count("--frames", args.frames, 1)?;
    if let Some(w) = args.warmup {
        check_count("--warmup", w, 0)?;
    }
    let warmup = speculum::steady::WarmUp::from_arg(args.warmup);
    check_count("--rays", args.rays, 1)?;
    check_outputs(
        &[("--json", c.json.as_deref(), Kind::Json)],
        &[("--settings", args.frame.settings.as_deref())],
    )?;
    // Every body count's scene first: a bad one fails before any GPU work.
    let (scenes, axis) = point_scenes(&args)?;
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let per = (args.frames + warmup.min_frames()) as u64;
    let bar = progress(per * scenes.len() as u64, "bench dynamic", c.quiet);
    let mut points = Vec::new();
    for scene in &scenes {
        points.push(run_point(
            &ctx,
            scene,
            &settings,
            warmup,
            args.frames,
            args.rays,
            &mut || bar.inc(1),
        )?);
    }
    bar.finish_and_clear();
    let (first, last) = (&points[0], &points[points.len() - 1]);
    let report = DynamicReport {
        header: Header::new("bench.dynamic", Some(&ctx), Some(&settings)),
        scene: match axis {
            Axis::Skinned => "skinned tube".into(),
            _ => args.scene.clone(),
        },
        resolution: [settings.width, settings.height],
        frames: args.frames,
        warmup: warmup.rule(),
        rebuild_growth: last.rebuild_ms.median / first.rebuild_ms.median,
        triangle_growth: last.dynamic_triangles as f64 / first.dynamic_triangles as f64,
        valid: points.iter().all(|p| p.valid),
        points,
    };
    print_points(
        &text,
        &report,
        &ctx.device_name,
        (&scenes, &settings),
        axis,
        args.frames,
    );
    let timing: speculum::vk::TimingCheck = report.points.iter().map(|p| &p.timing).collect();
    text.line(format_args!("  {}", crate::cli::timing_note(&timing)));
    if let Some(path) = &c.json {
        crate::cli::write_report(path, &report, &text)?;
    }
    crate::cli::check_validation(&ctx)?;
    valid_or_fail(report.valid)
}

/// What the points vary.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Axis {
    Bodies,
    Cloth,
    Skinned,
}

impl Axis {
    /// The table's first column and its step column.
    fn columns(self) -> (&'static str, &'static str) {
        match self {
            Axis::Bodies => ("bodies", "sim.transform"),
            Axis::Cloth => ("cloth", "sim.cloth"),
            Axis::Skinned => ("joints", "sim.skin"),
        }
    }

    /// Point `p`'s values of those two columns.
    fn values(self, p: &speculum::bench::dynamic::DynamicPoint) -> (u32, f64) {
        match self {
            Axis::Bodies => (p.bodies, p.sim_transform_ms.median),
            Axis::Cloth => (p.cloth_resolution, p.sim_cloth_ms.median),
            Axis::Skinned => (p.joints, p.sim_skin_ms.median),
        }
    }
}

/// The scene of every point (`--bodies` counts, `--cloth-res` resolutions or
/// `--skinned` sizes), each checked; and what the points vary.
fn point_scenes(args: &DynamicArgs) -> Result<(Vec<speculum::scene::Scene>, Axis)> {
    let given = [
        !args.bodies.is_empty(),
        !args.cloth_res.is_empty(),
        !args.skinned.is_empty(),
    ];
    if given.iter().filter(|g| **g).count() > 1 {
        anyhow::bail!("give one of --bodies, --cloth-res and --skinned");
    }
    if given[2] {
        let scenes = args.skinned.iter().map(|&n| speculum::scene::builtin::skinned_tube(n));
        return Ok((scenes.collect::<speculum::error::Result<Vec<_>>>()?, Axis::Skinned));
    }
    let by_cloth = given[1];
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
    Ok((scenes, if by_cloth { Axis::Cloth } else { Axis::Bodies }))
}

/// The table of points, with which rebuild the bodies got.
fn print_points(
    text: &Text,
    report: &speculum::bench::dynamic::DynamicReport,
    device: &str,
    (scenes, settings): (&[speculum::scene::Scene], &speculum::Settings),
    axis: Axis,
    frames: u32,
) {
    // Which rebuild the bodies get (the renderer's rule).
    let rigid = scenes
        .iter()
        .all(|s| speculum::tracers::lbvh::rigid::applies(s, settings.rigid_order));
    let rebuild = match (axis, rigid) {
        (Axis::Cloth | Axis::Skinned, _) => "",
        (Axis::Bodies, true) => "; bodies rebuilt in their own order, rigid_order",
        (Axis::Bodies, false) => "; every triangle sorted at each rebuild",
    };
    let (first, step) = axis.columns();
    text.line(format_args!(
        "{} on {}: {}x{}, median of {} frames per body count (ms; sim.rigid is CPU{rebuild})",
        report.scene, device, settings.width, settings.height, frames
    ));
    text.line(format_args!(
        "  {:>6} {:>9} {:>9} {:>13} {:>9} {:>8} {:>7} {:>10} {:>9} {:>9} {:>9}",
        first, "tris", "sim.rigid", step, "rebuild", "refit", "ratio", "rt.reflect", "frame", "trace new", "trace old"
    ));
    for p in &report.points {
        let (value, step_ms) = axis.values(p);
        text.line(format_args!(
            "  {:>6} {:>9} {:>9.2} {:>13.2} {:>9.2} {:>8.2} {:>7.3} {:>10.1} {:>9.1} {:>9.2} {:>9.2}",
            value,
            p.dynamic_triangles,
            p.sim_rigid_ms.median,
            step_ms,
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
    for p in &report.points {
        if let Some(r) = p.skin_refit_over_rebuild {
            text.line(format_args!(
                "  {} triangles: (sim.skin + refit) / rebuild = {r:.3} (median of per-frame ratios)",
                p.dynamic_triangles
            ));
        }
    }
    print_khr_points(text, report, axis);
}

/// The same frames through the vendor tracer, where the device has it.
fn print_khr_points(text: &Text, report: &speculum::bench::dynamic::DynamicReport, axis: Axis) {
    if report.points.iter().all(|p| p.khr.is_none()) {
        return;
    }
    text.line(format_args!(
        "  through the vendor tracer (tracer = khr; not interleaved with the rows above):"
    ));
    text.line(format_args!(
        "  {:>6} {:>9} {:>9} {:>10} {:>9} {:>15}",
        axis.columns().0,
        "as.tlas",
        "as.cloth",
        "rt.reflect",
        "frame",
        "frame vs lbvh"
    ));
    for p in &report.points {
        if let Some(k) = &p.khr {
            text.line(format_args!(
                "  {:>6} {:>9.2} {:>9.2} {:>10.1} {:>9.1} {:>14.2}x",
                axis.values(p).0,
                k.as_tlas_ms.median,
                k.as_cloth_ms.median,
                k.rt_reflect_ms.median,
                k.frame_ms.median,
                k.frame_over_lbvh
            ));
        }
    }
}
