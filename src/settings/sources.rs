//! Where the frame's visible surfaces and shadows come from (the `visibility` and
//! `shadows` settings): each fixed source, and `adaptive`, which the frame's plan
//! resolves to one of them per frame (`renderer::stages`).

use crate::shader_defines::{SHADOWS_HYBRID, SHADOWS_MAP, SHADOWS_RAYS};
use serde::{Deserialize, Serialize};

/// How the frame finds what each pixel sees: the G-buffer rasterized, traced by one
/// primary ray a pixel, or whichever of the two the frame's own timestamps find cheaper
/// (`about` says what each is).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Visibility {
    Raster,
    Rays,
    Adaptive,
}

impl Visibility {
    pub const ALL: [Visibility; 3] = [Visibility::Raster, Visibility::Rays, Visibility::Adaptive];
    /// The two ways a frame is made, in the order the adaptive frame prices them.
    pub const FIXED: [Visibility; 2] = [Visibility::Raster, Visibility::Rays];

    pub fn name(self) -> &'static str {
        match self {
            Visibility::Raster => "raster",
            Visibility::Rays => "rays",
            Visibility::Adaptive => "adaptive",
        }
    }

    /// What the visibility is, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            Visibility::Raster => "The G-buffer rasterized (gbuffer): vertex and fragment work",
            Visibility::Rays => {
                "The G-buffer by one primary ray a pixel through the tracer (gbuffer.trace): compute work, \
                 texture detail from ray cones"
            }
            Visibility::Adaptive => {
                "Raster or rays, whichever the frame's own timestamps price cheaper on this device \
                 (each priced over its first frames, rechecked one frame in 64)"
            }
        }
    }
}

/// Where the sun's shadows come from, on the visible surface and at every ray-traced
/// reflection hit alike (`about` says what each is). `adaptive` is not a source: each
/// frame takes one of `ADAPTIVE` (its plan's `shadows`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shadows {
    Map,
    Rays,
    Hybrid,
    Adaptive,
}

impl Shadows {
    pub const ALL: [Shadows; 4] = [Shadows::Map, Shadows::Rays, Shadows::Hybrid, Shadows::Adaptive];
    /// The sources `adaptive` prices, in the order it tries them: the two of equal
    /// quality (`hybrid` traces wherever the map is unsure, and there is exactly `rays`).
    pub const ADAPTIVE: [Shadows; 2] = [Shadows::Hybrid, Shadows::Rays];

    /// Whether the shadow map is rendered (every source but `rays` reads it; an
    /// adaptive frame's is its way's).
    pub fn uses_map(self) -> bool {
        self != Shadows::Rays
    }

    /// Whether shadow rays are traced (`shadow.classify`, `shadow.compact` and
    /// `shadow.trace` run).
    pub fn traces(self) -> bool {
        self != Shadows::Map
    }

    pub fn name(self) -> &'static str {
        match self {
            Shadows::Map => "map",
            Shadows::Rays => "rays",
            Shadows::Hybrid => "hybrid",
            Shadows::Adaptive => "adaptive",
        }
    }

    /// What the shadows are, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            Shadows::Map => "The shadow map, PCF-filtered: cheap, limited by its resolution and bias",
            Shadows::Rays => "A shadow ray toward the sun from every lit pixel (the reference)",
            Shadows::Hybrid => {
                "The shadow map where every PCF texel agrees and none is near the compare; a shadow ray elsewhere"
            }
            Shadows::Adaptive => {
                "Hybrid or rays (the same shadows where hybrid traces), whichever the frame's own timestamps \
                 price cheaper on this device (each priced over its first frames, rechecked one frame in 64)"
            }
        }
    }

    /// The value the kernels read (`SHADOWS_*` in shader_defines): a frame's own
    /// source, never `Adaptive` (the frame's plan resolves it).
    pub fn gpu(self) -> u32 {
        match self {
            Shadows::Map => SHADOWS_MAP,
            Shadows::Rays => SHADOWS_RAYS,
            Shadows::Hybrid => SHADOWS_HYBRID,
            Shadows::Adaptive => panic!("an adaptive frame's shadows are resolved by its plan"),
        }
    }
}
