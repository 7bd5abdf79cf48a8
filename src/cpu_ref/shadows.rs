//! Reference of `glsl/shadow_classify.comp` and `glsl/shadow_trace.comp`: the sun's
//! visibility of a pixel under `rays` and `hybrid` shadows.

use super::reflect::{self, PathScene};
use super::shading::{self, ShadowMap};
use crate::gpu_types::FrameUniforms;
use crate::settings::Shadows;
use crate::shader_defines::MATERIAL_NONE;
use glam::{IVec2, Vec3, Vec4Swizzles};

/// `shadow.classify` of pixel `p` (G-buffer depth, normal as stored, material): the
/// mask's `SHADOW_*` bits (nonzero: a shadow ray answers) and the visibility it writes
/// (-1 where a ray answers: `shadow.trace` overwrites it).
pub fn classify(
    frame: &FrameUniforms,
    map: &ShadowMap<'_>,
    shadows: Shadows,
    p: IVec2,
    (depth, normal, material): (f32, Vec3, u32),
) -> (u32, f32) {
    if material == MATERIAL_NONE {
        return (0, 1.0);
    }
    let ndl = normal.normalize().dot(frame.light_dir.xyz());
    let w = shading::world_from_depth(frame, p, depth);
    let (doubt, vis) = shading::shadow_ray_reasons(frame, map, w, ndl, shadows);
    (doubt, if doubt != 0 { -1.0 } else { vis })
}

/// `shadow.trace` of pixel `p`: the visibility of its shadow ray.
pub fn ray_visibility(s: &PathScene<'_>, p: IVec2, depth: f32, normal: Vec3) -> f32 {
    let pos = shading::world_from_depth(s.frame, p, depth);
    reflect::shadow_ray(s, pos, normal.normalize())
}

/// The visibility a frame's `light.direct` reads at pixel `p` under `shadows`: the
/// map's PCF, or `classify` answered by `ray_visibility` where it lists the pixel.
pub fn visibility(s: &PathScene<'_>, p: IVec2, (depth, normal, material): (f32, Vec3, u32)) -> f32 {
    if s.shadows == Shadows::Map {
        let w = shading::world_from_depth(s.frame, p, depth);
        return shading::shadow_visibility(s.frame, s.shadow_map, w);
    }
    match classify(s.frame, s.shadow_map, s.shadows, p, (depth, normal, material)) {
        (0, vis) => vis,
        _ => ray_visibility(s, p, depth, normal),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader_defines::SHADOW_ALL;

    /// The sky is lit and never listed; a surface facing away is dark and never listed.
    #[test]
    fn sky_and_back_faces_are_never_listed() {
        let frame = FrameUniforms {
            light_dir: glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
            ..Default::default()
        };
        let depth = [1.0f32; 4];
        let map = ShadowMap { size: 2, depth: &depth };
        let p = IVec2::ZERO;
        for shadows in [Shadows::Rays, Shadows::Hybrid] {
            assert_eq!(
                classify(&frame, &map, shadows, p, (0.5, Vec3::Y, MATERIAL_NONE)),
                (0, 1.0)
            );
            assert_eq!(classify(&frame, &map, shadows, p, (0.5, -Vec3::Y, 0)), (0, 0.0));
        }
        assert_eq!(
            classify(&frame, &map, Shadows::Rays, p, (0.5, Vec3::Y, 0)),
            (SHADOW_ALL, -1.0)
        );
    }
}
