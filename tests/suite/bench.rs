//! The LBVH benchmark checks what it times: a small run is valid, and its figures are
//! consistent with each other.

use crate::common;

use speculum::bench::lbvh::{run_case, Options};
use speculum::passes::rt_trace::Refill;
use speculum::scene::soup::{default_size, random_soup};
use speculum::steady::WarmUp;
use speculum::tracers::lbvh::{BvhKind, MortonBits, StaticLayout};

/// The `room` scene at 160x90: small enough for a quick benchmark run.
fn small_room() -> (speculum::scene::Scene, speculum::Settings) {
    let settings = speculum::Settings {
        width: 160,
        height: 90,
        ..Default::default()
    };
    (speculum::scene::builtin::room().unwrap(), settings)
}

#[test]
fn small_lbvh_benchmark_is_valid_and_consistent() {
    let ctx = common::context();
    let (v, i) = random_soup(5000, 1.0, default_size(5000), 9);
    let opts = Options {
        repeats: 2,
        rays: 4096,
        check_rays: 500,
        bits: MortonBits::Bits30,
        builders: BvhKind::ALL.to_vec(),
        layouts: StaticLayout::ALL.to_vec(),
        file_rays: None,
        keep_hits: false,
        khr_rays: 512,
        local_sort_scatter: false,
        sort_scan: false,
        // Two shapes: the default, and refills only once every lane idles.
        refilled: vec![Refill::DEFAULT, Refill::new(1, 2).unwrap()],
    };
    // Each builder in every layout; the vendor tracer with the first of each.
    let cases = BvhKind::ALL.into_iter().flat_map(|k| StaticLayout::ALL.map(|l| (k, l)));
    let (mut binary_steps, mut wide_steps) = (0.0, 0.0);
    // Embree runs once for the case: every builder and layout reads the same runs.
    let (mut anchor, mut first_anchor) = (None, None);
    for (kind, layout) in cases {
        let c = run_case(
            &ctx,
            "soup-5000",
            &v,
            &i,
            &opts,
            (kind, layout),
            (&mut anchor, &mut || {}),
        )
        .unwrap();
        assert!(c.valid, "{c:?}");
        assert_eq!(c.layout, layout);
        let embree_ms = c
            .embree
            .as_ref()
            .map(|e| e.iter().map(|q| q.build_ms.median).collect::<Vec<_>>());
        assert_eq!(
            *first_anchor.get_or_insert(embree_ms.clone()),
            embree_ms,
            "{kind:?} {layout:?}"
        );
        // A walk's work per ray, replayed on the CPU: the wide layout takes fewer steps
        // than the binary one for the same tree (the builds are deterministic), the
        // compressed wide one fewer still.
        let [_, incoherent] = c.walk_per_ray;
        assert!(
            incoherent.steps >= 1.0 && incoherent.boxes >= 2.0 * incoherent.steps,
            "{incoherent:?}"
        );
        // The exact nodes' walk (the dynamic BVH's) on each builder's first layout,
        // every checked hit the CPU's, with the dynamic BVH's id bit.
        let sound = |sets: &[speculum::bench::rays::RaySetReport; 2]| {
            for s in sets {
                assert!(s.checked > 0 && s.mismatches == 0 && s.failed_walks == 0, "{s:?}");
                assert!(s.mrays_per_s > 0.0 && s.hit_fraction > 0.0, "{s:?}");
            }
        };
        match (&c.exact_nodes, layout == opts.layouts[0]) {
            (Some(sets), true) => sound(sets),
            (None, false) => {}
            (e, _) => panic!("{layout:?}: exact nodes {e:?}"),
        }
        // The walk with its lanes refilled, asked for: on every case, in each shape.
        let shapes: Vec<Refill> = c.refilled.iter().map(|r| r.shape).collect();
        assert_eq!(shapes, opts.refilled, "{kind:?} {layout:?}");
        c.refilled.iter().for_each(|r| sound(&r.sets));
        // Lanes in lockstep: random rays' walks differ in length, and a wider group
        // idles at least as many lanes.
        let busy = (incoherent.lanes_busy_32, incoherent.lanes_busy_8);
        assert!(0.0 < busy.0 && busy.0 <= busy.1 && busy.1 < 1.0, "{incoherent:?}");
        match layout {
            StaticLayout::Binary => binary_steps = incoherent.steps,
            StaticLayout::Wide => {
                assert!(incoherent.steps < binary_steps, "{kind:?}: {incoherent:?}");
                wide_steps = incoherent.steps;
            }
            StaticLayout::Wide8 => assert!(incoherent.steps < wide_steps, "{kind:?}: {incoherent:?}"),
        }
        // The vendor tracer on the first builder's case: both orders, every checked hit
        // agreeing with the CPU, its builds timed.
        let first = kind == opts.builders[0] && layout == opts.layouts[0];
        match (&c.khr, first && ctx.ray_tracing.is_some()) {
            (Some(k), true) => {
                assert_eq!(k.iter().map(|k| k.order).collect::<Vec<_>>(), ["file", "morton"]);
                for k in k {
                    assert!(k.build_ms.median > 0.0 && k.bytes_per_triangle > 0.0, "{k:?}");
                    assert_eq!(
                        (k.coherent.rays, k.coherent.mismatches, k.incoherent.mismatches),
                        (512, 0, 0)
                    );
                    assert!(k.coherent.checked > 0 && k.incoherent.hit_fraction > 0.0, "{k:?}");
                    // Ray by ray against the LBVH: every ray of both sets compared.
                    for a in &k.lbvh_agreement[..2] {
                        let (agree, ties, differ) = a.expect("both sets compared");
                        assert_eq!(agree + ties + differ, 512, "{k:?}");
                        assert!(differ * 1000 <= 512 && agree >= 500, "{k:?}");
                    }
                    assert!(k.sound(), "{k:?}");
                }
            }
            (None, false) => {}
            (k, _) => panic!("{kind:?}: khr {k:?}"),
        }
        assert_eq!((c.triangles, c.builder), (5000, kind));
        // The sort's steps, timed apart on the case's first builder and layout: a sort
        // of one tile (lavapipe's 8,192 keys) runs the scatter alone.
        use speculum::tracers::lbvh::sort::{SortTile, COUNT, SCAN, SCATTER, STEPS};
        let steps = |s| c.sort_steps_ms.get(s).map(|t| t.median);
        if (kind, layout) == (BvhKind::ALL[0], StaticLayout::ALL[0]) {
            let tiles = 5000 > SortTile::of_context(&ctx).keys();
            assert!(steps(SCATTER).is_some_and(|ms| ms > 0.0), "{:?}", c.sort_steps_ms);
            assert_eq!((steps(COUNT).is_some(), steps(SCAN).is_some()), (tiles, tiles));
        } else {
            assert!(STEPS.iter().all(|&s| steps(s).is_none()), "{kind:?} {layout:?}");
        }
        for s in kind.stages() {
            assert!(c.stages_ms.median(s) > 0.0, "{kind:?}: stage {s} timed");
        }
        // The builds timed stage by stage cover their stages; the builds timed whole
        // (no stamps between the stages) are timed too.
        let sum: f64 = kind.stages().iter().map(|s| c.stages_ms.median(s)).sum();
        assert!(
            c.staged_build_ms.median >= 0.9 * sum,
            "{kind:?}: the staged build ({:?}) covers its stages ({sum})",
            c.staged_build_ms
        );
        assert!(
            c.build_ms.median > 0.0 && c.staged_build_ms.samples == 2,
            "{:?}",
            c.build_ms
        );
        assert!(
            c.sah_ratio > 0.8 && c.sah_ratio < 2.0,
            "{kind:?}: SAH ratio {}",
            c.sah_ratio
        );
        assert!((c.nodes_per_triangle - 1.0).abs() < 1e-3);
        assert_eq!(c.untimed_rounds, 0, "{kind:?}: the first submission ends the build");
        assert_eq!(c.coherent.checked, 500);
        assert!(c.coherent.hit_fraction > 0.05 && c.incoherent.hit_fraction > 0.05);
        assert!(c.coherent.mrays_per_s > 0.0 && c.refit_ms.median > 0.0);
        assert!(c.build_ms.p10 <= c.build_ms.median && c.build_ms.median <= c.build_ms.p90);
        assert_eq!(
            (c.build_ms.samples, c.refit_ms.samples, c.coherent.trace_ms.samples),
            (2, 2, 2)
        );
    }
}

