//! `speculum bench suite`: the fixed, versioned suite and its baseline comparison.

use super::Common;
use crate::cli::{check_count, check_outputs, progress, Text};
use anyhow::Result;
use clap::Args;
use speculum::output::Kind;
use speculum::report::Header;
use std::path::PathBuf;

#[derive(Args, Clone, Debug)]
pub struct SuiteArgs {
    /// The CI-sized subset: room and drop at 480x270, LBVH 10K and 100K.
    #[arg(long)]
    pub quick: bool,
    /// Measured frames (builds) per case.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Uncounted warm-up frames (builds) per case, exactly (a dynamic scene is reset
    /// after them) [default: until the clocks settle, as `render`]
    #[arg(long)]
    pub warmup: Option<u32>,
    /// A suite report to compare with, case by case and pass by pass.
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Compare this saved suite report with --baseline instead of running the suite.
    #[arg(long, requires = "baseline")]
    pub compare: Option<PathBuf>,
    /// The smallest relative change counted (the noise band is at least this).
    #[arg(long, default_value_t = 0.10)]
    pub threshold: f64,
    /// Exit 1 when the comparison finds a regression.
    #[arg(long, requires = "baseline")]
    pub fail_on_regression: bool,
    /// Also write the tables as Markdown to this file (`-`: stdout).
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    #[command(flatten)]
    pub common: Common,
}

pub(super) fn suite(args: SuiteArgs) -> Result<()> {
    use speculum::bench::suite::{self, SuiteReport};
    let c = &args.common;
    check_count("--frames", args.frames, 1)?;
    if !(args.threshold.is_finite() && (0.0..10.0).contains(&args.threshold)) {
        anyhow::bail!(speculum::Error::Input(format!(
            "--threshold {} is outside 0..10",
            args.threshold
        )));
    }
    check_outputs(
        &[
            ("--json", c.json.as_deref(), Kind::Json),
            ("--markdown", args.markdown.as_deref(), Kind::Json),
        ],
        &[
            ("--baseline", args.baseline.as_deref()),
            ("--compare", args.compare.as_deref()),
        ],
    )?;
    let read = |p: &PathBuf, what: &'static str| -> Result<suite::Baseline> {
        let text = speculum::error::read_text(p, what, speculum::error::bounds::TABLE)?;
        Ok(suite::read_baseline(&text, &p.display().to_string())?)
    };
    let baseline = args.baseline.as_ref().map(|p| read(p, "baseline")).transpose()?;
    if let (Some(new), Some(old)) = (&args.compare, &baseline) {
        // Two saved reports: no GPU work.
        let cmp = suite::compare(&read(new, "suite report")?, old, args.threshold);
        let md = suite::markdown_comparison(&cmp);
        let text = Text::new(&[args.markdown.as_deref()], c.quiet);
        text.line(format_args!("{md}"));
        if let Some(path) = &args.markdown {
            // `-` is standard output (write_atomic's rule).
            speculum::output::write_atomic(path, md.as_bytes())?;
        }
        return regressions(&cmp, args.fail_on_regression);
    }
    let cases = suite::cases(args.quick);
    let warmup = speculum::steady::WarmUp::from_arg(args.warmup);
    let text = Text::new(&[c.json.as_deref(), args.markdown.as_deref()], c.quiet);
    let ctx = c.gpu.context()?;
    let bar = progress(
        cases.len() as u64 * (warmup.min_frames() + args.frames) as u64,
        "suite",
        c.quiet,
    );
    let mut results = Vec::new();
    for case in &cases {
        results.push(suite::run_case(&ctx, case, warmup, args.frames, &mut || bar.inc(1))?);
    }
    bar.finish_and_clear();
    let mut report = SuiteReport {
        header: Header::new("bench.suite", Some(&ctx), None),
        suite_version: suite::SUITE_VERSION,
        quick: args.quick,
        warmup: warmup.rule(),
        frames: args.frames,
        cases: results,
    };
    report.header.refresh_validation(&ctx);
    let comparison = baseline
        .as_ref()
        .map(|b| suite::compare(&suite::as_baseline(&report.cases), b, args.threshold));
    if let Some(b) = &baseline {
        let missing: Vec<&str> = report
            .cases
            .iter()
            .filter(|c| !b.contains_key(&c.id))
            .map(|c| c.id.as_str())
            .collect();
        if !missing.is_empty() {
            text.line(format_args!("not in the baseline (new cases): {}", missing.join(", ")));
        }
    }
    let md = suite::markdown(&report, comparison.as_deref());
    text.line(format_args!("{md}"));
    if let Some(path) = &c.json {
        crate::cli::write_report(path, &report, &text)?;
    }
    if let Some(path) = &args.markdown {
        // `-` is standard output (write_atomic's rule).
        speculum::output::write_atomic(path, md.as_bytes())?;
    }
    crate::cli::check_validation(&ctx)?;
    match &comparison {
        Some(cmp) => regressions(cmp, args.fail_on_regression),
        None => Ok(()),
    }
}

/// Says which passes regressed; an error with `fail`.
fn regressions(cmp: &[speculum::bench::suite::Comparison], fail: bool) -> Result<()> {
    use speculum::bench::suite::Verdict;
    let list: Vec<String> = cmp
        .iter()
        .filter(|c| c.verdict == Verdict::Regression)
        .map(|c| format!("{} {} ({:.2}x)", c.case, c.pass, c.ratio))
        .collect();
    if !list.is_empty() {
        let line = format!("{} regression(s): {}", list.len(), list.join(", "));
        if fail {
            anyhow::bail!(line);
        }
        eprintln!("warning: {line}");
    }
    Ok(())
}
