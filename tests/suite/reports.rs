//! Every JSON report follows the one schema (`speculum::report`): an object starting
//! with the common header keys, every key present (nulls where a value does not
//! apply), a `Stat` (median, p10, p90, samples) beside every timing, and `passes_ms`
//! listing every scope of the frame. Runs each report kind through the real binary.

use crate::common;

use serde_json::Value;
use speculum::tracers::lbvh::{BvhKind, StaticLayout};
use std::path::Path;

fn speculum(args: &[&str], dir: &Path) -> Value {
    let out = common::speculum(args).dir(dir).run();
    let stderr = &out.stderr;
    assert!(out.ok(), "{args:?}: {stderr}");
    assert!(!stderr.contains("[vulkan"), "{args:?}: {stderr}");
    let text = std::fs::read_to_string(dir.join("r.json")).unwrap_or_else(|_| out.stdout.clone());
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {text}"))
}

/// The header every report starts with.
fn check_header(r: &Value, kind: &str, gpu: bool) {
    let obj = r.as_object().expect("a report is an object");
    let keys: Vec<&String> = obj.keys().collect();
    let header = [
        "schema",
        "kind",
        "speculum_version",
        "git_commit",
        "device",
        "settings",
        "validation_messages",
    ];
    assert_eq!(
        &keys[..header.len()],
        header.map(String::from).iter().collect::<Vec<_>>(),
        "{kind}"
    );
    assert_eq!(r["schema"], speculum::report::SCHEMA);
    assert_eq!(r["kind"], kind);
    assert!(r["git_commit"].as_str().is_some_and(|c| !c.is_empty()));
    if gpu {
        let d = &r["device"];
        for k in [
            "name",
            "kind",
            "driver_name",
            "driver_info",
            "driver_version",
            "vulkan_version",
        ] {
            assert!(!d[k].is_null(), "{kind}: device.{k}");
        }
        assert!(d["vulkan_version"].as_str().unwrap().starts_with("1."));
        assert_eq!(r["validation_messages"], 0, "{kind}: validation was on");
    } else {
        assert!(r["device"].is_null() && r["settings"].is_null());
    }
}

fn check_stat(v: &Value, what: &str) {
    for k in ["median", "p10", "p90", "samples"] {
        assert!(v[k].is_number(), "{what}: {k} in {v}");
    }
    let (p10, m, p90) = (
        v["p10"].as_f64().unwrap(),
        v["median"].as_f64().unwrap(),
        v["p90"].as_f64().unwrap(),
    );
    assert!(p10 <= m && m <= p90, "{what}: {v}");
}

/// The scopes only a dynamic scene runs (these reports are of static scenes).
const DYNAMIC_SCOPES: [&str; 11] = [
    "sim.rigid",
    "sim.transform",
    "sim.cloth",
    "sim.skin",
    "lbvh.bounds",
    "lbvh.morton",
    "lbvh.sort",
    "lbvh.fit",
    "lbvh.refit",
    "as.cloth",
    "as.tlas",
];

/// The scopes only shadows other than `map` run (these reports are of `map` shadows).
const TRACED_SHADOW_SCOPES: [&str; 3] = ["shadow.classify", "shadow.compact", "shadow.trace"];

/// The scope only a G-buffer by rays runs (`visibility`).
const RAYS_VISIBILITY: &str = "gbuffer.trace";

/// `passes_ms` of frames with `map` shadows and a rasterized G-buffer (see
/// `check_scopes`).
fn check_passes(p: &Value, not_run: &[&str]) {
    check_scopes(p, &[not_run, &TRACED_SHADOW_SCOPES, &[RAYS_VISIBILITY]].concat());
}

/// `passes_ms` has every scope of the frame, in frame order; `null` where not run
/// (`not_run`, and a dynamic scene's scopes).
fn check_scopes(p: &Value, not_run: &[&str]) {
    check_scopes_or(p, not_run, &[]);
}