/// With the Embree anchor built in, `bench lbvh` also builds the same triangles with
/// Embree LOW and MEDIUM and traces the same rays: both qualities are reported with
/// their timings, and Embree's hits agree with Speculum's on every ray but ties
/// (checked on a soup and on `room`, a scene of walls meeting at edges). Without the
/// feature the report's `embree` is null.
#[test]
fn lbvh_benchmark_anchors_against_embree() {
    let ctx = common::context();
    let opts = Options {
        repeats: 1,
        rays: 8192,
        check_rays: 200,
        bits: MortonBits::Bits30,
        builders: BvhKind::ALL.to_vec(),
        layouts: StaticLayout::ALL.to_vec(),
        file_rays: None,
        keep_hits: false,
        khr_rays: 0,
        local_sort_scatter: false,
        sort_scan: false,
        refilled: Vec::new(),
    };
    let (v, i) = random_soup(3000, 1.0, default_size(3000), 11);
    let room = speculum::scene::builtin::room().unwrap();
    // One anchor for both cases: the second is measured anew (its hits agree with room's).
    let mut anchor = None;
    for (name, v, i) in [("soup-3000", &v, &i), ("room", &room.vertices, &room.indices)] {
        let c = run_case(
            &ctx,
            name,
            v,
            i,
            &opts,
            (BvhKind::Lbvh, StaticLayout::Binary),
            (&mut anchor, &mut || {}),
        )
        .unwrap();
        assert!(c.valid, "{name}: {c:?}");
        if !cfg!(feature = "embree") {
            assert!(c.embree.is_none());
            continue;
        }
        let anchors = c.embree.as_ref().expect("the anchor ran");
        let qualities: Vec<&str> = anchors.iter().map(|a| a.quality).collect();
        assert_eq!(qualities, ["low", "medium"]);
        for a in anchors {
            assert!(
                a.build_ms.median > 0.0
                    && a.build_ratio.is_finite()
                    && a.static_build_ratio > a.build_ratio
                    && a.threads >= 1,
                "{a:?}"
            );
            assert!(a.file.is_none());
            for (set, r) in [("coherent", &a.coherent), ("incoherent", &a.incoherent)] {
                assert_eq!(r.agree + r.ties + r.disagree, 8192, "{name} {set}");
                // A ray through an edge may slip past one of two non-watertight tests.
                assert!(r.disagree <= 8, "{name} {} {set}: {r:?}", a.quality);
                assert!(r.ties <= 82, "{name} {} {set}: {r:?}", a.quality);
                assert!(r.mrays_per_s > 0.0 && r.speed_ratio > 0.0, "{r:?}");
            }
        }
    }
}

