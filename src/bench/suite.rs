//! `speculum bench suite`: a fixed, versioned set of timing cases, so that two runs
//! (two commits, drivers or GPUs) compare case by case and pass by pass.
//!
//! Suite version 1: every built-in scene (the dynamic ones included, measured over
//! their first frames after a reset) in `ssr`, `hybrid` and `rt` at 960x540 and
//! 1920x1080, and the LBVH build of random soups of 10K, 100K and 1M triangles.
//! `--quick` (CI-sized): `room` and `drop` in the three modes at 480x270, and the
//! 10K and 100K builds. Each case: warm-up frames, then N measured frames, every GPU
//! scope's median, p10, p90 and sample count.
//!
//! A comparison against a baseline report takes new / old per case and pass; the
//! noise band of a pair is half the larger relative p10–p90 spread of the two (at
//! least `threshold`), and a ratio above 1 + band is a regression, below 1 / (1 +
//! band) an improvement (`Faster`); passes under 0.05 ms in both runs are not compared.

use super::lbvh::{timed_build, BUILD, STAGES};
use crate::error::{Error, Result};
use crate::renderer::FRAME;
use crate::report::{Header, Stat};
use crate::settings::{Mode, Settings};
use crate::steady::{RoundsCheck, WarmUp, WarmUpReport};
use crate::tracers::lbvh::{Bvh, LbvhBuilder, MortonBits, UploadedTriangles};
use crate::vk::{remeasure_readout, Context, GpuTimer, TimerReadout, TimingCheck, Timings};
use crate::Renderer;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The suite's version: a report compares only with one of the same version.
pub const SUITE_VERSION: u32 = 1;

/// One case of the suite.
#[derive(Clone, Debug, PartialEq)]
pub enum Case {
    Frame {
        scene: String,
        mode: Mode,
        width: u32,
        height: u32,
    },
    Lbvh {
        triangles: u32,
    },
}

impl Case {
    /// The case's name in reports: `room/hybrid/960x540`, `lbvh/100000`.
    pub fn id(&self) -> String {
        match self {
            Case::Frame {
                scene,
                mode,
                width,
                height,
            } => format!("{scene}/{}/{width}x{height}", mode.name()),
            Case::Lbvh { triangles } => format!("lbvh/{triangles}"),
        }
    }
}

/// The cases of the full suite or of `--quick`.
pub fn cases(quick: bool) -> Vec<Case> {
    let modes = [Mode::Ssr, Mode::Hybrid, Mode::Rt];
    let (scenes, sizes, tris): (Vec<&str>, Vec<(u32, u32)>, Vec<u32>) = if quick {
        (vec!["room", "drop"], vec![(480, 270)], vec![10_000, 100_000])
    } else {
        (
            crate::scene::builtin::NAMES.to_vec(),
            vec![(960, 540), (1920, 1080)],
            vec![10_000, 100_000, 1_000_000],
        )
    };
    let mut out = Vec::new();
    for &(width, height) in &sizes {
        for s in &scenes {
            for mode in modes {
                out.push(Case::Frame {
                    scene: s.to_string(),
                    mode,
                    width,
                    height,
                });
            }
        }
    }
    out.extend(tris.into_iter().map(|triangles| Case::Lbvh { triangles }));
    out
}

/// What one case measured.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    pub id: String,
    /// "frame" or "lbvh".
    pub kind: &'static str,
    /// FNV-1a (64-bit, hex) of the case's settings as JSON (frame cases).
    pub settings_hash: Option<String>,
    pub resolution: Option<[u32; 2]>,
    pub triangles: Option<u32>,
    /// GPU scope → ms, in frame (or build) order; `frame` / `lbvh` is the whole.
    pub passes_ms: BTreeMap<String, Stat>,
    /// The scopes in order (JSON objects keep no order).
    pub order: Vec<String>,
    /// The self-check of every measured frame or build (`vk::timing`).
    pub timing: TimingCheck,
    /// How the case warmed up, and how its measured frames (or builds) held: one beyond
    /// 2x the median is measured again (`steady`).
    pub warmup: WarmUpReport,
    pub rounds_check: RoundsCheck,
}

/// The `bench suite` report.
#[derive(Clone, Debug, Serialize)]
pub struct SuiteReport {
    #[serde(flatten)]
    pub header: Header,
    pub suite_version: u32,
    pub quick: bool,
    /// The warm-up's rule (`frames N`, or `steady`); each case says how its went.
    pub warmup: String,
    pub frames: u32,
    pub cases: Vec<CaseResult>,
}

