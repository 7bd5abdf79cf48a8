//! `speculum bench lbvh`: the BVH builds and traversal, checked against the CPU.

use super::{valid_or_fail, Common};
use crate::cli::{cell, check_count, check_outputs, progress, Text};
use anyhow::Result;
use clap::Args;
use speculum::bench::lbvh::{run_case, Options, Report};
use speculum::output::Kind;
use speculum::passes::rt_trace::Refill;
use speculum::report::Header;
use speculum::tracers::lbvh::{BvhKind, MortonBits, StaticLayout};
use std::path::PathBuf;

#[derive(Args, Clone, Debug)]
pub struct LbvhArgs {
    /// Random triangle soups of these sizes (default 10000 100000 1000000 when no
    /// --scene is given).
    #[arg(long, num_args = 1..)]
    pub tris: Vec<u32>,
    /// Dense closed surfaces of about these triangle counts (a bumpy torus: a scanned
    /// model's class, small even triangles on one surface, where a soup's fill a volume).
    #[arg(long, num_args = 1..)]
    pub surface: Vec<u32>,
    /// Built-in scene names or .obj paths to benchmark as well.
    #[arg(long, num_args = 1..)]
    pub scene: Vec<String>,
    /// Morton code width in bits.
    #[arg(long, default_value = "30", value_parser = crate::cli::choice(&MortonBits::ALL, MortonBits::name, MortonBits::about))]
    pub bits: MortonBits,
    /// The trees to build of each case.
    #[arg(long, num_args = 1.., default_values = ["lbvh", "ploc"], value_parser = crate::cli::choice(&BvhKind::ALL, BvhKind::name, BvhKind::about))]
    pub builder: Vec<BvhKind>,
    /// The static walk's layouts each tree is walked in (`lbvh.compact`).
    #[arg(long, num_args = 1.., default_values = ["binary", "wide", "wide8"], value_parser = crate::cli::choice(&StaticLayout::ALL, StaticLayout::name, StaticLayout::about))]
    pub layout: Vec<StaticLayout>,
    /// Timed repetitions of each build and trace (medians are reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
    /// Rays per ray set (coherent and incoherent), at most 33,554,432 (a rays file's
    /// bound) [default: 2,097,152 on a GPU, about eight waves of a large GPU's resident
    /// threads (an H200 holds 270,336), so a set's time is the walk's throughput and not
    /// one wave's slowest rays; 262,144 on a CPU device]
    #[arg(long)]
    pub rays: Option<u32>,
    /// Rays of each set checked against the CPU reference.
    #[arg(long, default_value_t = 2000)]
    pub check_rays: u32,
    /// Rays of each set the vendor tracer (KHR acceleration structures, file and Morton
    /// order) traces, on the first builder's line; 0 leaves it out [default: every ray
    /// of the set on a GPU, so the driver's walk fills it; 512 on a CPU device, whose
    /// driver (lavapipe) builds its tree by the primitive order and traces file-order
    /// soups thousands of times slower than the LBVH: the default run stays bounded]
    #[arg(long)]
    pub khr_rays: Option<u32>,
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
    /// The sort's scatter puts each tile's pairs in order in shared memory and writes
    /// them out by consecutive invocations, on a GPU (its tiles of 16 keys a thread):
    /// a candidate against the direct scatter's scattered stores (lavapipe's tiles
    /// keep the direct one).
    #[arg(long)]
    pub local_sort_scatter: bool,
    /// Every sort of more than one tile runs its scan pass by pass, as before the
    /// scatter found the offsets of a sort of few tiles itself (up to 256 tiles on a
    /// GPU, 32 on a CPU device): what the fused passes are measured against.
    #[arg(long)]
    pub sort_scan: bool,
    /// Also trace both ray sets of each case through the walk with its lanes refilled
    /// (a candidate for wide SIMD groups: an invocation takes a new ray when its walk
    /// ends, so its group's lanes do not idle behind the longest walk), in its default
    /// shape (4:4, `--refill`)
    #[arg(long)]
    pub refilled: bool,
    /// The refilled walk in these shapes, SHARE:RAYS each: idle lanes take new rays
    /// once they are 1/SHARE of their subgroup's (1 to 64; 1: all of them), an
    /// invocation takes RAYS rays on average (1 to 1024)
    #[arg(long, num_args = 1.., value_name = "SHARE:RAYS")]
    pub refill: Vec<String>,
    #[command(flatten)]
    pub common: Common,
}

