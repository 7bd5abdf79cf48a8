//! Reference of `glsl/shared/shading.glsl` and `frame.glsl` (light.direct).

use crate::gpu_types::FrameUniforms;
use crate::settings::Shadows;
use crate::shader_defines::{MAX_PCF_RADIUS, SHADOW_ALL, SHADOW_EDGE, SHADOW_GRAZING, SHADOW_NEAR, SHADOW_OUTSIDE};
use glam::{IVec2, Vec2, Vec3, Vec3Swizzles, Vec4, Vec4Swizzles};

/// Sky radiance along unit direction `d` (`sky_radiance`).
pub fn sky(frame: &FrameUniforms, d: Vec3) -> Vec3 {
    let up = d.y.clamp(-1.0, 1.0);
    let (zen, hor) = (frame.sky_zenith.xyz(), frame.sky_horizon.xyz());
    if up >= 0.0 {
        hor.lerp(zen, up.sqrt())
    } else {
        hor * (0.6 + (0.25 - 0.6) * (-up * 4.0).min(1.0))
    }
}

/// World position of pixel `p` at depth `depth` (`world_from_depth`).
pub fn world_from_depth(frame: &FrameUniforms, p: IVec2, depth: f32) -> Vec3 {
    let res = Vec2::new(frame.resolution[0] as f32, frame.resolution[1] as f32);
    let ndc = (p.as_vec2() + 0.5) / res * 2.0 - 1.0;
    let w = frame.inv_view_proj * Vec4::new(ndc.x, ndc.y, depth, 1.0);
    w.xyz() / w.w
}

/// `pixel_spread`: the angle one pixel subtends at the camera (vertical).
pub fn pixel_spread(frame: &FrameUniforms) -> f32 {
    2.0 / (frame.proj.y_axis.y.abs() * frame.resolution[1] as f32)
}

/// A square shadow map of `size`² depths, row-major.
pub struct ShadowMap<'a> {
    pub size: u32,
    pub depth: &'a [f32],
}

impl ShadowMap<'_> {
    /// The depth of texel `q`, clamped to the edge.
    fn texel(&self, q: IVec2) -> f32 {
        let last = self.size as i32 - 1;
        let q = q.clamp(IVec2::ZERO, IVec2::splat(last));
        self.depth[(q.y * self.size as i32 + q.x) as usize]
    }
}

/// Fraction of light reaching `w` (`shadow_visibility`).
pub fn shadow_visibility(frame: &FrameUniforms, map: &ShadowMap<'_>, w: Vec3) -> f32 {
    shadow_pcf(frame, map, w).0
}

/// `shadow_pcf`: the fraction of light reaching `w` and the `SHADOW_*` bits of why the
/// map may be wrong there (0: sure).
pub fn shadow_pcf(frame: &FrameUniforms, map: &ShadowMap<'_>, w: Vec3) -> (f32, u32) {
    let c = frame.light_view_proj * w.extend(1.0);
    let ndc = c.xyz() / c.w;
    let uv = ndc.xy() * 0.5 + 0.5;
    if uv.x < 0.0 || uv.y < 0.0 || uv.x > 1.0 || uv.y > 1.0 || ndc.z > 1.0 {
        return (1.0, SHADOW_OUTSIDE);
    }
    let ref_depth = ndc.z - frame.shadow_bias;
    let t = uv * frame.shadow_map_size as f32 - 0.5;
    let cell = t.floor();
    let f = t - cell;
    let r = frame.pcf_radius.min(MAX_PCF_RADIUS) as i32;
    let base = cell.as_ivec2() - r;
    let n = 2 * r + 2;
    let mut sum = 0.0;
    let (mut any_lit, mut any_dark, mut doubt) = (false, false, 0);
    for j in 0..n {
        let wy = if j == 0 {
            1.0 - f.y
        } else if j == n - 1 {
            f.y
        } else {
            1.0
        };
        for i in 0..n {
            let wx = if i == 0 {
                1.0 - f.x
            } else if i == n - 1 {
                f.x
            } else {
                1.0
            };
            let d = map.texel(base + IVec2::new(i, j));
            let lit = d >= ref_depth;
            any_lit |= lit;
            any_dark |= !lit;
            if (d - ref_depth).abs() < frame.shadow_band {
                doubt |= SHADOW_NEAR;
            }
            sum += wx * wy * if lit { 1.0 } else { 0.0 };
        }
    }
    if any_lit && any_dark {
        doubt |= SHADOW_EDGE;
    }
    (sum / ((2 * r + 1) * (2 * r + 1)) as f32, doubt)
}

/// `SHADOW_GRAZING_NDL`: n.l under which the hybrid shadows do not trust the map.
pub const SHADOW_GRAZING_NDL: f32 = 0.1;