/// The reflection split benchmark's sweep is consistent: same reflective pixels at
/// every point, a failed share that only grows, everything ray traced at the end.
#[test]
fn reflection_split_benchmark_is_valid() {
    let ctx = common::context();
    let (scene, settings) = small_room();
    let r = speculum::bench::reflect::run(&ctx, &scene, &settings, WarmUp::Frames(0), 2, &mut || {}).unwrap();
    assert!(r.valid, "{r:?}");
    assert_eq!(r.points.len(), speculum::bench::reflect::sweep(&settings).len());
    assert!(r.points[0].rt_pixel_fraction < 0.9 && r.points.last().unwrap().rt_pixel_fraction == 1.0);
    // The share must actually vary along the step budgets, not only at the last point.
    let budgets = &r.points[..r.points.len() - 1];
    assert!(
        budgets.last().unwrap().rt_pixel_fraction > budgets[0].rt_pixel_fraction + 0.05,
        "{r:?}"
    );
    assert!(r
        .points
        .iter()
        .all(|p| p.passes_ms.get("rt.reflect").is_some() && p.passes_ms.get("ssr.trace").is_some()));
    assert!(
        r.points
            .iter()
            .all(|p| p.frame_over_rt.median > 0.0 && p.frame_ms.median > 0.0)
            && r.rt_frame_ms.median > 0.0
    );
}

