//! Reference of `glsl/ssr_classify.comp` and the ray setup it shares with
//! `ssr_trace.comp` (`glsl/shared/ssr.glsl`).

use super::shading::world_from_depth;
use crate::gpu_types::FrameUniforms;
use crate::shader_defines::{FAIL_FORCED, FAIL_LOW_CONFIDENCE, MATERIAL_NONE};
use glam::{IVec2, Mat3, Vec3, Vec4Swizzles};

/// The reflected view-space ray of a pixel (`SsrRay`).
#[derive(Clone, Copy, Debug)]
pub struct SsrRay {
    pub vpos: Vec3,
    pub vn: Vec3,
    pub vdir: Vec3,
}

/// `ssr_ray`: pixel `p`'s surface point, normal and reflected direction in view space.
pub fn ssr_ray(frame: &FrameUniforms, p: IVec2, depth: f32, n_world: Vec3) -> SsrRay {
    let vpos = (frame.view * world_from_depth(frame, p, depth).extend(1.0)).xyz();
    let vn = (Mat3::from_mat4(frame.view) * n_world.normalize()).normalize();
    let vdir = vpos.normalize().reflect(vn).normalize();
    SsrRay { vpos, vn, vdir }
}

/// `heading_confidence`.
pub fn heading_confidence(vdir: Vec3) -> f32 {
    (1.0 - vdir.z).clamp(0.0, 1.0)
}

/// What the classification does with a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Not marched: this fail mask (0: nothing to reflect), SSR colour 0.
    Done(u32),
    /// Appended to the march list.
    March,
}

/// `ssr_classify.comp` for one pixel (G-buffer depth, normal.xyz + reflectivity in w,
/// material id). Also returns the heading confidence it compared (NaN where none was),
/// so a test can tell pixels on the threshold, where float rounding decides.
pub fn classify(
    frame: &FrameUniforms,
    p: IVec2,
    gbuffer: (f32, [f32; 4], u32),
    min_confidence: f32,
    reflective_min: f32,
    mask_only: bool,
) -> (Class, f32) {
    let (depth, nr, material) = gbuffer;
    let reflective = material != MATERIAL_NONE && nr[3] > reflective_min;
    if mask_only {
        return (Class::Done(if reflective { FAIL_FORCED } else { 0 }), f32::NAN);
    }
    if !reflective {
        return (Class::Done(0), f32::NAN);
    }
    let ray = ssr_ray(frame, p, depth, Vec3::new(nr[0], nr[1], nr[2]));
    let h = heading_confidence(ray.vdir);
    if h >= min_confidence {
        (Class::March, h)
    } else {
        (Class::Done(FAIL_LOW_CONFIDENCE), h)
    }
}
