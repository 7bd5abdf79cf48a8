//! Sweep files: which scenes, at which size, with which fixed settings, over which
//! axes (settings fields with a list of values or a range), searched as a grid or at
//! seeded random points. Everything is checked when the file is read: an unknown
//! key or field, a wrong type, an empty range, a value the settings refuse.
//!
//! ```toml
//! scenes = ["room"]          # built-in names, scene files or models
//! width = 480                # render size (default: the settings' 960x540)
//! height = 270
//! rounds = 5                 # measured rounds per point (a static scene)
//! warmup = 1                 # unmeasured rounds per point
//! frames = [20, 30]          # a dynamic scene: measure frames 20..30 of its animation
//! search = "grid"            # or "random", with `points` and `seed`
//!
//! [settings]                 # fixed for every point (any settings field)
//! max_bounces = 2
//!
//! [axes]                     # one settings field per axis
//! ssr_max_steps = [8, 16, 32, 64]
//! ssr_stride = { min = 2, max = 16, steps = 5 }            # linear
//! ssr_thickness = { min = 0.01, max = 0.1, steps = 4, log = true }
//! ```

use crate::error::{Error, Result};
use crate::settings::Settings;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Search {
    #[default]
    Grid,
    Random,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum Axis {
    List(Vec<toml::Value>),
    Range {
        min: f64,
        max: f64,
        steps: u32,
        #[serde(default)]
        log: bool,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    scenes: Vec<String>,
    scene: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    rounds: Option<u32>,
    warmup: Option<u32>,
    frames: Option<[u32; 2]>,
    #[serde(default)]
    search: Search,
    points: Option<u32>,
    seed: Option<u64>,
    #[serde(default)]
    settings: toml::Table,
    #[serde(default)]
    axes: BTreeMap<String, Axis>,
}

/// A checked sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub scenes: Vec<String>,
    /// Every point's settings before its axis values: the defaults, the file's
    /// `[settings]`, its size.
    pub base: Settings,
    pub rounds: u32,
    pub warmup: u32,
    /// Frames first..last (exclusive) of a dynamic scene's animation.
    pub frames: [u32; 2],
    pub search: Search,
    pub points: u32,
    pub seed: u64,
    /// Axis name → its values as the text `Settings::with_field` takes, in order.
    pub axes: Vec<(String, Vec<String>)>,
}

/// One point of a sweep: a value per axis and the settings they make.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub values: Vec<(String, String)>,
    pub settings: Settings,
}

impl Point {
    /// The point's identity in CSV files (`--resume`): `name=value` per axis.
    pub fn key(&self) -> String {
        self.values
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(";")
    }
}

fn value_text(name: &str, v: &toml::Value) -> Result<String> {
    Ok(match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => f.to_string(),
        toml::Value::Boolean(b) => b.to_string(),
        other => {
            return Err(Error::Settings(format!(
                "axis {name}: a value must be a number, a boolean or a name, not {}",
                other.type_str()
            )))
        }
    })
}

/// Whether settings field `name` holds whole numbers (its default serializes as one).
fn is_integer(name: &str) -> bool {
    serde_json::to_value(Settings::default())
        .ok()
        .and_then(|v| v.get(name).map(|f| f.is_u64()))
        .unwrap_or(false)
}

/// Most points one sweep measures (and most values one range axis makes).
pub const MAX_POINTS: usize = 100_000;

/// The values of a range axis, as text: `steps` values from `min` to `max` (log-spaced
/// with `log`), rounded and deduplicated for a whole-number field.
fn range_values(name: &str, min: f64, max: f64, steps: u32, log: bool) -> Result<Vec<String>> {
    let bad = |why: String| Error::Settings(format!("axis {name}: {why}"));
    if !(min.is_finite() && max.is_finite()) || min > max {
        return Err(bad(format!("empty range {min}..{max}")));
    }
    // Bounded before any value is made: a sweep holds at most `MAX_POINTS` points.
    if steps as usize > MAX_POINTS {
        return Err(bad(format!(
            "{steps} steps, more than the {MAX_POINTS} points a sweep may hold"
        )));
    }
    if steps == 0 {
        return Err(bad("a range needs at least 1 step".into()));
    }
    if log && min <= 0.0 {
        return Err(bad("a log range must start above 0".into()));
    }
    let mut out: Vec<String> = Vec::new();
    // Deduplicated through a set: `Vec::contains` made 100,000 steps take 20 s.
    let mut seen = std::collections::HashSet::new();
    for i in 0..steps {
        let t = if steps == 1 { 0.0 } else { i as f64 / (steps - 1) as f64 };
        let v = if log {
            (min.ln() + t * (max.ln() - min.ln())).exp()
        } else {
            min + t * (max - min)
        };
        let text = if is_integer(name) {
            (v.round() as i64).to_string()
        } else {
            // Short and exact enough to read back: 6 significant digits.
            format!("{}", (v * 1e6).round() / 1e6)
        };
        if seen.insert(text.clone()) {
            out.push(text);
        }
    }
    Ok(out)
}