/// FNV-1a, 64-bit: a hash that is the same in every build and version of Rust.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

fn stats(timings: &Timings, names: &[&str]) -> (BTreeMap<String, Stat>, Vec<String>) {
    let mut map = BTreeMap::new();
    let mut order = Vec::new();
    for n in names {
        if let Some(s) = timings.samples(n).and_then(Stat::of) {
            map.insert(n.to_string(), s);
            order.push(n.to_string());
        }
    }
    (map, order)
}

/// Runs one case: warm-up frames (or builds) until `warmup` is done, then `frames`
/// measured, the straying ones again (`super::measure_rounds`).
pub fn run_case(
    ctx: &Arc<Context>,
    case: &Case,
    warmup: WarmUp,
    frames: u32,
    tick: super::Tick<'_>,
) -> Result<CaseResult> {
    match case {
        Case::Frame {
            scene,
            mode,
            width,
            height,
        } => frame_case(ctx, case, (scene, *mode, [*width, *height]), (warmup, frames), tick),
        Case::Lbvh { triangles } => lbvh_case(ctx, case, *triangles, (warmup, frames), tick),
    }
}

/// `frames` measurements by `measure` (a frame, a build) of which `scope` is the whole,
/// the straying ones again (`super::measure_rounds`): their timings and how they held.
fn measure_series(
    frames: u32,
    scope: &str,
    tick: super::Tick<'_>,
    mut measure: impl FnMut() -> Result<(TimerReadout, u32)>,
) -> Result<(Timings, RoundsCheck)> {
    let (measured, check) = super::measure_rounds(frames, scope, || {
        let m = measure()?;
        tick();
        Ok(vec![m])
    })?;
    let mut timings = Timings::default();
    for (t, discarded) in measured.iter().map(|m| &m[0]) {
        timings.add_measured(t, *discarded);
    }
    Ok((timings, check))
}

/// A frame case: `scene` in `mode` at `size`.
fn frame_case(
    ctx: &Arc<Context>,
    case: &Case,
    (scene, mode, [width, height]): (&str, Mode, [u32; 2]),
    (warmup, frames): (WarmUp, u32),
    tick: super::Tick<'_>,
) -> Result<CaseResult> {
    let scene = crate::scene::load(scene)?;
    let settings = Settings {
        width,
        height,
        mode,
        ..Settings::default()
    };
    let mut r = Renderer::new(ctx, &scene, &settings)?;
    let warmup = crate::headless::warm_up(&mut [&mut r], warmup, tick)?;
    // A dynamic scene's measured frames are always its first ones.
    r.reset_simulation()?;
    let (timings, rounds_check) = measure_series(frames, FRAME, tick, || r.render_frame_measured())?;
    let (passes_ms, order) = stats(&timings, &crate::renderer::SCOPES);
    let json = crate::report::to_json(&settings);
    Ok(CaseResult {
        id: case.id(),
        kind: "frame",
        settings_hash: Some(format!("{:016x}", fnv1a(json.as_bytes()))),
        resolution: Some([width, height]),
        triangles: None,
        passes_ms,
        order,
        timing: timings.check().clone(),
        warmup,
        rounds_check,
    })
}

/// An LBVH case: the build of a random soup of `triangles`.
fn lbvh_case(
    ctx: &Arc<Context>,
    case: &Case,
    triangles: u32,
    (warmup, frames): (WarmUp, u32),
    tick: super::Tick<'_>,
) -> Result<CaseResult> {
    let n = triangles as usize;
    let (v, i) = crate::scene::soup::random_soup(n, 1.0, crate::scene::soup::default_size(n), 42);
    let uploaded = UploadedTriangles::new(ctx, "suite", &v, &i)?;
    let geometry = uploaded.geometry();
    let builder = LbvhBuilder::new(ctx)?;
    let bvh = Bvh::new(ctx, triangles, MortonBits::Bits30)?;
    let mut timer = GpuTimer::new(ctx, 8)?;
    // At least one warm-up build (its first builds its pipelines' caches).
    let mut warming = match warmup {
        WarmUp::Frames(n) => WarmUp::Frames(n.max(1)),
        steady => steady,
    }
    .start();
    while !warming.done() {
        let (times, _) = remeasure_readout(|| timed_build(&mut timer, &builder, geometry, &bvh))?;
        warming.add(times.get(BUILD).unwrap_or(0.0));
        tick();
    }
    let (timings, rounds_check) = measure_series(frames, BUILD, tick, || {
        remeasure_readout(|| timed_build(&mut timer, &builder, geometry, &bvh))
    })?;
    let mut names: Vec<&str> = STAGES.to_vec();
    names.push(BUILD);
    let (passes_ms, order) = stats(&timings, &names);
    Ok(CaseResult {
        id: case.id(),
        kind: "lbvh",
        settings_hash: None,
        resolution: None,
        triangles: Some(triangles),
        passes_ms,
        order,
        timing: timings.check().clone(),
        warmup: warming.report(),
        rounds_check,
    })
}

