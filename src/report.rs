//! The one schema every JSON report follows (`render --timings`, `bench modes`,
//! `bench reflect`, `bench lbvh`, `compare --json`): an object whose first keys are the
//! `Header` (schema version, report kind, program version and git commit, the device and
//! its driver, the effective settings, validation messages), then the report's own keys.
//! Every key is always present: a count that is zero is 0, a value that does not apply
//! is `null`. Repeated measurements are a `Stat` (median with p10/p90 and the sample
//! count), never a bare median. `passes_ms` lists every timer scope of the frame in frame
//! order, `null` for a pass the mode does not run.

use crate::renderer::{FRAME, SCOPES};
use crate::settings::Settings;
use crate::vk::{Context, Timings};
use ash::vk;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

/// Version of the report schema; bumped when a key changes meaning or goes away.
pub const SCHEMA: u32 = 1;

/// The commit this binary was built from (`unknown` outside a git checkout).
pub const GIT_COMMIT: &str = env!("SPECULUM_GIT_COMMIT");

/// Median and spread of repeated measurements (milliseconds, or a ratio).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stat {
    pub median: f64,
    /// 10th and 90th percentiles (linear between order statistics, as numpy's default).
    pub p10: f64,
    pub p90: f64,
    pub samples: u32,
}

/// The `q` quantile (0..=1) of sorted values, linear between order statistics.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

impl Stat {
    /// The statistics of `values`; `None` for no values.
    pub fn of(values: &[f64]) -> Option<Stat> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(|a, b| a.total_cmp(b));
        Some(Stat {
            median: quantile(&v, 0.5),
            p10: quantile(&v, 0.1),
            p90: quantile(&v, 0.9),
            samples: v.len() as u32,
        })
    }
}

/// The device a report was measured on.
#[derive(Clone, Debug, Serialize)]
pub struct DeviceReport {
    pub name: String,
    /// "discrete GPU", "CPU", ...
    pub kind: &'static str,
    /// The driver's name and version text (`VkPhysicalDeviceDriverProperties`).
    pub driver_name: String,
    pub driver_info: String,
    /// The driver's raw version number (vendor encoding).
    pub driver_version: u32,
    /// "major.minor.patch" of the Vulkan version the device supports.
    pub vulkan_version: String,
}

impl DeviceReport {
    pub fn of(ctx: &Context) -> Self {
        let v = ctx.api_version;
        Self {
            name: ctx.device_name.clone(),
            kind: crate::vk::device::kind_name(ctx.device_type),
            driver_name: ctx.driver_name.clone(),
            driver_info: ctx.driver_info.clone(),
            driver_version: ctx.driver_version,
            vulkan_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
        }
    }
}

/// The keys every report starts with.
#[derive(Clone, Debug, Serialize)]
pub struct Header {
    pub schema: u32,
    /// "render", "bench.modes", "bench.reflect", "bench.lbvh" or "compare".
    pub kind: &'static str,
    pub speculum_version: &'static str,
    pub git_commit: &'static str,
    /// `null` for reports that use no GPU (`compare`).
    pub device: Option<DeviceReport>,
    /// The effective settings (file, then flags); `null` where no renderer ran.
    pub settings: Option<Settings>,
    /// Validation warnings and errors; `null` when validation was off.
    pub validation_messages: Option<u32>,
}

impl Header {
    pub fn new(kind: &'static str, ctx: Option<&Context>, settings: Option<&Settings>) -> Self {
        Self {
            schema: SCHEMA,
            kind,
            speculum_version: env!("CARGO_PKG_VERSION"),
            git_commit: GIT_COMMIT,
            device: ctx.map(DeviceReport::of),
            settings: settings.cloned(),
            validation_messages: ctx.and_then(|c| c.validation_enabled().then(|| c.validation_messages())),
        }
    }

    /// The validation count as it is now (reports are written after their GPU work).
    pub fn refresh_validation(&mut self, ctx: &Context) {
        self.validation_messages = ctx.validation_enabled().then(|| ctx.validation_messages());
    }
}

/// Every timer scope of the frame but `frame` itself, in frame order, each with its
/// statistics or `None` (`null`) when the frame did not run it.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTimes(pub Vec<(&'static str, Option<Stat>)>);

impl PassTimes {
    /// The frame's scopes (all of `SCOPES` but `FRAME`).
    pub fn of(timings: &Timings) -> Self {
        let passes: Vec<&'static str> = SCOPES.iter().copied().filter(|&s| s != FRAME).collect();
        Self::of_scopes(timings, &passes)
    }

    /// The scopes `names`, in that order.
    pub fn of_scopes(timings: &Timings, names: &[&'static str]) -> Self {
        Self(
            names
                .iter()
                .map(|&s| (s, timings.samples(s).and_then(Stat::of)))
                .collect(),
        )
    }

    /// The statistics of pass `name`, if it ran.
    pub fn get(&self, name: &str) -> Option<Stat> {
        self.0.iter().find(|(n, _)| *n == name).and_then(|(_, s)| *s)
    }

    /// The median of pass `name` in milliseconds, NaN when it did not run (for tables).
    pub fn median(&self, name: &str) -> f64 {
        self.get(name).map_or(f64::NAN, |s| s.median)
    }
}

impl Serialize for PassTimes {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, stat) in &self.0 {
            map.serialize_entry(name, stat)?;
        }
        map.end()
    }
}

/// One frame's milliseconds per scope of the frame but `frame` and `sim.rigid` (which
/// its line has apart), in frame order, `null` where not run.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTimes(pub Vec<(&'static str, Option<f64>)>);

