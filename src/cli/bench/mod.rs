//! `speculum bench modes|shadows|frame|reflect|lbvh|dynamic|suite`: GPU timing benchmarks
//! that check what they time.

mod dynamic;
mod lbvh;
mod scenes;
mod suite;

use super::GpuArgs;
use anyhow::Result;
use clap::{Args, Subcommand};
use dynamic::{dynamic, DynamicArgs};
use lbvh::{lbvh, LbvhArgs};
use scenes::{frame, modes, reflect, shadows, ModesArgs, ReflectArgs};
use std::path::PathBuf;
use suite::{suite, SuiteArgs};

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// LBVH build (per stage), refit, SAH quality and traversal throughput.
    Lbvh(LbvhArgs),
    /// Time of the reflection passes as the ray-traced share varies (every point and rt
    /// interleaved in one run).
    Reflect(ReflectArgs),
    /// Every mode timed in the same run, interleaved: per-pass medians, frame time
    /// against rt, SSIM/RMSE against rt, and whether ssr < hybrid < rt.
    Modes(ModesArgs),
    /// The shadow sources (map, hybrid, rays) timed in the same run, interleaved:
    /// per-pass medians, frame and shadow.trace time against rays, the traced share,
    /// and SSIM and sun visibility against the rays frame.
    Shadows(ModesArgs),
    /// Every visibility (raster, rays, adaptive) with every shadow source timed in the
    /// same run, interleaved: per-pass medians, frame time and SSIM against the raster
    /// frame, and the adaptive variants' choices and frame time over the cheapest fixed one.
    Frame(ModesArgs),
    /// A dynamic scene's per-frame costs as its bodies grow: simulation, transform,
    /// dynamic BVH rebuild vs refit, tracing, the frame; refit vs rebuilt traversal.
    Dynamic(DynamicArgs),
    /// The fixed, versioned suite: every built-in scene in ssr/hybrid/rt at 960x540
    /// and 1920x1080 and LBVH builds (10K/100K/1M), per pass; --baseline compares.
    Suite(SuiteArgs),
}

/// What every benchmark shares: reports, quietness, the device.
#[derive(Args, Clone, Debug)]
pub struct Common {
    /// Write the report as JSON to this file (`-`: stdout; the table goes to stderr).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// No progress bar and no table (errors still go to stderr).
    #[arg(long)]
    pub quiet: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

pub fn run(command: BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Lbvh(a) => lbvh(a),
        BenchCommand::Reflect(a) => reflect(a),
        BenchCommand::Modes(a) => modes(a),
        BenchCommand::Shadows(a) => shadows(a),
        BenchCommand::Frame(a) => frame(a),
        BenchCommand::Dynamic(a) => dynamic(a),
        BenchCommand::Suite(a) => suite(a),
    }
}

pub(super) fn valid_or_fail(valid: bool) -> Result<()> {
    if !valid {
        anyhow::bail!("a benchmark check failed (see the report)");
    }
    Ok(())
}