/// A case's pass medians and spreads as a baseline holds them.
pub type Baseline = BTreeMap<String, BTreeMap<String, Stat>>;

/// Reads a suite report as a baseline: per case id, per pass, its statistics. A file
/// that is not a suite report of this version is refused, naming what is wrong.
pub fn read_baseline(text: &str, what: &str) -> Result<Baseline> {
    let bad = |why: String| Error::Input(format!("baseline {what}: {why}"));
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON ({e})")))?;
    if v["kind"] != "bench.suite" {
        return Err(bad(format!(
            "not a bench suite report (kind {}, not bench.suite)",
            v["kind"]
        )));
    }
    if v["schema"] != crate::report::SCHEMA {
        return Err(bad(format!(
            "report schema {} (this is schema {}): run the baseline again",
            if v["schema"].is_null() {
                "missing".to_string()
            } else {
                v["schema"].to_string()
            },
            crate::report::SCHEMA
        )));
    }
    if v["suite_version"] != SUITE_VERSION {
        return Err(bad(format!(
            "suite version {} (this is version {SUITE_VERSION}): run the baseline again",
            v["suite_version"]
        )));
    }
    let cases = v["cases"].as_array().ok_or_else(|| bad("no cases array".into()))?;
    if cases.is_empty() {
        return Err(bad("no cases: nothing to compare against".into()));
    }
    let mut out = Baseline::new();
    for c in cases {
        let id = c["id"].as_str().ok_or_else(|| bad("a case without an id".into()))?;
        let passes = c["passes_ms"]
            .as_object()
            .ok_or_else(|| bad(format!("case {id}: no passes_ms")))?;
        let mut map = BTreeMap::new();
        for (name, s) in passes {
            let num = |k: &str| {
                s[k].as_f64()
                    .filter(|x| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| bad(format!("case {id} pass {name}: {k} is not a number >= 0")))
            };
            map.insert(
                name.clone(),
                Stat {
                    median: num("median")?,
                    p10: num("p10")?,
                    p90: num("p90")?,
                    samples: s["samples"].as_u64().unwrap_or(0) as u32,
                },
            );
        }
        out.insert(id.to_string(), map);
    }
    Ok(out)
}

/// How a pass compares with its baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Same,
    /// Faster beyond the band.
    Faster,
    /// Slower beyond the band.
    Regression,
}

#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub case: String,
    pub pass: String,
    pub old_ms: f64,
    pub new_ms: f64,
    pub ratio: f64,
    /// The relative band within which a ratio counts as noise.
    pub band: f64,
    pub verdict: Verdict,
}

/// A run's results in the form a baseline is read in.
pub fn as_baseline(cases: &[CaseResult]) -> Baseline {
    cases.iter().map(|c| (c.id.clone(), c.passes_ms.clone())).collect()
}

/// Compares `new` with `old` pass by pass (cases and passes in both, by name; passes
/// below 0.05 ms in both runs are skipped: timer noise).
pub fn compare(new: &Baseline, old: &Baseline, threshold: f64) -> Vec<Comparison> {
    let spread = |s: &Stat| {
        if s.median > 0.0 {
            (s.p90 - s.p10) / s.median
        } else {
            0.0
        }
    };
    let mut out = Vec::new();
    for (id, passes) in new {
        let Some(base) = old.get(id) else { continue };
        for (pass, n) in passes {
            let Some(o) = base.get(pass) else { continue };
            if n.median < 0.05 && o.median < 0.05 {
                continue;
            }
            let ratio = n.median / o.median.max(1e-9);
            let band = (0.5 * spread(n).max(spread(o))).max(threshold);
            let verdict = if ratio > 1.0 + band {
                Verdict::Regression
            } else if ratio < 1.0 / (1.0 + band) {
                Verdict::Faster
            } else {
                Verdict::Same
            };
            out.push(Comparison {
                case: id.clone(),
                pass: pass.clone(),
                old_ms: o.median,
                new_ms: n.median,
                ratio,
                band,
                verdict,
            });
        }
    }
    out
}