impl FrameTimes {
    pub fn of(times: &[(&'static str, f64)]) -> Self {
        let skip = [FRAME, crate::renderer::SIM_RIGID];
        Self(
            SCOPES
                .iter()
                .filter(|s| !skip.contains(s))
                .map(|&s| (s, times.iter().find(|(n, _)| *n == s).map(|t| t.1)))
                .collect(),
        )
    }
}

impl Serialize for FrameTimes {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, ms) in &self.0 {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

/// One line of `render --sequence`'s `frames.jsonl`: a measured frame.
#[derive(Clone, Debug, Serialize)]
pub struct FrameLine {
    /// From 0, the first measured frame.
    pub frame: u32,
    /// CPU wall-clock ms of the frame's rigid-body step; `null` for a static scene.
    pub sim_ms: Option<f64>,
    pub passes_ms: FrameTimes,
    /// GPU ms of the whole frame.
    pub frame_ms: f64,
    pub dynamic_triangles: u32,
    /// Traced / reflective pixels.
    pub rt_pixel_fraction: f64,
    /// With `--reference`: against the same frame in `rt` mode; `null` without.
    pub ssim: Option<f64>,
    pub rmse: Option<f64>,
    /// Why the frame's timings failed their self-check (`vk::timing`); `null` when
    /// they passed.
    pub timing_problem: Option<String>,
    /// How its G-buffer was made (`raster` or `rays`) and where its shadows came from
    /// (`map`, `rays` or `hybrid`): with an adaptive stage, the way the frame took.
    pub visibility: crate::settings::Visibility,
    pub shadows: crate::settings::Shadows,
    /// The adaptive hybrid's path: the one the frame ran and the one its image is
    /// (another only on a probe frame while idle); `null` for every other mode.
    pub path: Option<PathLine>,
}

/// A frame's adaptive hybrid path, by name (`march`, `skip_march`, `trace_all`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PathLine {
    pub runs: &'static str,
    pub shows: &'static str,
}

impl FrameLine {
    pub fn of(r: &FrameRecord<'_>) -> Self {
        let get = |name: &str| r.times.iter().find(|(n, _)| *n == name).map(|t| t.1);
        Self {
            frame: r.index,
            sim_ms: get(crate::renderer::SIM_RIGID),
            passes_ms: FrameTimes::of(r.times),
            frame_ms: get(FRAME).unwrap_or(f64::NAN),
            dynamic_triangles: r.dynamic_triangles,
            rt_pixel_fraction: r.rt_pixel_fraction,
            ssim: r.vs_rt.map(|c| c.ssim),
            rmse: r.vs_rt.map(|c| c.rmse),
            timing_problem: r.timing_problem.map(str::to_string),
            visibility: r.plan.visibility,
            shadows: r.plan.shadows,
            path: r.plan.hybrid.adaptive().then_some(PathLine {
                runs: r.plan.path.name(),
                shows: r.plan.shows.name(),
            }),
        }
    }
}

/// One measured frame, as `render`'s per-frame hook sees it (for `--sequence`).
pub struct FrameRecord<'a> {
    /// Measured frame number, from 0.
    pub index: u32,
    /// The frame's time per scope (ms; `sim.rigid` is CPU wall clock).
    pub times: &'a [(&'static str, f64)],
    /// Why this frame's timings failed their self-check; `None` when they passed.
    pub timing_problem: Option<&'a str>,
    pub rgba: &'a [u8],
    pub dynamic_triangles: u32,
    pub rt_pixel_fraction: f64,
    /// With a reference: SSIM and RMSE against the same frame in `rt` mode.
    pub vs_rt: Option<crate::metrics::Comparison>,
    /// What the frame's plan decided (its adaptive stages' ways).
    pub plan: crate::renderer::plan::FramePlan,
}

/// A report as pretty JSON with a trailing newline.
pub fn to_json<T: Serialize>(report: &T) -> String {
    serde_json::to_string_pretty(report).expect("reports serialize") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stat_quantiles_match_numpy_linear() {
        // numpy.percentile([1, 2, 3, 4, 10], [10, 50, 90]) = [1.4, 3.0, 7.6]
        let s = Stat::of(&[4.0, 1.0, 10.0, 3.0, 2.0]).unwrap();
        assert_eq!((s.median, s.samples), (3.0, 5));
        assert!((s.p10 - 1.4).abs() < 1e-12 && (s.p90 - 7.6).abs() < 1e-12, "{s:?}");
        assert_eq!(
            Stat::of(&[4.0, 1.0, 3.0, 2.0]).unwrap().median,
            2.5,
            "even count: the middle two's mean"
        );
        let one = Stat::of(&[2.5]).unwrap();
        assert_eq!((one.p10, one.median, one.p90), (2.5, 2.5, 2.5));
        assert!(Stat::of(&[]).is_none());
    }

    #[test]
    fn pass_times_list_every_scope_in_frame_order_with_nulls() {
        let mut t = Timings::default();
        t.add_frame(&[("gbuffer", 2.0), (FRAME, 5.0)]);
        let p = PassTimes::of(&t);
        let json = serde_json::to_string(&p).unwrap();
        assert!(
            json.starts_with(
                "{\"uniforms\":null,\"sim.rigid\":null,\"sim.transform\":null,\"sim.cloth\":null,\
                 \"sim.skin\":null,\"lbvh.bounds\":null,\"lbvh.morton\":null,\"lbvh.sort\":null,\
                 \"lbvh.fit\":null,\"lbvh.refit\":null,\"as.cloth\":null,\"as.tlas\":null,\
                 \"shadow.map\":null,\"gbuffer\":{\"median\":2.0"
            ),
            "{json}"
        );
        assert!(
            json.contains("\"ssr.trace\":null") && !json.contains("\"frame\""),
            "{json}"
        );
        assert_eq!(p.0.len(), SCOPES.len() - 1);
    }
}
