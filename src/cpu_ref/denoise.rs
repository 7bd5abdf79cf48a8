//! Reference of `glsl/reflect_denoise.comp` (reflect.denoise): the edge-aware,
//! variance-guided spatial filter of glossy reflections.

use super::glossy::{is_glossy, pcg_hash};
use super::shading::world_from_depth;
use crate::gpu_types::FrameUniforms;
use crate::shader_defines::{DENOISE_TAPS, MATERIAL_NONE};
use glam::{IVec2, Vec3};
use std::f32::consts::PI;

const GOLDEN_ANGLE: f32 = 2.399_963_2;
const DENOISE_PLANE: f32 = 0.01;
const DENOISE_NORMAL_POWER: f32 = 32.0;
const DENOISE_ROUGHNESS: f32 = 0.1;
const DENOISE_SIGMA: f32 = 2.0;

/// The G-buffer as the filter reads it, row-major over the frame's resolution.
pub struct Surfaces<'a> {
    pub depth: &'a [f32],
    /// xyz normal, w the traced reflectivity.
    pub normal: &'a [[f32; 4]],
    /// Perceptual roughness (the base-colour texel's alpha).
    pub roughness: &'a [f32],
    pub material: &'a [u32],
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The filtered reflection of every pixel (rgb; a: the source, unchanged).
pub fn denoise(
    frame: &FrameUniforms,
    g: &Surfaces<'_>,
    merged: &[[f32; 4]],
    radius: u32,
    reflective_min: f32,
) -> Vec<[f32; 4]> {
    let (w, h) = (frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * w + q.x) as usize;
    let glossy_at = |q: IVec2| -> (bool, Vec3, f32) {
        let nr = g.normal[at(q)];
        let n = Vec3::new(nr[0], nr[1], nr[2]).normalize();
        let r = g.roughness[at(q)];
        (
            g.material[at(q)] != MATERIAL_NONE && nr[3] > reflective_min && is_glossy(frame, r),
            n,
            r,
        )
    };
    let rgb = |c: [f32; 4]| Vec3::new(c[0], c[1], c[2]);
    let camera = frame.camera_pos.truncate();
    let spread = 2.0 / (frame.proj.y_axis.y.abs() * frame.resolution[1] as f32);
    let mut out = vec![[0.0f32; 4]; merged.len()];
    for y in 0..h {
        for x in 0..w {
            let p = IVec2::new(x, y);
            let c = merged[at(p)];
            let (glossy, n, roughness) = glossy_at(p);
            let disc = if glossy {
                (radius as f32).min(roughness * roughness / spread)
            } else {
                0.0
            };
            let taps = if disc >= 1.0 { DENOISE_TAPS } else { 0 };
            let xp = world_from_depth(frame, p, g.depth[at(p)]);
            let dist = (xp - camera).length();
            let turn = (pcg_hash(
                (x as u32).wrapping_add(pcg_hash((y as u32).wrapping_add(pcg_hash(frame.frame_index)))),
            ) >> 8) as f32
                * (1.0 / 16_777_216.0);
            let mut taken = vec![(rgb(c), 1.0f32, luminance(rgb(c)))];
            for i in 0..taps {
                let t = (i as f32 + 0.5) / DENOISE_TAPS as f32;
                let angle = i as f32 * GOLDEN_ANGLE + 2.0 * PI * turn;
                let off = disc * t.sqrt() * glam::Vec2::new(angle.cos(), angle.sin());
                let q = p + IVec2::new(off.x.round() as i32, off.y.round() as i32);
                let (mut wi, mut col) = (0.0, Vec3::ZERO);
                if q.x >= 0 && q.y >= 0 && q.x < w && q.y < h {
                    let (gq, nq, rq) = glossy_at(q);
                    if gq {
                        let xq = world_from_depth(frame, q, g.depth[at(q)]);
                        let plane = n.dot(xq - xp).abs() / (DENOISE_PLANE * dist);
                        wi = (-2.0 * t - plane * plane - (rq - roughness).abs() / DENOISE_ROUGHNESS).exp()
                            * n.dot(nq).max(0.0).powf(DENOISE_NORMAL_POWER);
                        col = rgb(merged[at(q)]);
                    }
                }
                taken.push((col, wi, luminance(col)));
            }
            let mut filtered = rgb(c);
            if taps > 0 {
                let wsum: f32 = taken.iter().map(|t| t.1).sum();
                let mean = taken.iter().map(|t| t.1 * t.2).sum::<f32>() / wsum;
                let sq = taken.iter().map(|t| t.1 * t.2 * t.2).sum::<f32>() / wsum;
                let variance = (sq - mean * mean).max(0.0);
                let k = 1.0 / (2.0 * DENOISE_SIGMA * DENOISE_SIGMA * variance + 1e-8);
                let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
                for &(col, wi, l) in &taken {
                    let d = l - mean;
                    let wk = wi * (-d * d * k).exp();
                    sum += wk * col;
                    total += wk;
                }
                if total > 1e-20 {
                    filtered = sum / total;
                }
            }
            out[at(p)] = [filtered.x, filtered.y, filtered.z, c[3]];
        }
    }
    out
}

