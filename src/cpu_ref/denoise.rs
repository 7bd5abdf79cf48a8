//! Reference of `glsl/reflect_denoise.comp` (reflect.denoise): the edge-aware,
//! variance-guided spatial filter of glossy reflections.

use super::glossy::{is_glossy, pixel_hash};
use super::shading::world_from_depth;
use crate::gpu_types::FrameUniforms;
use crate::shader_defines::{DENOISE_TAPS, MATERIAL_NONE};

/// The glossy pixels `ssr.classify` lists for the filter: a surface (not the sky) whose
/// traced reflectivity exceeds `reflective_min` and whose roughness is glossy.
pub fn glossy_pixels(frame: &FrameUniforms, g: &Surfaces<'_>, reflective_min: f32) -> Vec<IVec2> {
    let w = frame.resolution[0] as usize;
    (0..g.depth.len())
        .filter(|&i| {
            g.material[i] != MATERIAL_NONE && g.normal[i][3] > reflective_min && is_glossy(frame, g.roughness[i])
        })
        .map(|i| IVec2::new((i % w) as i32, (i / w) as i32))
        .collect()
}
use glam::{IVec2, Vec3};
use std::f32::consts::PI;

/// `reflect_denoise.comp`'s SPIRAL, the same numbers.
const SPIRAL: [[f32; 2]; DENOISE_TAPS as usize] = [
    [0.17677669, 0.0],
    [-0.22577219, 0.20682582],
    [0.034558054, -0.39377117],
    [0.28457123, 0.37117276],
    [-0.5222232, -0.09237393],
    [0.4946954, -0.31468472],
    [-0.16546592, 0.615525],
    [-0.31556147, -0.60759443],
    [0.68464214, 0.25003022],
    [-0.7122561, 0.29400897],
    [0.3433545, -0.73372865],
    [0.25373024, 0.808932],
    [-0.7647459, -0.44318587],
    [0.897134, -0.19723238],
    [-0.5475069, 0.77877223],
    [-0.12648676, -0.9760897],
];
const DENOISE_PLANE: f32 = 0.01;
const DENOISE_ROUGHNESS: f32 = 0.1;
const DENOISE_SIGMA: f32 = 2.0;
const DENOISE_MIN_RADIUS: f32 = 2.0;

/// The G-buffer as the filter reads it, row-major over the frame's resolution.
pub struct Surfaces<'a> {
    pub depth: &'a [f32],
    /// xyz normal, w the traced reflectivity.
    pub normal: &'a [[f32; 4]],
    /// Perceptual roughness (the base-colour texel's alpha).
    pub roughness: &'a [f32],
    pub material: &'a [u32],
    /// xyz: the surface point's world position the frame before minus this frame's.
    pub motion: &'a [[f32; 4]],
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Whether the filters take the surface at pixel `i` as glossy: by its traced
/// reflectivity and roughness alone (the sky's reflectivity is 0 in a real G-buffer).
fn glossy_at(frame: &FrameUniforms, g: &Surfaces<'_>, i: usize, reflective_min: f32) -> bool {
    g.normal[i][3] > reflective_min && is_glossy(frame, g.roughness[i])
}

fn normal_at(g: &Surfaces<'_>, i: usize) -> Vec3 {
    Vec3::new(g.normal[i][0], g.normal[i][1], g.normal[i][2]).normalize()
}

fn rgb(c: [f32; 4]) -> Vec3 {
    Vec3::new(c[0], c[1], c[2])
}

/// `merged` with each pixel of `list` spatially filtered (`reflect_denoise.comp`);
/// `hit_distance` per pixel, the distance to what its rays hit.
pub fn denoise(
    frame: &FrameUniforms,
    g: &Surfaces<'_>,
    merged: &[[f32; 4]],
    hit_distance: &[f32],
    list: &[IVec2],
    radius: u32,
    reflective_min: f32,
) -> Vec<[f32; 4]> {
    let (w, h) = (frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * w + q.x) as usize;
    let camera = frame.camera_pos.truncate();
    let spread = super::shading::pixel_spread(frame);
    let mut out = merged.to_vec();
    for &p in list {
        let c = merged[at(p)];
        let (n, roughness) = (normal_at(g, at(p)), g.roughness[at(p)]);
        let xp = world_from_depth(frame, p, g.depth[at(p)]);
        let dist = (xp - camera).length();
        let footprint = roughness * roughness * hit_distance[at(p)] / (dist * spread);
        let disc = (radius as f32).min(footprint.max(DENOISE_MIN_RADIUS));
        let taps = if disc >= 1.0 { DENOISE_TAPS } else { 0 };
        let hash = pixel_hash(p, frame.frame_index);
        let angle = 2.0 * PI * ((hash >> 8) as f32 * (1.0 / 16_777_216.0));
        let turn_by = disc * glam::Mat2::from_cols_array(&[angle.cos(), angle.sin(), -angle.sin(), angle.cos()]);
        let mut taken = vec![(rgb(c), 1.0f32, luminance(rgb(c)))];
        for (i, offset) in SPIRAL.iter().enumerate().take(taps as usize) {
            let t = (i as f32 + 0.5) / DENOISE_TAPS as f32;
            let off = turn_by * glam::Vec2::from(*offset);
            let q = p + IVec2::new(off.x.round() as i32, off.y.round() as i32);
            let (mut wi, mut col) = (0.0, Vec3::ZERO);
            if q.x >= 0 && q.y >= 0 && q.x < w && q.y < h && glossy_at(frame, g, at(q), reflective_min) {
                let xq = world_from_depth(frame, q, g.depth[at(q)]);
                let plane = n.dot(xq - xp).abs() / (DENOISE_PLANE * dist);
                let rq = g.roughness[at(q)];
                wi = (-2.0 * t - plane * plane - (rq - roughness).abs() / DENOISE_ROUGHNESS).exp()
                    * n.dot(normal_at(g, at(q))).max(0.0).powi(32);
                col = rgb(merged[at(q)]);
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
                let wk = wi / (1.0 + d * d * k);
                sum += wk * col;
                total += wk;
            }
            if total > 1e-20 {
                filtered = sum / total;
            }
        }
        out[at(p)] = [filtered.x, filtered.y, filtered.z, c[3]];
    }
    out
}

