//! The one settings struct shared by the CLI, the tests and (later) the demo, tuner
//! and benchmarks. Every field says what it trades.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Largest render side Speculum accepts on any device: 8192 keeps every target under
/// 512 MiB, within a single allocation on lavapipe (2 GiB) and common GPUs.
pub const MAX_SIDE: u32 = 8192;

/// What the renderer computes for reflections (`about` says what each mode is).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    Raster,
    Ssr,
    Hybrid,
    Rt,
    Provenance,
}

impl Mode {
    pub const ALL: [Mode; 5] = [Mode::Raster, Mode::Ssr, Mode::Hybrid, Mode::Rt, Mode::Provenance];

    /// Whether the frame has reflections at all (every mode but `raster`).
    pub fn reflects(self) -> bool {
        self != Mode::Raster
    }

    /// Whether SSR marches (`ssr.trace` runs): `rt` classifies only, to fail every pixel.
    pub fn marches(self) -> bool {
        matches!(self, Mode::Ssr | Mode::Hybrid | Mode::Provenance)
    }

    /// Whether failed pixels are ray traced (`ssr.compact` and `rt.reflect` run).
    pub fn traces(self) -> bool {
        matches!(self, Mode::Hybrid | Mode::Rt | Mode::Provenance)
    }

    /// Whether SSR and ray-traced reflections meet in one image (the seam blur runs).
    pub fn has_seams(self) -> bool {
        matches!(self, Mode::Hybrid | Mode::Provenance)
    }