const TEMPORAL_DISOCCLUSION: f32 = 0.01;
const TEMPORAL_GAMMA: f32 = 2.0;

/// The previous frame as `reflect_temporal.comp` reads it: its camera, its accumulated
/// reflection (rgba) and per pixel (distance, frames).
pub struct History<'a> {
    pub view_proj: glam::Mat4,
    pub camera: Vec3,
    pub color: &'a [[f32; 4]],
    pub meta: &'a [[f32; 4]],
}

/// The temporal step of `reflect.denoise` (`glsl/reflect_temporal.comp`): this frame's
/// accumulated reflection and meta (distance, frames) from the spatially filtered
/// `current` and the previous frame's `history` (`None`: no valid history).
pub fn temporal(
    frame: &FrameUniforms,
    g: &Surfaces<'_>,
    current: &[[f32; 4]],
    history: Option<&History<'_>>,
    reflective_min: f32,
    max_frames: u32,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let (w, h) = (frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * w + q.x) as usize;
    let rgb = |c: [f32; 4]| Vec3::new(c[0], c[1], c[2]);
    let camera = frame.camera_pos.truncate();
    let (mut out, mut meta) = (vec![[0.0f32; 4]; current.len()], vec![[0.0f32; 4]; current.len()]);
    for y in 0..h {
        for x in 0..w {
            let p = IVec2::new(x, y);
            let c = current[at(p)];
            let nr = g.normal[at(p)];
            let glossy =
                g.material[at(p)] != MATERIAL_NONE && nr[3] > reflective_min && is_glossy(frame, g.roughness[at(p)]);
            let xp = world_from_depth(frame, p, g.depth[at(p)]);
            let dist = (xp - camera).length();
            let (mut out_c, mut frames) = (rgb(c), 1.0f32);
            if let (true, Some(hist)) = (glossy, history) {
                let (mut m1, mut m2) = (Vec3::ZERO, Vec3::ZERO);
                for j in -1..=1 {
                    for i in -1..=1 {
                        let q = (p + IVec2::new(i, j)).clamp(IVec2::ZERO, IVec2::new(w - 1, h - 1));
                        let v = rgb(current[at(q)]);
                        m1 += v;
                        m2 += v * v;
                    }
                }
                m1 /= 9.0;
                let sigma = (m2 / 9.0 - m1 * m1).max(Vec3::ZERO).powf(0.5);
                let hc = hist.view_proj * xp.extend(1.0);
                let uv = hc.truncate().truncate() / hc.w * 0.5 + 0.5;
                let qf = (uv * glam::Vec2::new(w as f32, h as f32)).floor();
                let q = IVec2::new(qf.x as i32, qf.y as i32);
                if hc.w > 0.0 && q.x >= 0 && q.y >= 0 && q.x < w && q.y < h {
                    let m = hist.meta[at(q)];
                    let expected = (xp - hist.camera).length();
                    if m[1] >= 1.0 && (m[0] - expected).abs() < TEMPORAL_DISOCCLUSION * expected {
                        let prev =
                            rgb(hist.color[at(q)]).clamp(m1 - TEMPORAL_GAMMA * sigma, m1 + TEMPORAL_GAMMA * sigma);
                        frames = (m[1] + 1.0).min(max_frames as f32);
                        out_c = prev + (rgb(c) - prev) * (1.0 / frames);
                    }
                }
            }
            out[at(p)] = [out_c.x, out_c.y, out_c.z, c[3]];
            meta[at(p)] = if glossy {
                [dist, frames, 0.0, 0.0]
            } else {
                [-1.0, 0.0, 0.0, 0.0]
            };
        }
    }
    (out, meta)
}