/// The modes benchmark measures every mode in one run and checks itself: same
/// reflective pixels everywhere, rt traces them all, the SSR-first hybrid fewer and the
/// adaptive one (the default) no more, rt's SSIM against itself is 1, and only the
/// reflecting modes have reflection passes.
#[test]
fn modes_benchmark_is_valid() {
    let ctx = common::context();
    let (scene, settings) = small_room();
    let r = speculum::bench::modes::run(&ctx, &scene, &settings, WarmUp::Frames(0), 2, &mut || {}).unwrap();
    assert!(r.valid, "{r:?}");
    // Every mode, then hybrid with the other policy.
    assert_eq!(r.modes.len(), speculum::settings::Mode::ALL.len() + 1);
    assert_eq!(r.modes.last().unwrap().mode, "hybrid_ssr_first");
    let by = |name: &str| r.modes.iter().find(|m| m.mode == name).unwrap();
    assert_eq!(by("rt").ssim_vs_rt, 1.0);
    assert_eq!(by("rt").frame_over_rt.median, 1.0);
    let first = by("hybrid_ssr_first");
    assert!(first.traced_pixels > 0 && first.traced_pixels < by("rt").traced_pixels);
    assert!(by("hybrid").traced_pixels > 0 && by("hybrid").traced_pixels <= by("rt").traced_pixels);
    assert!(by("hybrid").ssim_vs_rt > 0.9 && by("raster").ssim_vs_rt < by("hybrid").ssim_vs_rt);
    assert!(by("raster").passes_ms.get("ssr.trace").is_none());
    assert!(by("hybrid").passes_ms.get("rt.reflect").is_some() && by("ssr").passes_ms.get("rt.reflect").is_none());
    assert!(by("rt").passes_ms.get("ssr.trace").is_none(), "rt mode marches nothing");
}

/// `bench shadows` on a small `room`: valid (the same lit pixels in every source, rays
/// traces them all, the hybrid fewer and exactly the rays' visibility there, the map
/// none), the rays frame equal to itself, the hybrid closer to it than the map, and
/// only the sources that trace have the tracing passes.
#[test]
fn shadows_benchmark_is_valid() {
    let ctx = common::context();
    let (scene, settings) = small_room();
    let r = speculum::bench::shadows::run(&ctx, &scene, &settings, WarmUp::Frames(0), 2, &mut || {}).unwrap();
    assert!(r.valid, "{r:?}");
    let by = |name: &str| r.shadows.iter().find(|s| s.shadows == name).unwrap();
    let (map, hybrid, rays) = (by("map"), by("hybrid"), by("rays"));
    assert_eq!((rays.vs_rays.ssim, rays.vs_rays.visibility_agreement), (1.0, 1.0));
    assert_eq!(rays.frame_over_rays.median, 1.0);
    assert!(hybrid.traced_pixels > 0 && hybrid.traced_pixels < rays.traced_pixels);
    assert!(hybrid.vs_rays.visibility_agreement > map.vs_rays.visibility_agreement);
    assert!(hybrid.vs_rays.visibility_agreement >= 0.995, "{:?}", hybrid.vs_rays);
    assert!(map.passes_ms.get("shadow.trace").is_none() && map.trace_over_rays.is_none());
    assert!(rays.passes_ms.get("shadow.map").is_none(), "rays render no shadow map");
    assert!(hybrid.trace_over_rays.is_some_and(|t| t > 0.0));
}

