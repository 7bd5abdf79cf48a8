//! What a frame's reflections did, per pixel and in total, read back from the G-buffer
//! and the fail mask: the counts in every report and the `--fail-mask` image.

use crate::shader_defines::{
    FAIL_BACK_FACE, FAIL_BEHIND, FAIL_BLEND, FAIL_FORCED, FAIL_HIT_REFLECTIVE, FAIL_LEFT_SCREEN, FAIL_LOW_CONFIDENCE,
    FAIL_OUT_OF_STEPS, FAIL_SKIPPED, FAIL_UNTRACED, MASK_COLOUR_0, MASK_COLOUR_1, MASK_COLOUR_2, MASK_COLOUR_3,
    MASK_COLOUR_4, MASK_COLOUR_5, MASK_COLOUR_6, MASK_COLOUR_7, MASK_COLOUR_8, MASK_COLOUR_9, MASK_COLOUR_SSR_OK,
};
use std::collections::BTreeMap;

/// Pixel counts of a frame's reflections.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReflectionStats {
    /// Pixels whose surface reflects (reflectivity above `reflective_min`).
    pub reflective_pixels: u64,
    /// Reflective pixels SSR failed on (all of them in `rt` mode, as `forced`).
    pub ssr_failed_pixels: u64,
    /// Reflective pixels the ray tracer produced: the failed ones but the untraced in
    /// the modes that trace (`hybrid`, `rt`, `provenance`), none in `ssr` and `raster`.
    pub traced_pixels: u64,
    /// Failed pixels by reason, every reason present (0 when none failed for it).
    pub fail_reasons: BTreeMap<&'static str, u64>,
}

impl ReflectionStats {
    /// traced / reflective pixels: the share of reflections the ray tracer produced.
    pub fn rt_pixel_fraction(&self) -> f64 {
        self.traced_pixels as f64 / self.reflective_pixels.max(1) as f64
    }
}

/// Per-pixel reflection state of a frame, row-major.
#[derive(Clone, Debug)]
pub struct ReflectionMaps {
    /// The pixel's surface reflects (reflectivity above `reflective_min`).
    pub reflective: Vec<bool>,
    /// `FAIL_*` bits written by `ssr.classify` and `ssr.trace` (0: SSR succeeded or
    /// nothing to reflect).
    pub mask: Vec<u32>,
    /// Whether the frame's mode ray traced the failed pixels.
    pub traced: bool,
}

impl ReflectionMaps {
    pub fn stats(&self) -> ReflectionStats {
        let failed = || self.mask.iter().zip(&self.reflective).filter(|(m, r)| **m != 0 && **r);
        // Every reason is reported, 0 when no pixel failed for it.
        let mut fail_reasons: BTreeMap<&'static str, u64> = FAIL_REASONS.iter().map(|&(_, n)| (n, 0)).collect();
        for (&m, _) in failed() {
            for (bit, name) in FAIL_REASONS {
                if m & bit != 0 {
                    *fail_reasons.entry(name).or_default() += 1;
                }
            }
        }
        let traced = failed().filter(|(m, _)| **m & FAIL_UNTRACED == 0).count() as u64;
        ReflectionStats {
            reflective_pixels: self.reflective.iter().filter(|r| **r).count() as u64,
            ssr_failed_pixels: failed().count() as u64,
            traced_pixels: if self.traced { traced } else { 0 },
            fail_reasons,
        }
    }

    /// The fail mask as tightly packed RGBA8, one colour per reason (untraced, else the
    /// lowest set bit; `FAIL_COLOURS`), SSR successes dark blue, non-reflective pixels black.
    pub fn fail_mask_rgba(&self) -> Vec<u8> {
        self.mask
            .iter()
            .zip(&self.reflective)
            .flat_map(|(&m, &r)| {
                let rgb = if !r {
                    [0, 0, 0]
                } else if m == 0 {
                    SSR_OK_COLOUR
                } else {
                    let reason = if m & FAIL_UNTRACED != 0 { FAIL_UNTRACED } else { m };
                    FAIL_COLOURS[reason.trailing_zeros() as usize % FAIL_COLOURS.len()]
                };
                [rgb[0], rgb[1], rgb[2], 255]
            })
            .collect()
    }
}

