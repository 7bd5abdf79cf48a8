//! `speculum tune` and `speculum plot` through the real binary: a 2x2 sweep on `room`
//! writes its CSV, JSON, plot and best settings; the Pareto flags in the CSV are what a
//! brute-force check of its own numbers gives; `--resume` measures only new points;
//! bad sweep files get one clear error.

use crate::common;

use std::path::Path;

fn speculum(args: &[&str]) -> common::Output {
    common::speculum(args).run()
}

fn ok(out: &common::Output) -> String {
    assert!(out.ok(), "failed:\n{}", out.stderr);
    out.stderr.clone() + &out.stdout
}

const SWEEP: &str = "scene = \"room\"\nwidth = 64\nheight = 40\nrounds = 2\nwarmup = 0\n\
                     [axes]\nssr_max_steps = [4, 64]\nmax_bounces = [1, 3]\n";

fn rows(dir: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(dir.join("points.csv"))
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn a_small_sweep_writes_its_outputs_and_resumes() {
    let _alone = common::alone();
    let dir = tempfile::tempdir().unwrap();
    let sweep = dir.path().join("sweep.toml");
    std::fs::write(&sweep, SWEEP).unwrap();
    let out = dir.path().join("out");
    let (s, o) = (sweep.to_str().unwrap(), out.to_str().unwrap());
    let text = ok(&speculum(&["tune", s, "--out", o, "--min-ssim", "0.5", "--quiet"]));
    for f in ["points.csv", "points.json", "pareto.png", "best.json"] {
        assert!(out.join(f).is_file(), "{f} missing: {text}");
    }
    let table = rows(&out);
    let head = &table[0];
    let col = |name: &str| {
        head.iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    assert_eq!(table.len(), 1 + 5, "4 points and the default");
    let keys: Vec<&str> = table[1..].iter().map(|r| r[col("key")].as_str()).collect();
    assert!(
        keys.contains(&"default") && keys.contains(&"max_bounces=1;ssr_max_steps=4"),
        "{keys:?}"
    );
    // The Pareto flags, recomputed by brute force from the CSV's own numbers.
    let num = |r: &Vec<String>, c: &str| r[col(c)].parse::<f64>().unwrap();
    for (flag, err) in [("pareto_ssim", "ssim"), ("pareto_flip", "flip")] {
        let pts: Vec<(f64, f64)> = table[1..]
            .iter()
            .map(|r| {
                let e = num(r, err);
                (num(r, "frame_over_rt"), if err == "ssim" { 1.0 - e } else { e })
            })
            .collect();
        for (i, r) in table[1..].iter().enumerate() {
            let (x, y) = pts[i];
            let dominated = pts.iter().any(|&(a, b)| a <= x && b <= y && (a < x || b < y));
            assert_eq!(r[col(flag)] == "true", !dominated, "{flag} of {}", r[col("key")]);
        }
    }
    for r in &table[1..] {
        let (ssim, flip, ratio) = (num(r, "ssim"), num(r, "flip"), num(r, "frame_over_rt"));
        assert!(
            ssim > 0.5 && ssim <= 1.0 && (0.0..1.0).contains(&flip) && ratio > 0.0,
            "{r:?}"
        );
    }
    // One bounce reflects less of the mirrors-in-mirrors than three: further from rt.
    let flip_of = |key: &str| {
        table[1..]
            .iter()
            .find(|r| r[col("key")] == key)
            .map(|r| num(r, "flip"))
            .unwrap()
    };
    assert!(flip_of("max_bounces=1;ssr_max_steps=64") > flip_of("max_bounces=3;ssr_max_steps=64"));
    let best = speculum::Settings::from_json(&std::fs::read_to_string(out.join("best.json")).unwrap()).unwrap();
    assert_eq!(
        (best.width, best.height),
        (64, 40),
        "best.json is a settings file render reads"
    );

    // Resume with one more value on an axis: only the two new points are measured,
    // the old rows stay as they were (their timings included).
    let text = ok(&speculum(&[
        "tune",
        s,
        "--out",
        o,
        "--resume",
        "--axis",
        "max_bounces=1,2,3",
    ]));
    assert!(text.contains("2 to measure"), "{text}");
    let again = rows(&out);
    assert_eq!(again.len(), 1 + 7);
    let stats = col("frame_ms")..col("ssim");
    for old in &table[1..] {
        let new = again.iter().find(|r| r[col("key")] == old[col("key")]).unwrap();
        assert_eq!(
            new[stats.clone()],
            old[stats.clone()],
            "{} was measured again",
            old[col("key")]
        );
    }

    // plot re-draws the figure from the CSV alone.
    let png = dir.path().join("again.png");
    ok(&speculum(&[
        "plot",
        out.join("points.csv").to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]));
    let img = speculum::metrics::load_rgba(&png).unwrap();
    assert_eq!(img.dimensions(), (1400, 600));
}

#[test]
fn bad_sweeps_and_csvs_are_refused_before_any_gpu_work() {
    let _alone = common::alone();
    let dir = tempfile::tempdir().unwrap();
    for (text, says) in [
        ("[axes]\nmax_bounce = [1, 2]\n", "unknown setting 'max_bounce'"),
        ("[axes]\nmax_bounces = [1, \"two\"]\n", "max_bounces"),
        ("[axes]\nssr_stride = { min = 8, max = 2, steps = 4 }\n", "empty range"),
        ("[axes]\nmax_bounces = [99]\n", "max_bounces 99"),
        ("width = 5\n[axes]\nmax_bounces = [1]\n", "SSIM needs"),
        ("[axes\n", "sweep file"),
    ] {
        let f = dir.path().join("bad.toml");
        std::fs::write(&f, text).unwrap();
        let out = speculum(&[
            "tune",
            f.to_str().unwrap(),
            "--out",
            dir.path().join("o").to_str().unwrap(),
        ]);
        let err = out.stderr;
        assert_eq!(out.code, 1, "{text:?}: {err}");
        assert!(err.contains(says), "{text:?}: {err}");
        assert_eq!(err.lines().filter(|l| l.starts_with("error:")).count(), 1, "{err}");
    }
    let csv = dir.path().join("bad.csv");
    std::fs::write(&csv, "scene,key,nonsense\nroom,a,1\n").unwrap();
    let out = speculum(&[
        "plot",
        csv.to_str().unwrap(),
        "--out",
        dir.path().join("p.png").to_str().unwrap(),
    ]);
    assert_eq!(out.code, 1);
    assert!(out.stderr.contains("points CSV"));
}

/// A sweep from the command line alone (no file): `--scene`, `--width`, `--height` and
/// the view flags as in every other command; bad ones refused before any GPU work.
#[test]
fn a_sweep_needs_no_file() {
    let _alone = common::alone();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let args = [
        "--scene",
        "mirrors",
        "--width",
        "64",
        "--height",
        "40",
        "--axis",
        "max_bounces=1,2",
    ];
    let text = ok(&speculum(
        &[&["tune"][..], &args, &["--out", o, "--confirm", "0"]].concat(),
    ));
    assert!(text.contains("64x40"), "{text}");
    let rows = rows(&out);
    assert_eq!(rows.len(), 4, "header + default + 2 points: {rows:?}");
    assert!(rows[1..].iter().all(|r| r[0] == "mirrors"), "{rows:?}");
    for (flag, value, says) in [
        ("--width", "0", "--width"),
        ("--fov", "0", "--fov 0"),
        ("--scene", "nosuch", "unknown scene 'nosuch'"),
    ] {
        let out = speculum(&["tune", "--axis", "max_bounces=1", "--out", o, flag, value]);
        let lines: Vec<&str> = out.stderr.lines().collect();
        assert_eq!(out.code, 1, "{flag} {value}: {}", out.stderr);
        assert!(
            lines.len() == 1 && lines[0].contains(says),
            "{flag} {value}: {}",
            out.stderr
        );
    }
}

/// The shadow source is an axis like any setting (by name: map, rays, hybrid); an
/// unknown source is refused naming the field.
#[test]
fn shadows_are_a_tuner_axis() {
    let _alone = common::alone();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let small = ["--scene", "room", "--width", "64", "--height", "40"];
    ok(&speculum(
        &[
            &["tune"][..],
            &small,
            &["--axis", "shadows=map,hybrid", "--out", o, "--confirm", "0"],
        ]
        .concat(),
    ));
    let rows = rows(&out);
    let column = rows[0].iter().position(|c| c == "shadows").expect("a shadows column");
    let values: Vec<&str> = rows[1..].iter().map(|r| r[column].as_str()).collect();
    assert_eq!(values, ["map", "map", "hybrid"], "default, then the points: {rows:?}");
    let bad = speculum(&[&["tune"][..], &small, &["--axis", "shadows=soft", "--out", o]].concat());
    assert_eq!(bad.code, 1, "{}", bad.stderr);
    assert!(bad.stderr.contains("shadows"), "{}", bad.stderr);
}