/// `bench dynamic` on `stress` with 4 and 12 bodies: every point valid (both BVHs'
/// hits equal the CPU's), the triangles growing with the bodies, each time measured.
#[test]
fn small_dynamic_benchmark_is_valid() {
    let ctx = common::context();
    let settings = speculum::Settings {
        width: 96,
        height: 54,
        ..Default::default()
    };
    let mut points = Vec::new();
    for n in [4, 12] {
        let mut scene = speculum::scene::builtin::stress().unwrap();
        scene.set_spawn_count(n).unwrap();
        let p = speculum::bench::dynamic::run_point(&ctx, &scene, &settings, WarmUp::Frames(1), 4, 3000, &mut || {})
            .unwrap();
        assert!(p.valid, "{p:?}");
        assert_eq!(p.bodies, n);
        for (what, ms) in [
            ("sim.transform", p.sim_transform_ms.median),
            ("rebuild", p.rebuild_ms.median),
            ("refit", p.refit_ms.median),
            ("rt.reflect", p.rt_reflect_ms.median),
            ("trace", p.trace_refit_ms),
        ] {
            assert!(ms > 0.0 && ms.is_finite(), "{n} bodies: {what} {ms}");
        }
        assert!(p.frame_ms.median >= p.rebuild_ms.median);
        // The vendor tracer's frames, where the device has it: its top level timed
        // every frame, no cloth here.
        match (&p.khr, ctx.ray_tracing.is_some()) {
            (Some(k), true) => {
                assert!(
                    k.as_tlas_ms.median > 0.0 && k.frame_ms.median > k.as_tlas_ms.median,
                    "{k:?}"
                );
                assert_eq!(k.as_cloth_ms.median, 0.0);
                assert!(k.rt_reflect_ms.median > 0.0 && k.frame_over_lbvh > 0.0, "{k:?}");
            }
            (None, false) => {}
            (k, _) => panic!("{n} bodies: khr {k:?}"),
        }
        points.push(p);
    }
    assert!(points[1].dynamic_triangles > 2 * points[0].dynamic_triangles);
}

/// `bench dynamic --skinned`: a skinned tube's point is valid, its skinning and
/// (skin + refit) / rebuild measured, none without an animated model; the command
/// takes one axis and a size in range, or says why in one line.
#[test]
fn skinned_dynamic_benchmark_is_valid() {
    let ctx = common::context();
    let settings = speculum::Settings {
        width: 96,
        height: 54,
        ..Default::default()
    };
    let scene = speculum::scene::builtin::skinned_tube(20_000).unwrap();
    assert_eq!(scene.dynamic_triangle_count(), 2 * 256 * 40);
    assert_eq!(scene.animated.as_ref().unwrap().joints.len(), 16);
    let p =
        speculum::bench::dynamic::run_point(&ctx, &scene, &settings, WarmUp::Frames(1), 4, 3000, &mut || {}).unwrap();
    assert!(p.valid, "{p:?}");
    assert_eq!(p.joints, 16);
    assert!(p.sim_skin_ms.median > 0.0 && p.refit_ms.median > 0.0 && p.rebuild_ms.median > 0.0);
    let want = (p.sim_skin_ms.median + p.refit_ms.median) / p.rebuild_ms.median;
    let got = p.skin_refit_over_rebuild.unwrap();
    assert!(
        got > 0.0 && got < 10.0 * want && want < 10.0 * got,
        "{got} vs medians' {want}"
    );
    let mut stress = speculum::scene::builtin::stress().unwrap();
    stress.set_spawn_count(2).unwrap();
    let q =
        speculum::bench::dynamic::run_point(&ctx, &stress, &settings, WarmUp::Frames(0), 1, 100, &mut || {}).unwrap();
    assert_eq!(
        (q.skin_refit_over_rebuild, q.sim_skin_ms.median, q.joints),
        (None, 0.0, 0)
    );
    for (args, says) in [
        (
            &["--skinned", "10"][..],
            "a skinned tube takes 1000..=4000000 triangles, not 10",
        ),
        (
            &["--skinned", "5000", "--bodies", "3"][..],
            "give one of --bodies, --cloth-res and --skinned",
        ),
    ] {
        let out = speculum_bin(&[&["bench", "dynamic", "--quiet"][..], args].concat());
        let lines: Vec<&str> = out.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert!(
            !out.ok() && lines.len() == 1 && lines[0].contains(says),
            "{}",
            out.stderr
        );
    }
}

fn speculum_bin(args: &[&str]) -> common::Output {
    common::speculum(args).run()
}