/// `check_scopes`, with scopes that may or may not have run (`either`: an adaptive
/// stage's, whose choice may change within the measured frames).
fn check_scopes_or(p: &Value, not_run: &[&str], either: &[&str]) {
    let not_run: Vec<&str> = not_run.iter().chain(&DYNAMIC_SCOPES).copied().collect();
    // The adaptive hybrid's recheck runs one marching frame in 64.
    let either = [either, &[speculum::renderer::RECHECK]].concat();
    let names: Vec<&str> = p.as_object().unwrap().keys().map(String::as_str).collect();
    let want: Vec<&str> = speculum::renderer::SCOPES
        .iter()
        .copied()
        .filter(|s| *s != speculum::renderer::FRAME)
        .collect();
    assert_eq!(names, want);
    for (name, v) in p.as_object().unwrap() {
        if either.contains(&name.as_str()) {
            if !v.is_null() {
                check_stat(v, name);
            }
            continue;
        }
        if not_run.contains(&name.as_str()) {
            assert!(v.is_null(), "{name} did not run: {v}");
        } else {
            check_stat(v, name);
        }
    }
}

#[test]
fn render_report_follows_the_schema() {
    let dir = tempfile::tempdir().unwrap();
    let r = speculum(
        &[
            "render",
            "--width",
            "48",
            "--height",
            "32",
            "--frames",
            "8",
            "--warmup",
            "0",
            "--mode",
            "ssr",
            "--timings",
            "r.json",
        ],
        dir.path(),
    );
    check_header(&r, "render", true);
    assert_eq!(
        (r["settings"]["width"].as_u64(), r["settings"]["mode"].as_str()),
        (Some(48), Some("ssr"))
    );
    // The default adaptive G-buffer prices both ways in the first frames (three checked
    // frames each): both G-buffer scopes ran, when every frame passed its check (else
    // the rays may not have had their turn yet).
    let checked = r["timing"]["discarded"] == 0 && r["timing"]["failed"] == 0;
    let either: &[&str] = if checked { &[] } else { &[RAYS_VISIBILITY] };
    check_scopes_or(
        &r["passes_ms"],
        &[&["ssr.compact", "rt.reflect"][..], &TRACED_SHADOW_SCOPES].concat(),
        either,
    );
    let v = &r["visibility"];
    assert_eq!(v["recheck_every"], speculum::renderer::stages::RECHECK_EVERY, "{v}");
    let ways = v["ways"].as_array().unwrap();
    let names: Vec<&str> = ways.iter().map(|w| w["way"].as_str().unwrap()).collect();
    assert_eq!(names, ["raster", "rays"]);
    if checked {
        // Every frame checked (a frame that fails the check prices nothing, and its way
        // is taken again): both ways tried three times and priced, and the frames take
        // the cheaper (or the one in use within `HOLD` of it).
        for w in ways {
            assert!(w["frames"].as_u64().unwrap() >= 3, "{v}");
        }
        let ms: Vec<f64> = ways.iter().map(|w| w["ms"].as_f64().expect("priced")).collect();
        let (taken, other) = match v["way"].as_str().unwrap() {
            "raster" => (ms[0], ms[1]),
            "rays" => (ms[1], ms[0]),
            w => panic!("{w}"),
        };
        assert!(taken * (1.0 - speculum::renderer::stages::HOLD) <= other, "{v}");
    }
    check_stat(&r["frame_ms"], "frame_ms");
    // The default static_ploc: the tree kept is the one whose walk was cheaper.
    let t = &r["static_tree"];
    let (ploc, lbvh) = (t["ploc_ms"].as_f64().unwrap(), t["lbvh_ms"].as_f64().unwrap());
    assert!(ploc > 0.0 && lbvh > 0.0 && t["rays"].as_u64().unwrap() > 0, "{t}");
    assert_eq!(t["kept"], if lbvh < ploc { "lbvh" } else { "ploc" }, "{t}");
    // The default `fastest` layout: the nodes kept are the cheapest walk's.
    let l = &r["static_layout"];
    let priced: Vec<(&str, f64)> = ["binary", "wide", "wide8"]
        .into_iter()
        .map(|k| (k, l[format!("{k}_ms")].as_f64().unwrap()))
        .collect();
    assert!(priced.iter().all(|(_, ms)| *ms > 0.0), "{l}");
    let cheapest = priced.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0;
    assert_eq!(l["kept"], cheapest, "{l}");
    assert_eq!(r["traced_pixels"], 0, "ssr mode traces nothing");
    assert_eq!(
        r["fail_reasons"].as_object().unwrap().len(),
        10,
        "every reason, zeros included"
    );
    assert_eq!(r["fail_reasons"]["forced"], 0);
    for k in ["ssim_vs_rt", "rmse_vs_rt", "rt_frame_ms", "vs_rt_mode"] {
        assert!(
            r.get(k).is_some_and(Value::is_null),
            "{k} is present and null without --reference"
        );
    }
}