/// `shadow_map_doubt`: 0 and the map's visibility (0 or 1) where the map is sure of
/// `w` (its normal's n.l = `ndl` > 0), else the `SHADOW_*` bits of why not.
pub fn shadow_map_doubt(frame: &FrameUniforms, map: &ShadowMap<'_>, w: Vec3, ndl: f32) -> (u32, f32) {
    let (pcf, mut doubt) = shadow_pcf(frame, map, w);
    if ndl < SHADOW_GRAZING_NDL {
        doubt |= SHADOW_GRAZING;
    }
    (doubt, if pcf > 0.5 { 1.0 } else { 0.0 })
}

/// `shadow_ray_reasons` under traced `shadows` (`rays` or `hybrid`): the `SHADOW_*`
/// reasons `w` (n.l = `ndl`) gets a shadow ray, or 0 and its visibility (0 facing away
/// from the sun, else the sure map's).
pub fn shadow_ray_reasons(
    frame: &FrameUniforms,
    map: &ShadowMap<'_>,
    w: Vec3,
    ndl: f32,
    shadows: Shadows,
) -> (u32, f32) {
    assert!(shadows.traces(), "shadow rays under map shadows");
    if ndl <= 0.0 {
        (0, 0.0)
    } else if shadows == Shadows::Rays {
        (SHADOW_ALL, 0.0)
    } else {
        shadow_map_doubt(frame, map, w, ndl)
    }
}

/// `DIELECTRIC_F0`: a dielectric's specular reflectance at normal incidence.
pub const DIELECTRIC_F0: f32 = 0.04;

/// `specular_f0`.
pub fn specular_f0(base: Vec3, metallic: f32) -> Vec3 {
    Vec3::splat(DIELECTRIC_F0).lerp(base, metallic)
}

/// `fresnel_schlick`.
pub fn fresnel_schlick(f0: Vec3, cos_theta: f32) -> Vec3 {
    let m = 1.0 - cos_theta.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

/// `reflection_weight`: the weight of the mirror reflection seen from `v`.
pub fn reflection_weight(base: Vec3, metallic: f32, reflectivity: f32, n: Vec3, v: Vec3) -> Vec3 {
    reflectivity * fresnel_schlick(specular_f0(base, metallic), n.dot(v))
}

/// A surface point's material as `shade_direct` reads it.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub base: Vec3,
    pub roughness: f32,
    pub reflectivity: f32,
    pub metallic: f32,
}

/// Direct radiance towards `v` (`shade_direct`).
pub fn shade_direct(frame: &FrameUniforms, s: Surface, n: Vec3, v: Vec3, visibility: f32) -> Vec3 {
    let l = frame.light_dir.xyz();
    let ndl = n.dot(l).max(0.0);
    let f0 = specular_f0(s.base, s.metallic);
    let f = fresnel_schlick(f0, n.dot(v));
    let diffuse_albedo = s.base * (1.0 - s.metallic) * (Vec3::ONE - f);
    let r = s.roughness.max(0.05);
    let e = (2.0 / (r * r) - 2.0).max(1.0);
    let h = (l + v).normalize();
    let spec = (e + 8.0) / (8.0 * std::f32::consts::PI) * n.dot(h).max(0.0).powf(e);
    let ks = fresnel_schlick(f0, h.dot(v));
    let direct =
        (diffuse_albedo * std::f32::consts::FRAC_1_PI + ks * spec) * frame.light_color.xyz() * ndl * visibility;
    let sky = frame.sky_horizon.xyz().lerp(frame.sky_zenith.xyz(), n.y * 0.5 + 0.5);
    let ambient = (diffuse_albedo + (1.0 - s.reflectivity) * f) * sky * frame.ambient;
    direct + ambient
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Schlick: F0 head-on, 1 at grazing, rising in between; a dielectric reflects 4%
    /// head-on, a metal its base colour; the mirror weight scales with reflectivity.
    #[test]
    fn fresnel_rises_from_f0_to_one_at_grazing() {
        let gold = Vec3::new(1.0, 0.766, 0.336);
        for f0 in [Vec3::splat(DIELECTRIC_F0), gold] {
            assert_eq!(fresnel_schlick(f0, 1.0), f0);
            assert_eq!(fresnel_schlick(f0, 0.0), Vec3::ONE);
            let mut prev = f0;
            for k in (0..100).rev() {
                let f = fresnel_schlick(f0, k as f32 / 100.0);
                assert!(f.cmpge(prev).all(), "{f} after {prev}");
                prev = f;
            }
        }
        assert_eq!(specular_f0(gold, 0.0), Vec3::splat(0.04));
        assert_eq!(specular_f0(gold, 1.0), gold);
        let w = reflection_weight(gold, 1.0, 0.5, Vec3::Y, Vec3::Y);
        assert!((w - 0.5 * gold).abs().max_element() < 1e-6);
    }
}