const TEMPORAL_DISOCCLUSION: f32 = 0.01;
const TEMPORAL_GAMMA: f32 = 2.0;

/// The previous frame as `reflect_temporal.comp` reads it: its camera, its accumulated
/// reflection (rgba) and per pixel (distance, frames, the stamp of the frame that wrote it).
pub struct History<'a> {
    pub view_proj: glam::Mat4,
    pub camera: Vec3,
    pub color: &'a [[f32; 4]],
    pub meta: &'a [[f32; 4]],
}

/// A frame's stamp in the history: its index mod 2^24, exact in f32.
pub fn stamp(index: u32) -> f32 {
    (index & 0xff_ffff) as f32
}

/// The temporal step of `reflect.denoise` (`glsl/reflect_temporal.comp`) over the pixels
/// of `list`: their accumulated reflection (rgba) and meta (distance, frames, stamp),
/// from the spatially filtered `current` and the previous frame's `history` (`None`: no
/// valid history). Pixels not in the list are left as (0, 0, 0, 0).
pub fn temporal(
    frame: &FrameUniforms,
    g: &Surfaces<'_>,
    current: &[[f32; 4]],
    list: &[IVec2],
    history: Option<&History<'_>>,
    reflective_min: f32,
    max_frames: u32,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let (w, h) = (frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * w + q.x) as usize;
    let camera = frame.camera_pos.truncate();
    let (mut out, mut meta) = (vec![[0.0f32; 4]; current.len()], vec![[0.0f32; 4]; current.len()]);
    for &p in list {
        let c = current[at(p)];
        let xp = world_from_depth(frame, p, g.depth[at(p)]);
        let dist = (xp - camera).length();
        let (mut out_c, mut frames) = (rgb(c), 1.0f32);
        if let Some(hist) = history {
            let (mut m1, mut m2, mut count) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
            for j in -1..=1 {
                for i in -1..=1 {
                    let q = p + IVec2::new(i, j);
                    if q.x >= 0 && q.y >= 0 && q.x < w && q.y < h && glossy_at(frame, g, at(q), reflective_min) {
                        let v = rgb(current[at(q)]);
                        m1 += v;
                        m2 += v * v;
                        count += 1.0;
                    }
                }
            }
            m1 /= count;
            let sigma = (m2 / count - m1 * m1).max(Vec3::ZERO).powf(0.5);
            let motion = g.motion[at(p)];
            let was = xp + Vec3::new(motion[0], motion[1], motion[2]);
            let hc = hist.view_proj * was.extend(1.0);
            let uv = hc.truncate().truncate() / hc.w * 0.5 + 0.5;
            let qf = (uv * glam::Vec2::new(w as f32, h as f32)).floor();
            let q = IVec2::new(qf.x as i32, qf.y as i32);
            if hc.w > 0.0 && q.x >= 0 && q.y >= 0 && q.x < w && q.y < h {
                let m = hist.meta[at(q)];
                let expected = (was - hist.camera).length();
                let fresh = m[2] == stamp(frame.frame_index.wrapping_sub(1));
                if fresh && (m[0] - expected).abs() < TEMPORAL_DISOCCLUSION * expected {
                    let prev = rgb(hist.color[at(q)]).clamp(m1 - TEMPORAL_GAMMA * sigma, m1 + TEMPORAL_GAMMA * sigma);
                    frames = (m[1] + 1.0).min(max_frames as f32);
                    out_c = prev + (rgb(c) - prev) * (1.0 / frames);
                }
            }
        }
        out[at(p)] = [out_c.x, out_c.y, out_c.z, c[3]];
        meta[at(p)] = [dist, frames, stamp(frame.frame_index), 0.0];
    }
    (out, meta)
}