/// `--json -` writes the report to stdout (the text goes to stderr).
#[test]
fn reports_go_to_stdout_with_a_dash() {
    let dir = tempfile::tempdir().unwrap();
    let r = speculum(
        &[
            "render",
            "--width",
            "48",
            "--height",
            "32",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--reference",
            "--timings",
            "-",
            "--out",
            "f.png",
        ],
        dir.path(),
    );
    check_header(&r, "render", true);
    check_passes(&r["passes_ms"], &[]);
    check_stat(&r["rt_frame_ms"], "rt_frame_ms");
    assert!(r["ssim_vs_rt"].as_f64().unwrap() > 0.5);
    // The default hybrid frame has glossy reflections: it is also compared with the
    // rt mode's frame of the same settings.
    let m = &r["vs_rt_mode"];
    assert!(
        m["ssim"].as_f64().unwrap() > 0.5 && m["rmse"].as_f64().unwrap() < 0.1,
        "{m}"
    );
    let v = &r["shadows_vs_rays"];
    assert!(v["ssim"].as_f64().unwrap() > 0.5, "{v}");
    assert!(v["visibility_agreement"].as_f64().unwrap() > 0.5, "{v}");
    assert!(v["lit_pixels"].as_u64().unwrap() > 0, "{v}");
}