/// The report as Markdown: a table of every case's passes, and the comparison's
/// table when there is one.
pub fn markdown(report: &SuiteReport, comparison: Option<&[Comparison]>) -> String {
    let d = report.header.device.as_ref();
    let mut s = format!(
        "Speculum bench suite v{} ({}) on {} ({}), commit {}, {} measured frames after warm-up ({})\n\n",
        report.suite_version,
        if report.quick { "quick" } else { "full" },
        d.map_or("?", |d| d.name.as_str()),
        d.map_or(String::from("?"), |d| format!(
            "{}, Vulkan {}",
            d.driver_info, d.vulkan_version
        )),
        report.header.git_commit,
        report.frames,
        report.warmup
    );
    s += "| case | frame (or build) ms | p10 | p90 | n | passes (median ms) |\n|---|---|---|---|---|---|\n";
    for c in &report.cases {
        let whole = if c.kind == "lbvh" {
            BUILD
        } else {
            crate::renderer::FRAME
        };
        let w = c.passes_ms.get(whole);
        let passes: Vec<String> = c
            .order
            .iter()
            .filter(|p| p.as_str() != whole)
            .map(|p| format!("{p} {:.2}", c.passes_ms[p].median))
            .collect();
        s += &format!(
            "| {} | {:.2} | {:.2} | {:.2} | {} | {} |\n",
            c.id,
            w.map_or(f64::NAN, |w| w.median),
            w.map_or(f64::NAN, |w| w.p10),
            w.map_or(f64::NAN, |w| w.p90),
            w.map_or(0, |w| w.samples),
            passes.join(", ")
        );
    }
    let invalid: Vec<String> = report
        .cases
        .iter()
        .filter_map(|c| c.timing.warning().map(|w| format!("- {}: {w}\n", c.id)))
        .collect();
    let checked: u32 = report.cases.iter().map(|c| c.timing.checked).sum();
    let discarded: u32 = report.cases.iter().map(|c| c.timing.discarded).sum();
    if invalid.is_empty() {
        s += &format!("\nEvery timing self-checked ({checked} readouts agree, {discarded} re-measured).\n");
    } else {
        s += "\n**Timings that failed their self-check** (not to be trusted):\n";
        s += &invalid.concat();
    }
    let unsettled: Vec<String> = report
        .cases
        .iter()
        .filter(|c| !c.warmup.settled || !c.rounds_check.settled())
        .map(|c| format!("- {}: {}\n", c.id, unsettled_note(c)))
        .collect();
    let remeasured: u32 = report.cases.iter().map(|c| c.rounds_check.remeasured).sum();
    if unsettled.is_empty() {
        s += &format!("Clocks settled in every case ({remeasured} straying frames measured again).\n");
    } else {
        s += "\n**Cases whose clocks did not settle** (not to be trusted):\n";
        s += &unsettled.concat();
    }
    if let Some(cmp) = comparison {
        s += "\n";
        s += &markdown_comparison(cmp);
    }
    s
}

/// Why a case's clocks did not settle.
fn unsettled_note(c: &CaseResult) -> String {
    let mut why = Vec::new();
    if !c.warmup.settled {
        why.push(format!("warm-up of {} frames did not settle", c.warmup.frames));
    }
    if !c.rounds_check.settled() {
        why.push(format!("{} frames still strayed", c.rounds_check.still_straying));
    }
    why.join("; ")
}

