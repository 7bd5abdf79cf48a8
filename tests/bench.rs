//! The LBVH benchmark checks what it times: a small run is valid, and its figures are
//! consistent with each other.

mod common;

use speculum::bench::lbvh::{run_case, Options, STAGES};
use speculum::passes::lbvh::MortonBits;
use speculum::scene::soup::{default_size, random_soup};

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
    };
    let c = run_case(&ctx, "soup-5000", &v, &i, &opts, &mut || {}).unwrap();
    assert!(c.valid, "{c:?}");
    assert_eq!(c.triangles, 5000);
    for s in STAGES {
        assert!(c.stages_ms.median(s) > 0.0, "stage {s} timed");
    }
    let sum: f64 = STAGES.iter().map(|s| c.stages_ms.median(s)).sum();
    assert!(
        c.build_ms.median >= 0.9 * sum,
        "the whole build ({:?}) covers its stages ({sum})",
        c.build_ms
    );
    assert!(c.sah_ratio > 0.8 && c.sah_ratio < 2.0, "SAH ratio {}", c.sah_ratio);
    assert!((c.nodes_per_triangle - 2.0).abs() < 1e-3);
    assert_eq!(c.coherent.checked, 500);
    assert!(c.coherent.hit_fraction > 0.05 && c.incoherent.hit_fraction > 0.05);
    assert!(c.coherent.mrays_per_s > 0.0 && c.refit_ms.median > 0.0);
    assert!(c.build_ms.p10 <= c.build_ms.median && c.build_ms.median <= c.build_ms.p90);
    assert_eq!(
        (c.build_ms.samples, c.refit_ms.samples, c.coherent.trace_ms.samples),
        (2, 2, 2)
    );
    common::assert_no_validation_messages(&ctx);
}

/// The reflection split benchmark's sweep is consistent: same reflective pixels at
/// every point, a failed share that only grows, everything ray traced at the end.
#[test]
fn reflection_split_benchmark_is_valid() {
    let ctx = common::context();
    let (scene, settings) = small_room();
    let r = speculum::bench::reflect::run(&ctx, &scene, &settings, 0, 2, &mut || {}).unwrap();
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
    common::assert_no_validation_messages(&ctx);
}

/// The modes benchmark measures every mode in one run and checks itself: same
/// reflective pixels everywhere, rt traces them all and hybrid fewer, rt's SSIM against
/// itself is 1, and only the reflecting modes have reflection passes.
#[test]
fn modes_benchmark_is_valid() {
    let ctx = common::context();
    let (scene, settings) = small_room();
    let r = speculum::bench::modes::run(&ctx, &scene, &settings, 0, 2, &mut || {}).unwrap();
    assert!(r.valid, "{r:?}");
    assert_eq!(r.modes.len(), speculum::settings::Mode::ALL.len());
    let by = |name: &str| r.modes.iter().find(|m| m.mode == name).unwrap();
    assert_eq!(by("rt").ssim_vs_rt, 1.0);
    assert_eq!(by("rt").frame_over_rt.median, 1.0);
    assert!(by("hybrid").traced_pixels > 0 && by("hybrid").traced_pixels < by("rt").traced_pixels);
    assert!(by("hybrid").ssim_vs_rt > 0.9 && by("raster").ssim_vs_rt < by("hybrid").ssim_vs_rt);
    assert!(by("raster").passes_ms.get("ssr.trace").is_none());
    assert!(by("hybrid").passes_ms.get("rt.reflect").is_some() && by("ssr").passes_ms.get("rt.reflect").is_none());
    assert!(by("rt").passes_ms.get("ssr.trace").is_none(), "rt mode marches nothing");
    common::assert_no_validation_messages(&ctx);
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
        let p = speculum::bench::dynamic::run_point(&ctx, &scene, &settings, 1, 4, 3000, &mut || {}).unwrap();
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
        points.push(p);
    }
    assert!(points[1].dynamic_triangles > 2 * points[0].dynamic_triangles);
    common::assert_no_validation_messages(&ctx);
}
