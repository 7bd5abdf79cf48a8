//! `speculum compare A.png B.png`: SSIM and RMSE of two images, thresholds, a heat map.

use super::{check_outputs, Text};
use anyhow::Result;
use clap::Args;
use serde::Serialize;
use speculum::metrics;
use speculum::output::Kind;
use speculum::report::Header;
use std::path::PathBuf;

#[derive(Args, Clone, Debug)]
pub struct CompareArgs {
    pub a: PathBuf,
    pub b: PathBuf,
    /// Fail (exit 1) when SSIM is below this.
    #[arg(long)]
    pub min_ssim: Option<f64>,
    /// Fail (exit 1) when RMSE is above this.
    #[arg(long)]
    pub max_rmse: Option<f64>,
    /// Write a heat map of the per-pixel error as a PNG (black: equal; white: an RMS
    /// difference of 0.25 or more).
    #[arg(long)]
    pub diff: Option<PathBuf>,
    /// Write the report as JSON to this file (`-`: stdout).
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The `compare` report.
#[derive(Serialize)]
struct CompareReport {
    #[serde(flatten)]
    header: Header,
    a: PathBuf,
    b: PathBuf,
    resolution: [u32; 2],
    /// SSIM on luma (Gaussian 11x11, sigma 1.5) and RMSE over RGB in [0, 1].
    ssim: f64,
    rmse: f64,
    /// The thresholds given (`null`: none) and whether both were met.
    min_ssim: Option<f64>,
    max_rmse: Option<f64>,
    passed: bool,
}

pub fn run(args: CompareArgs) -> Result<()> {
    for (flag, v) in [("--min-ssim", args.min_ssim), ("--max-rmse", args.max_rmse)] {
        if v.is_some_and(|v| !v.is_finite()) {
            anyhow::bail!("{flag} must be a finite number");
        }
    }
    check_outputs(
        &[
            ("--diff", args.diff.as_deref(), Kind::Png),
            ("--json", args.json.as_deref(), Kind::Json),
        ],
        &[("image A", Some(&args.a)), ("image B", Some(&args.b))],
    )?;
    let (ia, ib) = (metrics::load_rgba(&args.a)?, metrics::load_rgba(&args.b)?);
    metrics::check_same_size(&args.a, &ia, &args.b, &ib)?;
    let c = metrics::compare_rgba8(ia.as_raw(), ib.as_raw(), ia.width(), ia.height())?;
    let ssim_ok = args.min_ssim.is_none_or(|m| c.ssim >= m);
    let rmse_ok = args.max_rmse.is_none_or(|m| c.rmse <= m);
    let text = Text::new(&[args.json.as_deref()], false);
    text.line(format_args!(
        "SSIM {:.6} (luma, Gaussian 11x11, sigma 1.5)  RMSE {:.6} (RGB in [0, 1])",
        c.ssim, c.rmse
    ));
    if let Some(path) = &args.diff {
        let heat = metrics::error_heatmap(ia.as_raw(), ib.as_raw());
        speculum::output::save_png(path, &heat, ia.width(), ia.height())?;
        text.line(format_args!("wrote {}", path.display()));
    }
    if let Some(path) = &args.json {
        let report = CompareReport {
            header: Header::new("compare", None, None),
            a: args.a.clone(),
            b: args.b.clone(),
            resolution: [ia.width(), ia.height()],
            ssim: c.ssim,
            rmse: c.rmse,
            min_ssim: args.min_ssim,
            max_rmse: args.max_rmse,
            passed: ssim_ok && rmse_ok,
        };
        super::write_report(path, &report, &text)?;
    }
    match (ssim_ok, rmse_ok) {
        (true, true) => Ok(()),
        (false, _) => anyhow::bail!(
            "SSIM {:.6} is below --min-ssim {}",
            c.ssim,
            args.min_ssim.unwrap_or(0.0)
        ),
        (_, false) => anyhow::bail!(
            "RMSE {:.6} is above --max-rmse {}",
            c.rmse,
            args.max_rmse.unwrap_or(0.0)
        ),
    }
}