/// The refilled walk's shapes: `--refill`'s, after the default where `--refilled`
/// asks for it too; each once.
fn refill_shapes(args: &LbvhArgs) -> Result<Vec<Refill>> {
    let mut shapes = Vec::from_iter(args.refilled.then_some(Refill::DEFAULT));
    for arg in &args.refill {
        let shape = arg
            .parse::<Refill>()
            .map_err(|e| speculum::Error::Input(format!("--refill {e}")))?;
        if !shapes.contains(&shape) {
            shapes.push(shape);
        }
    }
    Ok(shapes)
}

/// The vendor tracer's rays per set on a CPU device, without `--khr-rays`.
const KHR_RAYS_ON_A_CPU: u32 = 512;
/// Rays per set without `--rays`: on a GPU, and on a CPU device.
const RAYS_ON_A_GPU: u32 = 1 << 21;
const RAYS_ON_A_CPU: u32 = 1 << 18;
/// The most rays a set may have (what a rays file may hold).
const MAX_RAYS: u64 = speculum::error::bounds::RAYS / 32;

/// A benchmark case's triangles: its name, vertices and indices.
type Case = (String, Vec<speculum::gpu_types::GpuVertex>, Vec<u32>);

/// The options `args` give, checked (their device-dependent defaults are filled once
/// the device is known), and the rays file read: before any GPU work.
fn lbvh_options(args: &LbvhArgs) -> Result<Options> {
    check_count("--repeats", args.repeats, 1)?;
    if let Some(n) = args.rays.filter(|&n| n == 0 || n as u64 > MAX_RAYS) {
        anyhow::bail!(speculum::Error::Input(format!(
            "--rays {n}: each ray set needs 1 to {MAX_RAYS} rays"
        )));
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
    Ok(Options {
        repeats: args.repeats,
        rays: args.rays.unwrap_or(RAYS_ON_A_CPU),
        check_rays: args.check_rays,
        bits: args.bits,
        builders: args.builder.clone(),
        layouts: args.layout.clone(),
        file_rays,
        keep_hits: dumping,
        khr_rays: args.khr_rays.unwrap_or(0),
        local_sort_scatter: false,
        sort_scan: args.sort_scan,
        refilled: refill_shapes(args)?,
    })
}

pub(super) fn lbvh(args: LbvhArgs) -> Result<()> {
    let c = &args.common;
    let opts = lbvh_options(&args)?;
    let dumping = opts.keep_hits;
    let mut inputs = vec![("--rays-file", args.rays_file.as_deref())];
    inputs.extend(args.scene.iter().map(|s| ("--scene", crate::cli::input_file(s))));
    check_outputs(
        &[
            ("--json", c.json.as_deref(), Kind::Json),
            ("--dump-rays", args.dump_rays.as_deref(), Kind::Json),
            ("--dump-hits", args.dump_hits.as_deref(), Kind::Json),
        ],
        &inputs,
    )?;
    let cases = lbvh_cases(&args)?;
    if dumping && cases.len() * args.builder.len() * args.layout.len() != 1 {
        anyhow::bail!(speculum::Error::Input(format!(
            "--dump-rays/--dump-hits need a single case (one --tris or one --scene, one --builder, one --layout), not {}",
            cases.len() * args.builder.len() * args.layout.len()
        )));
    }
    let text = Text::new(&[c.json.as_deref()], c.quiet);
    let ctx = speculum::vk::Context::new(&speculum::vk::ContextDesc {
        local_sort_scatter: args.local_sort_scatter,
        sort_scan: args.sort_scan,
        ..c.gpu.desc()
    })?;
    let mut opts = opts;
    opts.local_sort_scatter = speculum::tracers::lbvh::sort::SortTile::of_context(&ctx).local;
    let cpu = ctx.device_type == ash::vk::PhysicalDeviceType::CPU;
    opts.rays = args.rays.unwrap_or(if cpu { RAYS_ON_A_CPU } else { RAYS_ON_A_GPU });
    opts.khr_rays = args.khr_rays.unwrap_or(if cpu { KHR_RAYS_ON_A_CPU } else { opts.rays });
    text.line(format_args!(
        "LBVH on {} ({}-bit Morton{}{}, median (p10–p90) of {} runs, GPU ms)",
        ctx.device_name,
        args.bits.bits(),
        if opts.local_sort_scatter {
            ", sort written out in order"
        } else {
            ""
        },
        if opts.sort_scan { ", every sort scanned" } else { "" },
        opts.repeats
    ));
    if args.local_sort_scatter && !opts.local_sort_scatter {
        text.line(format_args!(
            "  (--local-sort-scatter: this device's sort tiles keep the direct scatter)"
        ));
    }
    let runs = (cases.len() * opts.builders.len() * opts.layouts.len()) as u64;
    let bar = progress(runs * (opts.repeats as u64 + 1), "bench lbvh", c.quiet);
    let mut results = Vec::new();
    for (name, v, i) in &cases {
        // Embree's runs of the case, made for its first builder and layout.
        let mut anchor = None;
        for &kind in &opts.builders {
            for &layout in &opts.layouts {
                let case = run_case(
                    &ctx,
                    name,
                    v,
                    i,
                    &opts,
                    (kind, layout),
                    (&mut anchor, &mut || bar.inc(1)),
                )?;
                bar.suspend(|| print_lbvh_case(&text, &case));
                results.push(case);
            }
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
        crate::cli::write_report(path, &report, &text)?;
    }
    crate::cli::check_validation(&ctx)?;
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
/// soups of `--tris` (10K, 100K, 1M without `--tris`, `--surface` or `--scene`), the
/// surfaces, then the scenes.
fn lbvh_cases(args: &LbvhArgs) -> Result<Vec<Case>> {
    use speculum::scene::soup::{bumpy_torus, default_size, random_soup, BUMPY_TORUS_MIN};
    let mut tris = args.tris.clone();
    if tris.is_empty() && args.surface.is_empty() && args.scene.is_empty() {
        tris = vec![10_000, 100_000, 1_000_000];
    }
    let max = speculum::tracers::lbvh::MAX_TRIANGLES;
    for (flag, counts, min) in [
        ("--tris", &tris, 1),
        ("--surface", &args.surface, BUMPY_TORUS_MIN as u32),
    ] {
        if let Some(n) = counts.iter().find(|&&n| n < min || n > max) {
            anyhow::bail!(speculum::Error::Input(format!(
                "{flag} {n}: a case needs {min} to {max} triangles"
            )));
        }
    }
    let mut cases = Vec::new();
    for &n in &tris {
        let (v, i) = random_soup(n as usize, 1.0, default_size(n as usize), n as u64);
        cases.push((format!("soup-{n}"), v, i));
    }
    for &n in &args.surface {
        let (v, i) = bumpy_torus(n as usize);
        let made = i.len() / 3;
        if made > max as usize {
            anyhow::bail!(speculum::Error::Input(format!(
                "--surface {n}: its grid makes {made} triangles, more than the LBVH's {max}"
            )));
        }
        cases.push((format!("surface-{made}"), v, i));
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
    let steps: Vec<String> = (case.sort_steps_ms.0.iter())
        .filter_map(|(s, stat)| {
            Some(format!(
                "{} {:.3}",
                s.trim_start_matches("lbvh.sort."),
                stat.as_ref()?.median
            ))
        })
        .collect();
    let stages: Vec<String> = case
        .builder
        .stages()
        .iter()
        .map(|&s| {
            let ms = format!("{} {:.3}", s.trim_start_matches("lbvh."), case.stages_ms.median(s));
            match s == speculum::tracers::lbvh::SORT && !steps.is_empty() {
                true => format!("{ms} (timed apart: {})", steps.join(", ")),
                false => ms,
            }
        })
        .collect();
    let untimed = match case.untimed_rounds {
        0 => String::new(),
        r => format!(" (+{r} rounds untimed)"),
    };
    text.line(format_args!(
        "{:<14} {:>9} tris  build {}{untimed} ({:7.2} Mtris/s) [by stage {:.3}: {}]  refit {}  compact {}",
        format!("{} {} {}", case.name, case.builder.name(), case.layout.name()),
        case.triangles,
        cell(Some(case.build_ms)),
        case.mtris_per_s,
        case.staged_build_ms.median,
        stages.join(", "),
        cell(Some(case.refit_ms)),
        cell(Some(case.compact_ms))
    ));
    let checks = if case.valid {
        format!("valid; {}", crate::cli::timing_note(&case.timing))
    } else {
        format!(
            "INVALID: {:?} {} {} mismatches, {} {} failed walks",
            case.invariant_error,
            case.coherent.mismatches,
            case.incoherent.mismatches,
            case.coherent.failed_walks,
            case.incoherent.failed_walks
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
    print_walks(text, case);
    print_khr(text, case);
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
            "{:<14} Embree {} ({} CPU threads, wall ms): build {} (Speculum {:.2}x its time, {:.2}x with lbvh.compact); {}",
            "",
            a.quality.to_uppercase(),
            a.threads,
            cell(Some(a.build_ms)),
            a.build_ratio,
            a.static_build_ratio,
            rays.join(", ")
        ));
    }
}

/// A case's walk lines: the CPU replay's counts, the exact nodes' walk, the refilled
/// walk and the rays file's trace, each where the case has it.
fn print_walks(text: &Text, case: &speculum::bench::lbvh::CaseReport) {
    let walk = |w: &speculum::bench::lbvh::WalkPerRay| {
        format!(
            "{:.1} steps, {:.1} boxes, {:.1} triangles, lanes busy {:.2} (8 wide) {:.2} (32 wide)",
            w.steps, w.boxes, w.triangles, w.lanes_busy_8, w.lanes_busy_32
        )
    };
    text.line(format_args!(
        "{:<14} a ray's walk (CPU replay, any device): coherent {}; incoherent {}",
        "",
        walk(&case.walk_per_ray[0]),
        walk(&case.walk_per_ray[1])
    ));
    // Both sets through another walk of the tree, against the case's own.
    let other_walk = |label: &str, [c, i]: &[speculum::bench::rays::RaySetReport; 2]| {
        let ratio = |e: f64, compact: f64| e / compact.max(1e-12);
        text.line(format_args!(
            "{:<14} {label}: coherent {:.2} Mrays/s ({:.2}x), incoherent {:.2} Mrays/s ({:.2}x); {} and {} checked differ, {} failed walks",
            "",
            c.mrays_per_s,
            ratio(c.mrays_per_s, case.coherent.mrays_per_s),
            i.mrays_per_s,
            ratio(i.mrays_per_s, case.incoherent.mrays_per_s),
            c.mismatches,
            i.mismatches,
            c.failed_walks + i.failed_walks
        ));
    };
    if let Some(sets) = &case.exact_nodes {
        other_walk("exact nodes (the dynamic BVH's walk, no compact)", sets);
    }
    for r in &case.refilled {
        let label = format!(
            "lanes refilled at 1/{} idle, {} rays a lane (the same walk)",
            r.shape.share(),
            r.shape.rays_per_lane()
        );
        other_walk(&label, &r.sets);
    }
    if let Some(f) = &case.file {
        text.line(format_args!(
            "{:<14} rays file: {} rays, {} ({:.1} Mrays/s), {:.1}% hit, {} of {} checked differ, {} failed walks",
            "",
            f.rays,
            cell(Some(f.trace_ms)),
            f.mrays_per_s,
            100.0 * f.hit_fraction,
            f.mismatches,
            f.checked,
            f.failed_walks
        ))
    }
}

/// The vendor tracer's lines of a case (`bench::khr`).
fn print_khr(text: &Text, case: &speculum::bench::lbvh::CaseReport) {
    for k in case.khr.iter().flatten() {
        let file = k
            .file
            .as_ref()
            .map_or(String::new(), |f| format!(", file {:.3} Mrays/s", f.mrays_per_s));
        let differ: u32 = [Some(&k.coherent), Some(&k.incoherent), k.file.as_ref()]
            .into_iter()
            .flatten()
            .map(|r| r.mismatches)
            .sum();
        text.line(format_args!(
            "{:<14} KHR {} order: build {} + compact {} ({:.1} B/tri, {:.1} uncompacted); {} rays: coherent {:.3} Mrays/s, incoherent {:.3} Mrays/s{file} (this tree on the same rays: {}; ray by ray against its hits: {}); {differ} of the checked hits differ from the CPU's",
            "",
            k.order,
            cell(Some(k.build_ms)),
            cell(Some(k.compact_ms)),
            k.bytes_per_triangle,
            k.uncompacted_bytes_per_triangle,
            k.coherent.rays,
            k.coherent.mrays_per_s,
            k.incoherent.mrays_per_s,
            k.lbvh_same_rays_mrays_per_s
                .iter()
                .flatten()
                .map(|m| format!("{m:.3}"))
                .collect::<Vec<_>>()
                .join(", "),
            k.lbvh_agreement
                .iter()
                .flatten()
                .map(|(a, t, d)| format!("{a} agree, {t} ties, {d} differ"))
                .collect::<Vec<_>>()
                .join("; "),
        ));
    }
}