impl Sweep {
    /// Reads a sweep file's text (`what` names it in errors), plus `extra_axes` from
    /// the command line (`name=v1,v2,...`, replacing a file axis of that name).
    pub fn parse(text: &str, what: &str, extra_axes: &[String]) -> Result<Self> {
        let f: File = toml::from_str(text).map_err(|e| {
            Error::Settings(format!(
                "sweep file {what}: {}",
                crate::scene::file::toml_detail(text, &e)
            ))
        })?;
        let mut scenes = f.scenes;
        if let Some(s) = f.scene {
            scenes.insert(0, s);
        }
        if scenes.is_empty() {
            scenes.push("room".into());
        }
        let mut base = Settings::default();
        for (name, v) in &f.settings {
            base = base
                .with_field(name, &value_text(name, v)?)
                .map_err(|e| Error::Settings(format!("[settings] {name}: {e}")))?;
        }
        if let Some(w) = f.width {
            base = base.with_field("width", &w.to_string())?;
        }
        if let Some(h) = f.height {
            base = base.with_field("height", &h.to_string())?;
        }
        let mut axes: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (name, axis) in &f.axes {
            let values = match axis {
                Axis::List(list) => list.iter().map(|v| value_text(name, v)).collect::<Result<Vec<_>>>()?,
                Axis::Range { min, max, steps, log } => range_values(name, *min, *max, *steps, *log)?,
            };
            axes.insert(name.clone(), values);
        }
        for a in extra_axes {
            let (name, list) = a
                .split_once('=')
                .ok_or_else(|| Error::Settings(format!("--axis {a}: give name=v1,v2,...")))?;
            let values: Vec<String> = list
                .split(',')
                .map(|v| v.trim().to_string())
                .filter(|v| !v.is_empty())
                .collect();
            axes.insert(name.trim().to_string(), values);
        }
        for (name, values) in &axes {
            if values.is_empty() {
                return Err(Error::Settings(format!("axis {name} has no values")));
            }
            for v in values {
                base.with_field(name, v)
                    .map_err(|e| Error::Settings(format!("axis {name}: {e}")))?;
            }
        }
        let rounds = f.rounds.unwrap_or(3);
        if rounds == 0 || rounds > 1000 {
            return Err(Error::Settings(format!("rounds {rounds} is outside 1..=1000")));
        }
        let frames = f.frames.unwrap_or([10, 20]);
        if frames[0] >= frames[1] || frames[1] > 100_000 {
            return Err(Error::Settings(format!(
                "frames [{}, {}] must be a range first < last <= 100000",
                frames[0], frames[1]
            )));
        }
        let points = match (f.search, f.points) {
            (Search::Random, None) => return Err(Error::Settings("search = \"random\" needs points = N".into())),
            (_, Some(0)) => return Err(Error::Settings("points must be at least 1".into())),
            (_, p) => p.unwrap_or(0),
        };
        let sweep = Sweep {
            scenes,
            base,
            rounds,
            warmup: f.warmup.unwrap_or(1),
            frames,
            search: f.search,
            points,
            seed: f.seed.unwrap_or(1),
            axes: axes.into_iter().collect(),
        };
        if sweep.axes.is_empty() {
            return Err(Error::Settings("the sweep has no axes (add [axes] or --axis)".into()));
        }
        Ok(sweep)
    }

