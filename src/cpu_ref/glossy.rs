//! Reference of `glsl/shared/glossy.glsl`: which surfaces are glossy, and the GGX
//! VNDF-sampled directions of their rays.

use crate::gpu_types::FrameUniforms;
use crate::shader_defines::{R2_A1, R2_A2};
use glam::{IVec2, Vec2, Vec3};
use std::f32::consts::PI;

pub fn is_glossy(frame: &FrameUniforms, roughness: f32) -> bool {
    frame.glossy != 0 && roughness >= frame.mirror_roughness && roughness < frame.rough_roughness
}

pub fn traced_reflectivity(frame: &FrameUniforms, reflectivity: f32, roughness: f32) -> f32 {
    if roughness >= frame.rough_roughness {
        0.0
    } else {
        reflectivity
    }
}

pub fn reflection_rays(frame: &FrameUniforms, roughness: f32) -> u32 {
    if is_glossy(frame, roughness) {
        frame.reflection_rays
    } else {
        1
    }
}

pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// `pixel_hash`: a hash of pixel `p` and `seed`.
pub fn pixel_hash(p: IVec2, seed: u32) -> u32 {
    pcg_hash((p.x as u32).wrapping_add(pcg_hash((p.y as u32).wrapping_add(pcg_hash(seed)))))
}

pub fn sample_rotation(p: IVec2, stream: u32) -> [u32; 2] {
    let h = pixel_hash(p, stream);
    [h, pcg_hash(h)]
}

pub fn r2_sample(k: u32, rotation: [u32; 2]) -> Vec2 {
    let f = [
        k.wrapping_mul(R2_A1).wrapping_add(rotation[0]),
        k.wrapping_mul(R2_A2).wrapping_add(rotation[1]),
    ];
    Vec2::new((f[0] >> 8) as f32, (f[1] >> 8) as f32) * (1.0 / 16_777_216.0)
}

/// A GGX microfacet normal drawn from the distribution of normals visible from `ve`
/// (unit, z > 0, the surface normal being z) by `u` in [0, 1)^2: Heitz 2018, listing 1.
pub fn ggx_vndf(ve: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * ve.x, alpha * ve.y, ve.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let mut p2 = r * phi.sin();
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// The orthonormal basis (b1, b2) around unit `n` of Duff et al. 2017.
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sgn = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x),
        Vec3::new(b, sgn + n.y * n.y * a, -n.y),
    )
}

/// Tries at a direction above the surface before the mirror direction is taken.
pub const GLOSSY_TRIES: u32 = 4;

fn reflect(i: Vec3, n: Vec3) -> Vec3 {
    i - 2.0 * n.dot(i) * n
}

/// Direction of glossy ray `s` of pixel `p` in `frame`'s frame (`glossy_direction`).
pub fn glossy_direction(frame: &FrameUniforms, p: IVec2, n: Vec3, v: Vec3, roughness: f32, s: u32) -> Vec3 {
    let alpha = (roughness * roughness).max(1e-4);
    let (b1, b2) = basis(n);
    let ve = Vec3::new(v.dot(b1), v.dot(b2), v.dot(n).max(1e-4)).normalize();
    let k = frame.frame_index.wrapping_mul(frame.reflection_rays).wrapping_add(s);
    let mut rot = sample_rotation(p, frame.sample_stream);
    for _ in 0..GLOSSY_TRIES {
        let h = ggx_vndf(ve, alpha, r2_sample(k, rot));
        let l = reflect(-ve, h);
        if l.z > 0.0 {
            return (l.x * b1 + l.y * b2 + l.z * n).normalize();
        }
        rot = [pcg_hash(rot[0]), pcg_hash(rot[1])];
    }
    reflect(-v, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampled microfacet normals follow GGX's visible-normal density: their mean
    /// cosine to the surface normal, for a view along the normal, is that of the
    /// distribution D(h) (h.n) (h.v) / (n.v) integrated numerically.
    #[test]
    fn vndf_mean_cosine_matches_the_distribution() {
        for alpha in [0.05f32, 0.2, 0.5] {
            let rot = [12_345, 678_901];
            let n = 4096u32;
            let mean: f32 = (0..n)
                .map(|k| ggx_vndf(Vec3::Z, alpha, r2_sample(k, rot)).z)
                .sum::<f32>()
                / n as f32;
            // For v = n the VNDF is G1(v) (v.h) D(h) / (v.n) = D(h) (h.n): the mean of
            // cos is the integral of cos^2 D over that of cos D (which is 1).
            let d = |c: f32| {
                let a2 = alpha * alpha;
                let t = c * c * (a2 - 1.0) + 1.0;
                a2 / (PI * t * t)
            };
            let steps = 200_000;
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for i in 0..steps {
                let c = (i as f64 + 0.5) / steps as f64; // cos theta, d(omega) = 2 pi d(cos)
                let w = d(c as f32) as f64 * c;
                num += w * c;
                den += w;
            }
            let expected = (num / den) as f32;
            assert!(
                (mean - expected).abs() < 2e-3,
                "alpha {alpha}: mean cos {mean} vs {expected}"
            );
        }
    }

    /// Every direction is unit and above the surface, mirror-like for a tiny alpha and
    /// spread for a large one; the same inputs give the same bits.
    #[test]
    fn directions_are_above_the_surface() {
        let frame = FrameUniforms {
            reflection_rays: 3,
            frame_index: 7,
            ..Default::default()
        };
        let n = Vec3::new(0.2, 0.9, -0.1).normalize();
        let v = Vec3::new(-0.6, 0.3, 0.7).normalize();
        let mirror = reflect(-v, n);
        for s in 0..64 {
            let p = IVec2::new(s as i32 * 7, 11);
            let smooth = glossy_direction(&frame, p, n, v, 0.02, s);
            assert!(smooth.dot(mirror) > 0.999, "{smooth} vs mirror {mirror}");
            let rough = glossy_direction(&frame, p, n, v, 0.9, s);
            assert!((rough.length() - 1.0).abs() < 1e-5 && rough.dot(n) > 0.0);
            assert_eq!(rough, glossy_direction(&frame, p, n, v, 0.9, s));
        }
    }
}