/// `bench suite --quick` runs every case with every scope timed; compared with itself
/// it finds no regression; a baseline doctored to make one pass 2x faster flags that
/// pass (and exits 1 with --fail-on-regression); a bad baseline is refused.
#[test]
fn the_quick_suite_runs_and_compares_with_a_baseline() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("suite.json");
    let md = dir.path().join("suite.md");
    let (j, m) = (json.to_str().unwrap(), md.to_str().unwrap());
    let out = speculum_bin(&[
        "bench",
        "suite",
        "--quick",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--json",
        j,
        "--markdown",
        m,
        "--quiet",
    ]);
    assert!(out.ok(), "{}", out.stderr);
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["kind"], "bench.suite");
    assert_eq!(report["suite_version"], speculum::bench::suite::SUITE_VERSION);
    assert_eq!(report["validation_messages"], 0);
    let ids: Vec<&str> = report["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_str().unwrap())
        .collect();
    let want: Vec<String> = speculum::bench::suite::cases(true).iter().map(|c| c.id()).collect();
    assert_eq!(ids, want);
    for c in report["cases"].as_array().unwrap() {
        let whole = if c["kind"] == "lbvh" { "lbvh" } else { "frame" };
        let s = &c["passes_ms"][whole];
        assert_eq!(s["samples"], 3, "{}", c["id"]);
        assert!(s["median"].as_f64().unwrap() > 0.0 && s["p10"].as_f64() <= s["p90"].as_f64());
    }
    assert!(
        report["cases"][1]["passes_ms"]["rt.reflect"]["median"]
            .as_f64()
            .unwrap()
            > 0.0,
        "hybrid traces"
    );
    assert!(
        report["cases"][0]["passes_ms"].get("rt.reflect").is_none(),
        "ssr does not"
    );
    assert!(std::fs::read_to_string(&md)
        .unwrap()
        .contains("| room/hybrid/480x270 |"));

    // The run against itself: every ratio 1, nothing flagged.
    let again = dir.path().join("again.md");
    let compare = |baseline: &str, md: &std::path::Path| {
        speculum_bin(&[
            "bench",
            "suite",
            "--compare",
            j,
            "--baseline",
            baseline,
            "--fail-on-regression",
            "--markdown",
            md.to_str().unwrap(),
            "--quiet",
        ])
    };
    let out = compare(j, &again);
    assert!(out.ok(), "self-comparison: {}", out.stderr);
    let text = std::fs::read_to_string(&again).unwrap();
    assert!(
        text.lines().count() > 20 && !text.contains("Regression") && !text.contains("Faster"),
        "{text}"
    );

    // A baseline whose gbuffer on room/hybrid took half the time: that pass regressed.
    let mut doctored = report.clone();
    let g = &mut doctored["cases"][1]["passes_ms"]["gbuffer"];
    for k in ["median", "p10", "p90"] {
        g[k] = serde_json::json!(g[k].as_f64().unwrap() / 2.0);
    }
    let doctored_path = dir.path().join("doctored.json");
    std::fs::write(&doctored_path, serde_json::to_string(&doctored).unwrap()).unwrap();
    let flagged = dir.path().join("flagged.md");
    let out = compare(doctored_path.to_str().unwrap(), &flagged);
    let err = out.stderr;
    assert_eq!(out.code, 1, "{err}");
    assert!(err.contains("room/hybrid/480x270 gbuffer"), "{err}");
    let text = std::fs::read_to_string(&flagged).unwrap();
    let regressions: Vec<&str> = text.lines().filter(|l| l.contains("Regression")).collect();
    assert_eq!(regressions.len(), 1, "{text}");
    // And a fresh run against the first, with a generous band, runs the comparison.
    let out = speculum_bin(&[
        "bench",
        "suite",
        "--quick",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--baseline",
        j,
        "--threshold",
        "3",
        "--quiet",
    ]);
    assert!(out.ok(), "{}", out.stderr);
    assert!(
        regressions[0].starts_with("| room/hybrid/480x270 | gbuffer |"),
        "{text}"
    );

    // Bad baselines: named, before any GPU work.
    for (content, says) in [("{}", "not a bench suite report"), ("[1", "not JSON")] {
        let bad = dir.path().join("bad.json");
        std::fs::write(&bad, content).unwrap();
        let out = speculum_bin(&["bench", "suite", "--quick", "--baseline", bad.to_str().unwrap()]);
        let err = out.stderr;
        assert_eq!(out.code, 1, "{err}");
        assert!(err.contains(says), "{err}");
    }
}

