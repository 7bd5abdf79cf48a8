//! The one settings struct shared by the CLI, the tests and (later) the demo, tuner
//! and benchmarks. Every field says what it trades.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Largest render side Speculum accepts on any device: 8192 keeps every target under
/// 512 MiB, within a single allocation on lavapipe (2 GiB) and common GPUs.
pub const MAX_SIDE: u32 = 8192;

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
        }
    }
}

impl Settings {
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
        for (name, v) in [
            ("shadow_bias", self.shadow_bias),
            ("shadow_slope_bias", self.shadow_slope_bias),
            ("exposure", self.exposure),
            ("ambient", self.ambient),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(Error::Settings(format!("{name} {v} must be a finite number >= 0")));
            }
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
    fn json_round_trip_and_unknown_fields() {
        let s: Settings = serde_json::from_str(r#"{"width": 320, "pcf_radius": 2}"#).unwrap();
        assert_eq!((s.width, s.height, s.pcf_radius), (320, Settings::default().height, 2));
        assert!(serde_json::from_str::<Settings>(r#"{"widht": 320}"#).is_err());
    }
}