    /// The points to measure, in order: the grid's (last axis fastest), or `points`
    /// distinct random picks of it (seeded), each checked.
    pub fn points(&self) -> Result<Vec<Point>> {
        let sizes: Vec<usize> = self.axes.iter().map(|(_, v)| v.len()).collect();
        // Saturating: a grid of many large axes must not overflow before it is refused.
        let total: usize = sizes.iter().fold(1usize, |t, &n| t.saturating_mul(n));
        if self.search == Search::Grid && total > MAX_POINTS {
            return Err(Error::Settings(format!(
                "a grid of {total} points: at most {MAX_POINTS} (a random search picks fewer)"
            )));
        }
        let pick = |mut i: usize| -> Vec<usize> {
            let mut idx = vec![0; sizes.len()];
            for a in (0..sizes.len()).rev() {
                idx[a] = i % sizes[a];
                i /= sizes[a];
            }
            idx
        };
        let chosen: Vec<usize> = match self.search {
            Search::Grid => (0..total).collect(),
            Search::Random => {
                use rand::seq::index::sample;
                use rand::SeedableRng;
                let mut rng = rand::rngs::StdRng::seed_from_u64(self.seed);
                let n = (self.points as usize).min(total);
                let mut picks = sample(&mut rng, total, n).into_vec();
                picks.sort_unstable();
                picks
            }
        };
        if chosen.len() > MAX_POINTS {
            return Err(Error::Settings(format!(
                "{} points: at most {MAX_POINTS}",
                chosen.len()
            )));
        }
        chosen
            .into_iter()
            .map(|i| {
                let idx = pick(i);
                let mut s = self.base.clone();
                let mut values = Vec::new();
                for ((name, vals), &k) in self.axes.iter().zip(&idx) {
                    s = s.with_field(name, &vals[k])?;
                    values.push((name.clone(), vals[k].clone()));
                }
                Ok(Point { values, settings: s })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_of_lists_and_ranges() {
        let text = r#"
scene = "room"
width = 64
height = 40
[settings]
max_bounces = 2
[axes]
ssr_max_steps = [8, 16]
ssr_stride = { min = 2, max = 16, steps = 3 }
"#;
        let s = Sweep::parse(text, "t", &[]).unwrap();
        assert_eq!((s.base.width, s.base.height, s.base.max_bounces), (64, 40, 2));
        let points = s.points().unwrap();
        assert_eq!(points.len(), 6);
        assert_eq!(points[0].key(), "ssr_max_steps=8;ssr_stride=2");
        assert_eq!(points[5].key(), "ssr_max_steps=16;ssr_stride=16");
        assert_eq!(points[1].settings.ssr_stride, 9.0);
        assert_eq!(points[3].settings.ssr_max_steps, 16);
        // An integer range rounds and drops repeats; a log range spaces by ratio.
        assert_eq!(
            range_values("ssr_max_steps", 8.0, 10.0, 5, false).unwrap(),
            ["8", "9", "10"]
        );
        assert_eq!(
            range_values("ssr_thickness", 0.01, 1.0, 3, true).unwrap(),
            ["0.01", "0.1", "1"]
        );
        // --axis replaces a file axis.
        let s = Sweep::parse(text, "t", &["ssr_max_steps=4,5,6".into()]).unwrap();
        assert_eq!(s.points().unwrap().len(), 9);
    }

    #[test]
    fn random_points_are_seeded_and_distinct() {
        let text = "search = \"random\"\npoints = 5\nseed = 7\n[axes]\nssr_max_steps = [1, 2, 3, 4]\nmax_bounces = [1, 2, 3]\n";
        let a = Sweep::parse(text, "t", &[]).unwrap().points().unwrap();
        let b = Sweep::parse(text, "t", &[]).unwrap().points().unwrap();
        assert_eq!(a, b);
        assert_eq!(a.len(), 5);
        let keys: std::collections::HashSet<String> = a.iter().map(Point::key).collect();
        assert_eq!(keys.len(), 5);
    }

    #[test]
    fn bad_sweeps_name_the_problem() {
        for (text, says) in [
            ("[axes]\nbounces = [1]\n", "unknown setting 'bounces'"),
            ("[axes]\nmax_bounces = [\"many\"]\n", "max_bounces"),
            ("[axes]\nmax_bounces = [0]\n", "max_bounces 0"),
            ("[axes]\nssr_stride = { min = 5, max = 2, steps = 3 }\n", "empty range"),
            ("[axes]\nssr_stride = []\n", "no values"),
            (
                "[axes]\nssr_stride = { min = 1, max = 2, steps = 0 }\n",
                "at least 1 step",
            ),
            ("[settings]\nwidht = 3\n[axes]\nmax_bounces = [1]\n", "widht"),
            ("sceen = \"room\"\n[axes]\nmax_bounces = [1]\n", "sceen"),
            ("width = 3\n", "no axes"),
            ("search = \"random\"\n[axes]\nmax_bounces = [1]\n", "points"),
            ("[axes]\nmax_bounces = [[1]]\n", "array"),
            ("rounds = 0\n[axes]\nmax_bounces = [1]\n", "rounds"),
        ] {
            let e = Sweep::parse(text, "t.toml", &[]).map(|_| ()).unwrap_err().to_string();
            assert!(e.contains(says), "{text:?}: {e}");
        }
        let e = Sweep::parse("[axes]\nmax_bounces=[1]\n", "t", &["max_bounces".into()]).unwrap_err();
        assert!(e.to_string().contains("name=v1"), "{e}");
    }
}