/// The comparison as a Markdown table.
pub fn markdown_comparison(cmp: &[Comparison]) -> String {
    let mut s = String::from(
        "| case | pass | old ms | new ms | new / old | noise band | verdict |\n|---|---|---|---|---|---|---|\n",
    );
    for c in cmp {
        {
            s += &format!(
                "| {} | {} | {:.3} | {:.3} | {:.3} | ±{:.1}% | {:?} |\n",
                c.case,
                c.pass,
                c.old_ms,
                c.new_ms,
                c.ratio,
                100.0 * c.band,
                c.verdict
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stat(m: f64, spread: f64) -> Stat {
        Stat {
            median: m,
            p10: m * (1.0 - spread / 2.0),
            p90: m * (1.0 + spread / 2.0),
            samples: 10,
        }
    }

    fn case(id: &str, passes: &[(&str, f64)]) -> CaseResult {
        CaseResult {
            id: id.into(),
            kind: "frame",
            settings_hash: None,
            resolution: None,
            triangles: None,
            passes_ms: passes.iter().map(|(n, m)| (n.to_string(), stat(*m, 0.1))).collect(),
            order: passes.iter().map(|(n, _)| n.to_string()).collect(),
            timing: TimingCheck::default(),
            warmup: WarmUp::Frames(1).start().report(),
            rounds_check: Default::default(),
        }
    }

    #[test]
    fn the_suite_is_fixed() {
        let full = cases(false);
        assert_eq!(full.len(), crate::scene::builtin::NAMES.len() * 3 * 2 + 3);
        assert_eq!(full[0].id(), "room/ssr/960x540");
        assert_eq!(full.last().unwrap().id(), "lbvh/1000000");
        let quick = cases(true);
        assert_eq!(quick.len(), 2 * 3 + 2);
        let ids: std::collections::HashSet<String> = full.iter().map(Case::id).collect();
        assert_eq!(ids.len(), full.len(), "ids are unique");
        assert_eq!(fnv1a(b"a"), 0xaf63dc4c8601ec8c, "the FNV-1a test vector");
    }

    #[test]
    fn compare_flags_what_is_slower_beyond_the_noise() {
        let new = vec![case(
            "room/hybrid/480x270",
            &[("gbuffer", 2.0), ("rt.reflect", 10.0), ("frame", 20.0), ("tiny", 0.01)],
        )];
        let old: Baseline = [(
            "room/hybrid/480x270".to_string(),
            [
                ("gbuffer".to_string(), stat(1.0, 0.1)),
                ("rt.reflect".to_string(), stat(10.2, 0.1)),
                ("frame".to_string(), stat(30.0, 0.1)),
                ("tiny".to_string(), stat(0.005, 0.1)),
            ]
            .into_iter()
            .collect(),
        )]
        .into_iter()
        .collect();
        let c = compare(&as_baseline(&new), &old, 0.1);
        let v: Vec<(&str, Verdict)> = c.iter().map(|c| (c.pass.as_str(), c.verdict)).collect();
        assert_eq!(
            v,
            [
                ("frame", Verdict::Faster),
                ("gbuffer", Verdict::Regression),
                ("rt.reflect", Verdict::Same)
            ]
        );
        assert!(compare(&old, &old, 0.0)
            .iter()
            .all(|c| c.verdict == Verdict::Same && c.ratio == 1.0));
        let md = markdown(
            &SuiteReport {
                header: Header::new("bench.suite", None, None),
                suite_version: SUITE_VERSION,
                quick: true,
                warmup: "frames 1".into(),
                frames: 3,
                cases: new,
            },
            Some(&c),
        );
        assert!(
            md.contains("| room/hybrid/480x270 | gbuffer | 1.000 | 2.000 | 2.000 |"),
            "{md}"
        );
    }

    #[test]
    fn bad_baselines_are_named() {
        for (text, says) in [
            ("nonsense", "not JSON"),
            ("{\"kind\": \"render\"}", "not a bench suite report"),
            ("{\"kind\": \"bench.suite\", \"suite_version\": 1}", "schema missing"),
            ("{\"kind\": \"bench.suite\", \"schema\": 99, \"suite_version\": 1}", "schema 99"),
            ("{\"kind\": \"bench.suite\", \"schema\": 1, \"suite_version\": 0}", "suite version 0"),
            ("{\"kind\": \"bench.suite\", \"schema\": 1, \"suite_version\": 1}", "no cases"),
            ("{\"kind\": \"bench.suite\", \"schema\": 1, \"suite_version\": 1, \"cases\": []}", "no cases"),
            (
                "{\"kind\": \"bench.suite\", \"schema\": 1, \"suite_version\": 1, \"cases\": [{\"id\": \"a\", \"passes_ms\": {\"frame\": {\"median\": \"x\"}}}]}",
                "median is not a number",
            ),
        ] {
            let e = read_baseline(text, "b.json").unwrap_err().to_string();
            assert!(e.contains(says) && e.contains("b.json"), "{text}: {e}");
        }
    }
}