    pub fn name(self) -> &'static str {
        match self {
            Mode::Raster => "raster",
            Mode::Ssr => "ssr",
            Mode::Hybrid => "hybrid",
            Mode::Rt => "rt",
            Mode::Provenance => "provenance",
        }
    }

    /// What the mode renders, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            Mode::Raster => "No reflections: direct lighting only",
            Mode::Ssr => "Screen-space reflections only; where SSR fails there is no reflection",
            Mode::Hybrid => "The method: SSR first, the failed pixels ray traced, merged, seams blurred",
            Mode::Rt => "Every reflective pixel ray traced (the quality reference), same bounces",
            Mode::Provenance => {
                "Hybrid, with each pixel painted by its reflection's source: pink = ray traced, blue = SSR, \
                 grey = no reflective surface"
            }
        }
    }
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Mode::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            Error::Settings(format!(
                "unknown mode '{s}' (modes: raster, ssr, hybrid, rt, provenance)"
            ))
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Render width in pixels. Every screen-space pass scales with width × height.
    pub width: u32,
    /// Render height in pixels.
    pub height: u32,
    /// Shadow-map edge in texels: sharper shadow edges vs memory and `shadow.map` time.
    pub shadow_map_size: u32,
    /// PCF radius in shadow-map texels: softer, less aliased shadow edges vs
    /// (2r+2)^2 texel fetches per pixel in `light.direct`.
    pub pcf_radius: u32,
    /// Depth bias of the shadow compare, in light clip-space depth (fraction of the
    /// light's depth range): removes shadow acne vs detaches shadows from casters.
    pub shadow_bias: f32,
    /// Slope-scaled raster depth bias of `shadow.map`: less acne on surfaces at grazing
    /// light angles vs more peter-panning.
    pub shadow_slope_bias: f32,
    /// Exposure multiplier before tonemapping (no time cost).
    pub exposure: f32,
    /// Strength of the sky's hemispherical ambient light (no time cost).
    pub ambient: f32,
    /// Reflection mode.
    pub mode: Mode,
    /// Reflectivity above which a pixel gets a reflection: lower reflects more surfaces
    /// at more SSR and ray-tracing work.
    pub reflective_min: f32,
    /// Rays per reflection path in `rt.trace` (1 = a single reflection): more shows
    /// mirrors within mirrors, each bounce costs another traversal for paths still on a
    /// reflector.
    pub max_bounces: u32,
    /// SSR step budget per ray: more finds farther hits, at up to that many depth reads.
    pub ssr_max_steps: u32,
    /// SSR step length in pixels: longer reaches farther for the same budget but can
    /// step over objects thinner than a step (a hit is refined to the pixel by binary
    /// search inside its step).
    pub ssr_stride: f32,
    /// Depth a surface is assumed to have, as a fraction of its distance along the view
    /// axis (so the same at any scene scale): thicker finds hits behind thin
    /// silhouettes but makes false hits behind objects.
    pub ssr_thickness: f32,
    /// Longest SSR ray, in multiples of the reflecting point's distance along the view
    /// axis (scale-free): longer finds farther hits at more steps.
    pub ssr_max_distance: f32,
    /// Fraction of the screen's smaller side over which SSR confidence fades at the
    /// edges: larger hides the edge seam but sends more pixels to the ray tracer.
    pub ssr_edge_fade: f32,
    /// SSR hits below this confidence fail (go to the ray tracer): higher is cleaner
    /// and slower.
    pub ssr_min_confidence: f32,
    /// SSR hits on surfaces whose own mirror reflection, seen along the ray, weighs
    /// more than this (reflectivity x Fresnel, the largest channel) fail and go to the
    /// ray tracer (the screen holds no reflection of a reflection). Hits on weaker
    /// reflectors (a dielectric seen head-on reflects 4%) are kept without their own
    /// reflection: a lower value is closer to the reference, a higher one ray traces
    /// fewer pixels.
    pub ssr_recursion_min: f32,
    /// Seam blur radius in pixels (0: off): smoother SSR/RT transitions vs detail.
    pub blur_radius: u32,
    /// Half-width in pixels of the band around SSR/RT seams that the blur touches.
    pub blur_band: u32,
    /// Shadows at ray-traced hits from shadow rays (exact, one more traversal per hit)
    /// instead of the shadow map (cheap, limited by its resolution).
    pub shadow_rays: bool,
    /// Simulated seconds per rendered frame of a dynamic scene (a fixed step, so frame
    /// k is the same image in every run): smaller is smoother motion and more frames
    /// for the same animation.
    pub sim_dt: f32,
    /// Rebuild the dynamic BVH of a scene whose only dynamic geometry is cloth every
    /// frame instead of refitting it (refit is cheaper; its tree loosens as the cloth
    /// deforms).
    pub cloth_rebuild: bool,
    /// When refitting, still rebuild every this many frames (1: always rebuild).
    pub refit_rebuild_every: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            width: 960,
            height: 540,
            shadow_map_size: 2048,
            pcf_radius: 1,
            shadow_bias: 0.0015,
            shadow_slope_bias: 1.5,
            exposure: 1.0,
            ambient: 0.35,
            mode: Mode::Hybrid,
            reflective_min: 0.02,
            max_bounces: 3,
            ssr_max_steps: 64,
            ssr_stride: 8.0,
            ssr_thickness: 0.03,
            ssr_max_distance: 5.0,
            ssr_edge_fade: 0.05,
            ssr_min_confidence: 0.3,
            ssr_recursion_min: 0.2,
            blur_radius: 3,
            blur_band: 3,
            shadow_rays: false,
            sim_dt: 1.0 / 60.0,
            cloth_rebuild: false,
            refit_rebuild_every: 60,
        }
    }
}

