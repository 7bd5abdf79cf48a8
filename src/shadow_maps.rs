//! Per-pixel shadow state of a frame read back from the GPU (the G-buffer, the shadow
//! mask and the visibility): which pixels the sun lights, which got a shadow ray and
//! why, and the share traced. For reports, tests and the shadow provenance image.

use crate::error::Result;
use crate::metrics::compare_rgba8;
use crate::shader_defines::{SHADOW_ALL, SHADOW_EDGE, SHADOW_GRAZING, SHADOW_NEAR, SHADOW_OUTSIDE};
use serde::Serialize;
use std::collections::BTreeMap;

/// The `SHADOW_*` reasons by name, in bit order.
pub const REASONS: [(u32, &str); 5] = [
    (SHADOW_OUTSIDE, "outside"),
    (SHADOW_EDGE, "edge"),
    (SHADOW_NEAR, "near"),
    (SHADOW_GRAZING, "grazing"),
    (SHADOW_ALL, "all"),
];

/// How far a frame's shadows are from the same frame's with `rays` shadows.
#[derive(Clone, Debug, Serialize)]
pub struct ShadowsVsRays {
    /// SSIM and RMSE of the final images.
    pub ssim: f64,
    pub rmse: f64,
    /// Lit pixels whose visibility is the rays' (within 1/256: a PCF-filtered map's
    /// fractions count as different).
    pub visibility_agreement: f64,
    /// RMSE of the visibility over the lit pixels (0..1).
    pub visibility_rmse: f64,
    /// Lit pixels compared.
    pub lit_pixels: u64,
}

impl ShadowsVsRays {
    /// Compares a frame (`rgba`, `maps`) with the rays frame, the visibility over the
    /// rays frame's lit pixels.
    pub fn of(
        (rgba, maps): (&[u8], &ShadowMaps),
        (rays_rgba, rays): (&[u8], &ShadowMaps),
        [width, height]: [u32; 2],
    ) -> Result<Self> {
        let c = compare_rgba8(rgba, rays_rgba, width, height)?;
        let lit: Vec<usize> = (0..rays.lit.len()).filter(|&i| rays.lit[i]).collect();
        let (mut agree, mut sq) = (0u64, 0f64);
        for &i in &lit {
            let d = (maps.visibility[i] - rays.visibility[i]) as f64;
            agree += (d.abs() < 1.0 / 256.0) as u64;
            sq += d * d;
        }
        let n = lit.len().max(1) as f64;
        Ok(Self {
            ssim: c.ssim,
            rmse: c.rmse,
            visibility_agreement: agree as f64 / n,
            visibility_rmse: (sq / n).sqrt(),
            lit_pixels: lit.len() as u64,
        })
    }
}

/// Per-pixel shadow state of a frame, row-major.
#[derive(Clone, Debug)]
pub struct ShadowMaps {
    /// The pixel shows a surface that faces the sun (n.l > 0): a lit pixel, whose
    /// visibility a shadow can change.
    pub lit: Vec<bool>,
    /// `SHADOW_*` bits written by `shadow.classify` (0: the map answered, or not lit);
    /// all 0 under `map` shadows.
    pub mask: Vec<u32>,
    /// The sun's visibility `light.direct` shaded with (under `map` shadows, the map's
    /// PCF, which it writes back).
    pub visibility: Vec<f32>,
}

/// What `ShadowMaps` counts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowStats {
    pub lit_pixels: u64,
    /// Lit pixels that got a shadow ray.
    pub traced_pixels: u64,
    /// Traced pixels by reason, every reason present (a pixel counts once per bit).
    pub reasons: BTreeMap<&'static str, u64>,
}

impl ShadowStats {
    /// traced / lit pixels: the share of the sun's visibility that rays answered.
    pub fn ray_fraction(&self) -> f64 {
        self.traced_pixels as f64 / self.lit_pixels.max(1) as f64
    }
}

/// `--shadow-sources` colours: a lit pixel the shadow map answered is grey, light where
/// the sun reaches it and dark where not (PCF fractions in between); one a shadow ray
/// answered is pink where the sun reaches it, dark magenta where not; sky and surfaces
/// facing away from the sun are black.
pub const SOURCE_COLOURS: [(&str, [u8; 3]); 5] = [
    ("map, lit", [200, 200, 200]),
    ("map, shadowed", [60, 60, 60]),
    ("ray, lit", [240, 110, 180]),
    ("ray, shadowed", [110, 20, 70]),
    ("not lit (sky, facing away)", [0, 0, 0]),
];

impl ShadowMaps {
    /// Each pixel coloured by where its shadow came from (`SOURCE_COLOURS`), RGBA8.
    pub fn sources_rgba(&self) -> Vec<u8> {
        let [map_lit, map_dark, ray_lit, ray_dark, none] = SOURCE_COLOURS.map(|c| c.1);
        let mix = |a: [u8; 3], b: [u8; 3], t: f32| {
            let t = t.clamp(0.0, 1.0);
            [0, 1, 2].map(|c| (a[c] as f32 + (b[c] as f32 - a[c] as f32) * t).round() as u8)
        };
        (0..self.lit.len())
            .flat_map(|i| {
                let v = self.visibility[i];
                let rgb = match (self.lit[i], self.mask[i] != 0) {
                    (false, _) => none,
                    (true, false) => mix(map_dark, map_lit, v),
                    (true, true) => mix(ray_dark, ray_lit, v),
                };
                [rgb[0], rgb[1], rgb[2], 255]
            })
            .collect()
    }

    pub fn stats(&self) -> ShadowStats {
        let mut s = ShadowStats {
            reasons: REASONS.iter().map(|&(_, name)| (name, 0)).collect(),
            ..Default::default()
        };
        for (&lit, &m) in self.lit.iter().zip(&self.mask) {
            s.lit_pixels += lit as u64;
            if lit && m != 0 {
                s.traced_pixels += 1;
                for &(bit, name) in &REASONS {
                    if m & bit != 0 {
                        *s.reasons.get_mut(name).expect("every reason present") += 1;
                    }
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_count_lit_and_traced_pixels_by_reason() {
        let maps = ShadowMaps {
            lit: vec![true, true, false, true],
            mask: vec![0, SHADOW_EDGE | SHADOW_NEAR, 0, SHADOW_OUTSIDE],
            visibility: vec![],
        };
        let s = maps.stats();
        assert_eq!((s.lit_pixels, s.traced_pixels), (3, 2));
        assert_eq!((s.reasons["edge"], s.reasons["near"], s.reasons["outside"]), (1, 1, 1));
        assert_eq!(s.reasons["grazing"], 0);
        assert!((s.ray_fraction() - 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn sources_are_coloured_by_origin_and_visibility() {
        let maps = ShadowMaps {
            lit: vec![true, true, true, true, false],
            mask: vec![0, 0, SHADOW_EDGE, SHADOW_ALL, 0],
            visibility: vec![1.0, 0.0, 1.0, 0.0, 1.0],
        };
        let rgba = maps.sources_rgba();
        let px: Vec<[u8; 3]> = rgba.chunks(4).map(|c| [c[0], c[1], c[2]]).collect();
        let want: Vec<[u8; 3]> = SOURCE_COLOURS.iter().map(|c| c.1).collect();
        assert_eq!(px, want);
    }
}