#[test]
fn bench_reports_follow_the_schema() {
    // `bench frame` is valid once its adaptive stages are priced, by frames whose
    // timings pass their self-check: alone.
    let _alone = common::alone();
    let dir = tempfile::tempdir().unwrap();
    let small = ["--width", "48", "--height", "32"];
    // A fixed exchange rate: the adaptive hybrid marches in every measured frame (with
    // a measured one it may not, and its march scopes may be null).
    // A rasterized G-buffer: the adaptive one may not have priced rays yet.
    std::fs::write(
        dir.path().join("s.json"),
        r#"{"exchange_rate": 0.1, "visibility": "raster"}"#,
    )
    .unwrap();
    let modes = speculum(
        &[
            &["bench", "modes", "--rounds", "2", "--warmup", "0", "--json", "r.json"][..],
            &["--settings", "s.json"],
            &small,
        ]
        .concat(),
        dir.path(),
    );
    check_header(&modes, "bench.modes", true);
    let scene = &modes["scenes"][0];
    for m in scene["modes"].as_array().unwrap() {
        check_stat(&m["frame_ms"], "frame_ms");
        check_stat(&m["frame_over_rt"], "frame_over_rt");
        let not_run: &[&str] = match m["mode"].as_str().unwrap() {
            "raster" => &[
                "ssr.hiz",
                "ssr.classify",
                "ssr.trace",
                "ssr.compact",
                "rt.reflect",
                "reflect.merge",
                "reflect.denoise",
            ],
            "ssr" => &["ssr.compact", "rt.reflect"],
            "rt" => &["ssr.hiz", "ssr.trace"],
            _ => &[],
        };
        check_passes(&m["passes_ms"], not_run);
    }
    std::fs::remove_file(dir.path().join("r.json")).unwrap();

    let shadows = speculum(
        &[
            &["bench", "shadows", "--rounds", "2", "--warmup", "0", "--json", "r.json"][..],
            &["--settings", "s.json"],
            &small,
        ]
        .concat(),
        dir.path(),
    );
    check_header(&shadows, "bench.shadows", true);
    let scene = &shadows["scenes"][0];
    assert_eq!(scene["mode"], "hybrid");
    for s in scene["shadows"].as_array().unwrap() {
        check_stat(&s["frame_ms"], "frame_ms");
        check_stat(&s["frame_over_rays"], "frame_over_rays");
        for k in ["ssim", "rmse", "visibility_agreement", "visibility_rmse"] {
            assert!(s["vs_rays"][k].is_number(), "{k} in {s}");
        }
        let not_run: &[&str] = match s["shadows"].as_str().unwrap() {
            "map" => &["shadow.classify", "shadow.compact", "shadow.trace", RAYS_VISIBILITY],
            "rays" => &["shadow.map", RAYS_VISIBILITY],
            _ => &[RAYS_VISIBILITY],
        };
        assert_eq!(s["trace_over_rays"].is_null(), s["shadows"] == "map");
        check_scopes(&s["passes_ms"], not_run);
    }
    std::fs::remove_file(dir.path().join("r.json")).unwrap();

    // Frames large enough for lavapipe's timestamps to pass their self-check: an
    // adaptive stage is priced only by checked frames, and at 320x180 7 of 10 frames
    // of a G-buffer by rays leave more time between their scopes than the check allows
    // (docs/experiments.md).
    let frame = speculum(
        &[
            &["bench", "frame", "--rounds", "2", "--warmup", "0", "--json", "r.json"][..],
            &["--settings", "s.json", "--width", "640", "--height", "360"],
        ]
        .concat(),
        dir.path(),
    );
    check_header(&frame, "bench.frame", true);
    let scene = &frame["scenes"][0];
    let variants = scene["variants"].as_array().unwrap();
    assert_eq!(variants.len(), 12, "every visibility with every shadow source");
    for v in variants {
        check_stat(&v["frame_ms"], "frame_ms");
        check_stat(&v["frame_over_raster"], "frame_over_raster");
        assert!(v["ssim_vs_raster"].is_number(), "{v}");
        let (vis, sh) = (v["visibility"].as_str().unwrap(), v["shadows"].as_str().unwrap());
        // An adaptive stage reports its ways, and its rows are the way it took.
        let way = |stage: &str, setting: &str| match setting {
            "adaptive" => {
                let w = &v[stage];
                assert_eq!(w["ways"].as_array().unwrap().len(), 2, "{v}");
                assert!(
                    w["ways"].as_array().unwrap().iter().all(|w| w["ms"].is_number()),
                    "priced: {v}"
                );
                w["way"].as_str().unwrap().to_string()
            }
            fixed => {
                assert!(v[stage].is_null(), "{v}");
                fixed.to_string()
            }
        };
        let (vis_way, sh_way) = (way("visibility_ways", vis), way("shadow_ways", sh));
        let adaptive = vis == "adaptive" || sh == "adaptive";
        assert_eq!(v["over_cheapest_fixed"].is_number(), adaptive, "{v}");
        assert_eq!(v["chose_cheapest"].is_boolean(), adaptive, "{v}");
        assert_eq!(v["recheck_ms"].is_number(), adaptive, "{v}");
        // The rows of the way taken ran; the other way's did unless the stage is
        // adaptive (it may have changed its choice, or rechecked, within the rounds).
        let mut not_run = vec![if vis_way == "rays" { "gbuffer" } else { RAYS_VISIBILITY }];
        not_run.extend(match sh_way.as_str() {
            "map" => &TRACED_SHADOW_SCOPES[..],
            "rays" => &["shadow.map"],
            _ => &[],
        });
        let either: Vec<&str> = not_run
            .iter()
            .copied()
            .filter(|&s| match s {
                "gbuffer" | RAYS_VISIBILITY => vis == "adaptive",
                _ => sh == "adaptive",
            })
            .collect();
        check_scopes_or(&v["passes_ms"], &not_run, &either);
    }
    std::fs::remove_file(dir.path().join("r.json")).unwrap();

    let reflect = speculum(
        &[
            &["bench", "reflect", "--frames", "1", "--json", "r.json"][..],
            &["--settings", "s.json"],
            &small,
        ]
        .concat(),
        dir.path(),
    );
    check_header(&reflect, "bench.reflect", true);
    check_stat(&reflect["rt_frame_ms"], "rt_frame_ms");
    for p in reflect["points"].as_array().unwrap() {
        check_stat(&p["frame_over_rt"], "frame_over_rt");
        check_passes(&p["passes_ms"], &[]);
    }
    std::fs::remove_file(dir.path().join("r.json")).unwrap();

    let lbvh = speculum(
        &[
            "bench",
            "lbvh",
            "--tris",
            "2000",
            "--repeats",
            "2",
            "--rays",
            "1024",
            "--check-rays",
            "100",
            "--json",
            "r.json",
        ],
        dir.path(),
    );
    check_header(&lbvh, "bench.lbvh", true);
    let suite = speculum(
        &[
            "bench", "suite", "--quick", "--frames", "1", "--warmup", "0", "--json", "r.json",
        ],
        dir.path(),
    );
    check_header(&suite, "bench.suite", true);
    for c in suite["cases"].as_array().unwrap() {
        for (pass, s) in c["passes_ms"].as_object().unwrap() {
            check_stat(s, pass);
        }
    }
    assert!(lbvh["settings"].is_null() && lbvh["options"]["repeats"] == 2);
    let case = &lbvh["cases"][0];
    for k in ["build_ms", "staged_build_ms", "refit_ms"] {
        check_stat(&case[k], k);
    }
    check_stat(&case["coherent"]["trace_ms"], "trace_ms");
    // One case per builder and layout (all by default), each with its stages in build
    // order.
    let cases = lbvh["cases"].as_array().unwrap();
    let want: Vec<(BvhKind, StaticLayout)> = BvhKind::ALL
        .into_iter()
        .flat_map(|k| StaticLayout::ALL.map(|l| (k, l)))
        .collect();
    assert_eq!(cases.len(), want.len());
    for (case, (kind, layout)) in cases.iter().zip(want) {
        assert_eq!(
            (&case["builder"], &case["layout"]),
            (&kind.name().into(), &layout.name().into())
        );
        let stages: Vec<&String> = case["stages_ms"].as_object().unwrap().keys().collect();
        assert_eq!(stages, kind.stages().map(String::from).iter().collect::<Vec<_>>());
    }
}