impl Settings {
    /// Settings from a JSON object: any subset of the fields, the rest defaults. An
    /// array or any other JSON value is refused, as is an unknown field (serde names it,
    /// with its line and column).
    pub fn from_json(text: &str) -> Result<Self> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| Error::Settings(format!("not JSON: {e}")))?;
        if !value.is_object() {
            let kind = match value {
                serde_json::Value::Array(_) => "an array",
                serde_json::Value::String(_) => "a string",
                serde_json::Value::Number(_) => "a number",
                serde_json::Value::Bool(_) => "a boolean",
                _ => "null",
            };
            return Err(Error::Settings(format!(
                "settings must be a JSON object {{\"field\": value, ...}}, not {kind}"
            )));
        }
        // Parsed from the text again (not the value) so errors keep their line and column.
        serde_json::from_str(text).map_err(|e| Error::Settings(e.to_string()))
    }

    /// The names of the fields, in declaration order.
    pub fn field_names() -> Vec<String> {
        match serde_json::to_value(Settings::default()) {
            Ok(serde_json::Value::Object(map)) => map.keys().cloned().collect(),
            _ => unreachable!("Settings serialize to an object"),
        }
    }

    /// These settings with field `name` set to `value`, checked: the value is JSON
    /// (`3`, `0.5`, `true`) or, for the mode, its name (`hybrid`). The one path by
    /// which the demo's HUD and scripts change a setting; an unknown field, a value
    /// of the wrong type or one `validate` refuses is an error naming the field.
    pub fn with_field(&self, name: &str, value: &str) -> Result<Settings> {
        let serde_json::Value::Object(mut map) = serde_json::to_value(self).expect("Settings serialize") else {
            unreachable!("Settings serialize to an object")
        };
        if !map.contains_key(name) {
            return Err(Error::Settings(format!(
                "unknown setting '{name}' (settings: {})",
                Self::field_names().join(", ")
            )));
        }
        let parsed =
            serde_json::from_str(value.trim()).unwrap_or_else(|_| serde_json::Value::String(value.trim().into()));
        map.insert(name.into(), parsed);
        let s: Settings = serde_json::from_value(serde_json::Value::Object(map))
            .map_err(|e| Error::Settings(format!("{name} = {value}: {e}")))?;
        s.validate()?;
        Ok(s)
    }

    /// Checks the values that do not depend on the device.
    pub fn validate(&self) -> Result<()> {
        let side = |what: &str, v: u32| -> Result<()> {
            if v == 0 || v > MAX_SIDE {
                return Err(Error::Settings(format!("{what} {v} is outside 1..={MAX_SIDE}")));
            }
            Ok(())
        };
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(Error::Settings(format!(
                "resolution {}x{} is outside 1x1..={MAX_SIDE}x{MAX_SIDE}",
                self.width, self.height
            )));
        }
        side("shadow_map_size", self.shadow_map_size)?;
        if self.pcf_radius > crate::shader_defines::MAX_PCF_RADIUS {
            return Err(Error::Settings(format!(
                "pcf_radius {} is above the maximum {}",
                self.pcf_radius,
                crate::shader_defines::MAX_PCF_RADIUS
            )));
        }
        if self.max_bounces == 0 || self.max_bounces > 16 {
            return Err(Error::Settings(format!(
                "max_bounces {} is outside 1..=16",
                self.max_bounces
            )));
        }
        if self.ssr_max_steps == 0 || self.ssr_max_steps > 4096 {
            return Err(Error::Settings(format!(
                "ssr_max_steps {} is outside 1..=4096",
                self.ssr_max_steps
            )));
        }
        let most = crate::shader_defines::BLUR_MAX_EXTENT;
        if self.blur_radius > 16 || self.blur_band > most {
            return Err(Error::Settings(format!(
                "blur_radius {} / blur_band {} too large (16 / {most})",
                self.blur_radius, self.blur_band
            )));
        }
        // Finite: an infinite stride would be written back as JSON `null`, unreadable.
        if !(self.ssr_stride >= 0.5 && self.ssr_stride <= MAX_SIDE as f32) {
            return Err(Error::Settings(format!(
                "ssr_stride {} must be at least 0.5 and at most {MAX_SIDE} pixels",
                self.ssr_stride
            )));
        }
        for (name, v) in [
            ("reflective_min", self.reflective_min),
            ("ssr_thickness", self.ssr_thickness),
            ("ssr_max_distance", self.ssr_max_distance),
            ("ssr_edge_fade", self.ssr_edge_fade),
            ("ssr_min_confidence", self.ssr_min_confidence),
            ("ssr_recursion_min", self.ssr_recursion_min),
            ("shadow_bias", self.shadow_bias),
            ("shadow_slope_bias", self.shadow_slope_bias),
            ("exposure", self.exposure),
            ("ambient", self.ambient),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(Error::Settings(format!("{name} {v} must be a finite number >= 0")));
            }
        }
        if self.refit_rebuild_every == 0 {
            return Err(Error::Settings("refit_rebuild_every must be at least 1".into()));
        }
        if !(self.sim_dt.is_finite() && self.sim_dt > 0.0 && self.sim_dt <= 1.0) {
            return Err(Error::Settings(format!(
                "sim_dt {} must be a time step in (0, 1] seconds",
                self.sim_dt
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        Settings::default().validate().unwrap();
    }

    #[test]
    fn rejects_out_of_range_values() {
        let bad = [
            Settings {
                width: 0,
                ..Default::default()
            },
            Settings {
                height: MAX_SIDE + 1,
                ..Default::default()
            },
            Settings {
                shadow_map_size: 0,
                ..Default::default()
            },
            Settings {
                pcf_radius: crate::shader_defines::MAX_PCF_RADIUS + 1,
                ..Default::default()
            },
            Settings {
                exposure: f32::NAN,
                ..Default::default()
            },
            Settings {
                shadow_bias: -1.0,
                ..Default::default()
            },
        ];
        for s in bad {
            assert!(s.validate().is_err(), "{s:?}");
        }
    }

    #[test]
    fn settings_json_must_be_an_object() {
        for bad in [
            "[1, 2, 3]",
            "42",
            "\"hybrid\"",
            "null",
            "{\"widht\": 320}",
            "{\"width\": \"wide\"}",
        ] {
            assert!(Settings::from_json(bad).is_err(), "{bad}");
        }
        let e = Settings::from_json("[960, 540]").unwrap_err().to_string();
        assert!(e.contains("JSON object") && e.contains("array"), "{e}");
        let s = Settings::from_json("{\"height\": 100}").unwrap();
        assert_eq!((s.width, s.height), (Settings::default().width, 100));
    }

    #[test]
    fn with_field_sets_one_field_or_names_the_problem() {
        let d = Settings::default();
        let s = d.with_field("max_bounces", "2").unwrap();
        assert_eq!(
            s,
            Settings {
                max_bounces: 2,
                ..d.clone()
            }
        );
        assert_eq!(d.with_field("mode", "rt").unwrap().mode, Mode::Rt);
        assert_eq!(d.with_field("ssr_stride", "2.5").unwrap().ssr_stride, 2.5);
        assert!(d.with_field("ssr_stride", "1e300").is_err(), "infinite as f32");
        assert!(d.with_field("shadow_rays", "true").unwrap().shadow_rays);
        for (name, value, says) in [
            ("bounces", "2", "unknown setting 'bounces'"),
            ("max_bounces", "many", "max_bounces"),
            ("max_bounces", "0", "max_bounces 0"),
            ("mode", "shiny", "mode"),
            ("width", "-3", "width"),
        ] {
            let e = d.with_field(name, value).unwrap_err().to_string();
            assert!(e.contains(says), "{name} = {value}: {e}");
        }
        assert_eq!(Settings::field_names().len(), 24);
    }

    #[test]
    fn json_round_trip_and_unknown_fields() {
        let s: Settings = serde_json::from_str(r#"{"width": 320, "pcf_radius": 2}"#).unwrap();
        assert_eq!((s.width, s.height, s.pcf_radius), (320, Settings::default().height, 2));
        assert!(serde_json::from_str::<Settings>(r#"{"widht": 320}"#).is_err());
    }
}

/// SSR settings (see `Settings` for what each trades).
#[derive(Clone, Copy, Debug)]
pub struct SsrParams {
    pub max_steps: u32,
    pub stride: f32,
    pub thickness: f32,
    pub max_distance: f32,
    pub edge_fade: f32,
    pub min_confidence: f32,
    pub reflective_min: f32,
    /// Hits on surfaces more reflective than this fail (need the ray tracer's bounce).
    pub recursion_min: f32,
}

impl SsrParams {
    /// The SSR fields of the frame's settings.
    pub fn from_settings(st: &Settings) -> Self {
        Self {
            max_steps: st.ssr_max_steps,
            stride: st.ssr_stride,
            thickness: st.ssr_thickness,
            max_distance: st.ssr_max_distance,
            edge_fade: st.ssr_edge_fade,
            min_confidence: st.ssr_min_confidence,
            reflective_min: st.reflective_min,
            recursion_min: st.ssr_recursion_min.max(st.reflective_min),
        }
    }
}