/// `bench lbvh --rays-file --dump-rays --dump-hits`: the file's rays come back byte for
/// byte, and their hits (t and triangle in the soup's order, misses as +inf and
/// 0xFFFFFFFF) are what brute force over the same soup finds.
#[test]
fn lbvh_traces_a_rays_file_and_dumps_its_hits() {
    use speculum::bench::rays_file::{read_hits, write_rays};
    use speculum::gpu_types::Ray;
    let n = 700u32;
    let (v, i) = random_soup(n as usize, 1.0, default_size(n as usize), n as u64);
    let mut rng = 99u64;
    let mut r = || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    };
    let size = default_size(n as usize);
    let rays: Vec<Ray> = (0..3000)
        .map(|k| {
            let o = [r() * size * 1.5, r() * size * 1.5, r() * size * 1.5];
            let d = [r(), r(), r() + 0.01];
            Ray {
                origin: o,
                dir: d,
                tmin: 0.0,
                tmax: if k % 3 == 0 { 0.5 * size } else { f32::INFINITY },
            }
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let (rf, dr, dh) = (
        dir.path().join("rays.bin"),
        dir.path().join("out_rays.bin"),
        dir.path().join("hits.bin"),
    );
    std::fs::write(&rf, write_rays(&rays)).unwrap();
    let out = speculum_bin(&[
        "bench",
        "lbvh",
        "--tris",
        &n.to_string(),
        "--repeats",
        "1",
        "--rays",
        "1024",
        "--check-rays",
        "200",
        "--builder",
        "lbvh",
        "--layout",
        "wide",
        "--rays-file",
        rf.to_str().unwrap(),
        "--dump-rays",
        dr.to_str().unwrap(),
        "--dump-hits",
        dh.to_str().unwrap(),
        "--quiet",
        "--json",
        dir.path().join("r.json").to_str().unwrap(),
    ]);
    assert!(out.ok(), "{}", out.stderr);
    // Without --khr-rays the vendor tracer takes every ray of a set on a GPU and 512 on a
    // CPU device (lavapipe traces file-order soups thousands of times slower: bounded).
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("r.json")).unwrap()).unwrap();
    let ctx = common::context();
    let want = match ctx.device_type {
        ash::vk::PhysicalDeviceType::CPU => 512,
        _ => 1024,
    };
    assert_eq!(report["options"]["khr_rays"], want, "{}", report["options"]);
    if ctx.ray_tracing.is_some() {
        assert_eq!(report["cases"][0]["khr"][0]["coherent"]["rays"], want);
    }
    drop(ctx);
    assert_eq!(
        std::fs::read(&dr).unwrap(),
        std::fs::read(&rf).unwrap(),
        "the rays come back as given"
    );
    let hits = read_hits(&std::fs::read(&dh).unwrap(), "hits").unwrap();
    assert_eq!(hits.len(), rays.len());
    let (mut hit, mut miss) = (0, 0);
    for (k, (ray, &(t, tri))) in rays.iter().zip(&hits).enumerate() {
        let want = speculum::cpu_ref::trace::brute_force(ray, &v, &i);
        if want.prim == speculum::shader_defines::BVH_INVALID {
            assert_eq!((t, tri), (f32::INFINITY, u32::MAX), "ray {k}: a miss");
            miss += 1;
        } else {
            let close = (t - want.t).abs() <= 1e-5 * t.abs().max(1.0);
            assert!(close, "ray {k}: t {t} vs {}", want.t);
            assert!(tri == want.prim || close, "ray {k}");
            assert!(tri < n);
            hit += 1;
        }
    }
    assert!(hit > 300 && miss > 300, "{hit} hits, {miss} misses");
    // A malformed rays file is refused before GPU work, and dumps need one case.
    std::fs::write(&rf, [0u8; 33]).unwrap();
    let out = speculum_bin(&["bench", "lbvh", "--tris", "100", "--rays-file", rf.to_str().unwrap()]);
    assert_eq!(out.code, 1);
    assert!(out.stderr.contains("32-byte rays"));
    let out = speculum_bin(&[
        "bench",
        "lbvh",
        "--tris",
        "100",
        "200",
        "--dump-hits",
        dh.to_str().unwrap(),
    ]);
    assert!(out.stderr.contains("single case"));
}