#[test]
fn compare_report_follows_the_schema_and_thresholds_fail() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    let b = dir.path().join("b.png");
    image::RgbaImage::from_fn(32, 32, |x, y| image::Rgba([(x * 8) as u8, (y * 8) as u8, 90, 255]))
        .save(&a)
        .unwrap();
    image::RgbaImage::from_fn(32, 32, |x, y| image::Rgba([(x * 8) as u8, (y * 7) as u8, 90, 255]))
        .save(&b)
        .unwrap();
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let r = speculum(&["compare", a, b, "--json", "r.json", "--diff", "d.png"], dir.path());
    check_header(&r, "compare", false);
    assert!(r["min_ssim"].is_null() && r["passed"] == true && r["rmse"].as_f64().unwrap() > 0.0);
    let diff = image::open(dir.path().join("d.png")).unwrap().to_rgba8();
    assert_eq!(diff.dimensions(), (32, 32));
    assert_eq!(diff.get_pixel(0, 0).0, [0, 0, 0, 255], "equal pixels are black");
    assert_ne!(diff.get_pixel(0, 31).0, [0, 0, 0, 255], "differing pixels are not");
    // A threshold that is not met fails with one line naming it.
    for (flag, v) in [("--min-ssim", "0.9999"), ("--max-rmse", "0.0001")] {
        let out = common::speculum(["compare", a, b, flag, v]).run();
        let stderr = out.stderr;
        assert_eq!(out.code, 1, "{stderr}");
        assert!(stderr.contains(flag) && stderr.lines().count() == 1, "{stderr}");
    }
}

/// FLIP: identical images score 0; NVIDIA's reference pair scores what FLIP's own
/// command-line tool prints for it (0.133285, within 1e-4); more noise scores more.
#[test]
fn flip_matches_the_reference_implementation() {
    let load = |name: &str| {
        speculum::metrics::load_rgba(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/data/flip")
                .join(name),
        )
        .unwrap()
    };
    let (r, t) = (load("tree-ref.png"), load("tree-test.png"));
    let (w, h) = r.dimensions();
    let same = speculum::metrics::flip_mean(r.as_raw(), r.as_raw(), w, h).unwrap();
    assert_eq!(same, 0.0);
    let pair = speculum::metrics::flip_mean(t.as_raw(), r.as_raw(), w, h).unwrap();
    assert!((pair - 0.133285).abs() < 1e-4, "FLIP of the reference pair: {pair}");
    let noisy = |amount: u8| -> Vec<u8> {
        let mut rng = 7u32;
        r.as_raw()
            .iter()
            .map(|&v| {
                rng = rng.wrapping_mul(1664525).wrapping_add(1013904223);
                v.saturating_add(((rng >> 24) as u8) % amount.max(1))
            })
            .collect()
    };
    let (a, b) = (
        speculum::metrics::flip_mean(&noisy(8), r.as_raw(), w, h).unwrap(),
        speculum::metrics::flip_mean(&noisy(64), r.as_raw(), w, h).unwrap(),
    );
    assert!(0.0 < a && a < b && b < 1.0, "noise 8: {a}, noise 64: {b}");
    assert!(speculum::metrics::flip_mean(&[0; 8], &[0; 4], 1, 1).is_err());
}