const fn unpack(c: u32) -> [u8; 3] {
    [c as u8, (c >> 8) as u8, (c >> 16) as u8]
}

/// Colour of a reflective pixel SSR answered, in `--fail-mask` images and the demo's
/// fail-mask view (`compose`'s `COMPOSE_FAIL_MASK`, which this mirrors).
pub const SSR_OK_COLOUR: [u8; 3] = unpack(MASK_COLOUR_SSR_OK);
/// Colour of each fail reason, indexed by bit position (the order of
/// `FAIL_REASONS`): yellow, orange, red, magenta, cyan, green, white, light blue (an
/// SSR hit blended with the ray tracer's), grey (untraced), brown (a rays-only tile's).
pub const FAIL_COLOURS: [[u8; 3]; 10] = [
    unpack(MASK_COLOUR_0),
    unpack(MASK_COLOUR_1),
    unpack(MASK_COLOUR_2),
    unpack(MASK_COLOUR_3),
    unpack(MASK_COLOUR_4),
    unpack(MASK_COLOUR_5),
    unpack(MASK_COLOUR_6),
    unpack(MASK_COLOUR_7),
    unpack(MASK_COLOUR_8),
    unpack(MASK_COLOUR_9),
];

/// Names of the fail-mask reason bits, for reports.
pub const FAIL_REASONS: [(u32, &str); 10] = [
    (FAIL_LEFT_SCREEN, "left_screen"),
    (FAIL_BEHIND, "behind_geometry"),
    (FAIL_OUT_OF_STEPS, "out_of_steps"),
    (FAIL_BACK_FACE, "back_face"),
    (FAIL_LOW_CONFIDENCE, "low_confidence"),
    (FAIL_HIT_REFLECTIVE, "hit_reflective"),
    (FAIL_FORCED, "forced"),
    (FAIL_BLEND, "ssr_blend"),
    (FAIL_UNTRACED, "untraced"),
    (FAIL_SKIPPED, "rays_only_tile"),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// `FAIL_REASONS` lists the fail bits in bit order, so a reason's colour index in
    /// `FAIL_COLOURS` is its bit position.
    #[test]
    fn fail_reasons_are_in_bit_order() {
        for (i, (bit, _)) in FAIL_REASONS.iter().enumerate() {
            assert_eq!(*bit, 1 << i);
        }
        assert_eq!(FAIL_REASONS.len(), FAIL_COLOURS.len());
    }

    /// Stats and the debug image agree with a hand-made mask.
    #[test]
    fn maps_count_and_colour_each_reason() {
        let maps = ReflectionMaps {
            reflective: vec![false, true, true, true, true],
            mask: vec![0, 0, FAIL_BACK_FACE, FAIL_LEFT_SCREEN | FAIL_BEHIND, FAIL_FORCED],
            traced: true,
        };
        let s = maps.stats();
        assert_eq!((s.reflective_pixels, s.ssr_failed_pixels, s.traced_pixels), (4, 3, 3));
        let untraced = ReflectionMaps {
            traced: false,
            ..maps.clone()
        };
        assert_eq!(untraced.stats().traced_pixels, 0, "ssr mode traces nothing");
        assert_eq!(s.fail_reasons["back_face"], 1);
        assert_eq!(s.fail_reasons["left_screen"], 1);
        assert_eq!(s.fail_reasons["behind_geometry"], 1);
        assert_eq!(s.fail_reasons["out_of_steps"], 0, "absent reasons are reported as 0");
        assert_eq!(s.fail_reasons.len(), FAIL_REASONS.len());
        let rgba = maps.fail_mask_rgba();
        assert_eq!(&rgba[0..4], &[0, 0, 0, 255]);
        assert_eq!(&rgba[4..7], &SSR_OK_COLOUR);
        assert_eq!(&rgba[8..11], &FAIL_COLOURS[3]);
        assert_eq!(&rgba[12..15], &FAIL_COLOURS[0]);
        assert_eq!(&rgba[16..19], &FAIL_COLOURS[6]);
    }
}
