//! Reference of the linear march (`march_linear` in `glsl/ssr_trace.comp`): the
//! perspective-correct DDA of McGuire & Mara 2014, the hit refined by binary search and a secant.

use super::{boundary_gap, gap, mix, sign, swap_if, to_pixel, view_z, Found, MarchInputs, Margins};
use crate::gpu_types::FrameUniforms;
use crate::settings::SsrParams;
use crate::shader_defines::{FAIL_BEHIND, FAIL_LEFT_SCREEN, FAIL_OUT_OF_STEPS, SSR_REFINE_STEPS};
use glam::{IVec2, Vec2, Vec2Swizzles, Vec3, Vec4};

/// `march_linear`: the perspective-correct DDA (McGuire & Mara 2014), the hit refined
/// by binary search and a secant.
// Long: it mirrors `march_linear` in `ssr_trace.comp` line by line.
pub(super) fn march_linear(
    frame: &FrameUniforms,
    (h0, h1): (Vec4, Vec4),
    (origin, end_point): (Vec3, Vec3),
    inputs: &MarchInputs<'_>,
    params: &SsrParams,
    m: &mut Margins,
) -> Found {
    let res = IVec2::new(frame.resolution[0] as i32, frame.resolution[1] as i32);
    let depth_at = |q: IVec2| inputs.depth[(q.y * res.x + q.x) as usize];
    let view_z = |d: f32| view_z(frame, d);
    let (k0, k1) = (1.0 / h0.w, 1.0 / h1.w);
    let (q0, q1) = (origin * k0, end_point * k1);
    let (mut p0, mut p1) = (to_pixel(frame, h0), to_pixel(frame, h1));
    if (p1 - p0).dot(p1 - p0) < 1e-4 {
        p1 += Vec2::splat(0.01);
    }
    let mut delta = p1 - p0;
    let permute = delta.x.abs() < delta.y.abs();
    if permute {
        delta = delta.yx();
        p0 = p0.yx();
        p1 = p1.yx();
    }
    let step_dir = sign(delta.x);
    let invdx = step_dir / delta.x;
    let dq = (q1 - q0) * invdx * params.stride;
    let dk = (k1 - k0) * invdx * params.stride;
    let dp = Vec2::new(step_dir, delta.y * invdx) * params.stride;
    let mut pp = p0 + dp;
    let mut qz = q0.z + dq.z;
    let mut k = k0 + dk;
    let end = p1.x * step_dir;
    let mut prev_z = (q0.z + 0.5 * dq.z) / (k0 + 0.5 * dk);
    let (mut went_behind, mut hit) = (false, false);
    let mut found = Found {
        reason: 0,
        hit_pixel: IVec2::splat(-1),
        hit_pos: Vec2::splat(-1.0),
    };
    while pp.x * step_dir <= end && m.steps < params.max_steps {
        m.margin = m.margin.min(gap(pp.x * step_dir, end));
        let px = swap_if(pp, permute);
        m.pixel = m.pixel.min(boundary_gap(px));
        let ip = px.floor().as_ivec2();
        if ip.cmplt(IVec2::ZERO).any() || ip.cmpge(res).any() {
            break;
        }
        let mut ray_z_min = prev_z;
        let mut ray_z_max = (dq.z * 0.5 + qz) / (dk * 0.5 + k);
        prev_z = ray_z_max;
        if ray_z_min > ray_z_max {
            std::mem::swap(&mut ray_z_min, &mut ray_z_max);
        }
        let scene_depth = depth_at(ip);
        if scene_depth < 1.0 {
            let scene_z_max = view_z(scene_depth);
            let scene_z_min = scene_z_max - params.thickness * scene_z_max.abs();
            m.margin = m
                .margin
                .min(gap(ray_z_max, scene_z_min))
                .min(gap(ray_z_min, scene_z_max));
            if ray_z_max >= scene_z_min && ray_z_min <= scene_z_max {
                hit = true;
                found.hit_pixel = ip;
                found.hit_pos = px;
                break;
            }
            if ray_z_max < scene_z_min {
                went_behind = true;
                break;
            }
        }
        pp += dp;
        qz += dq.z;
        k += dk;
        m.steps += 1;
    }
    if !hit {
        let left = m.steps < params.max_steps;
        found.reason = if went_behind {
            FAIL_BEHIND
        } else if left {
            FAIL_LEFT_SCREEN
        } else {
            FAIL_OUT_OF_STEPS
        };
        return found;
    }
    if params.stride > 1.0 {
        let (mut a_p, mut b_p) = (pp - dp, pp);
        let (mut a_qz, mut b_qz) = (qz - dq.z, qz);
        let (mut a_k, mut b_k) = (k - dk, k);
        let clamp_px = |v: Vec2| v.floor().as_ivec2().clamp(IVec2::ZERO, res - 1);
        for _ in 0..SSR_REFINE_STEPS {
            let m_p = 0.5 * (a_p + b_p);
            let m_qz = 0.5 * (a_qz + b_qz);
            let m_k = 0.5 * (a_k + b_k);
            m.pixel = m.pixel.min(boundary_gap(swap_if(m_p, permute)));
            let d = depth_at(clamp_px(swap_if(m_p, permute)));
            if d < 1.0 {
                m.margin = m.margin.min(gap(m_qz / m_k, view_z(d)));
            }
            if d < 1.0 && m_qz / m_k <= view_z(d) {
                (b_p, b_qz, b_k) = (m_p, m_qz, m_k);
            } else {
                (a_p, a_qz, a_k) = (m_p, m_qz, m_k);
            }
        }
        let (pa, pb) = (swap_if(a_p, permute), swap_if(b_p, permute));
        let za = depth_at(clamp_px(pa));
        let zb = depth_at(clamp_px(pb));
        let gap_a = a_qz / a_k - view_z(za);
        let gap_b = b_qz / b_k - view_z(zb);
        // `gap_a > 0` decides whether the secant is used at all.
        m.margin = m.margin.min(gap(a_qz / a_k, view_z(za)));
        let f = if za < 1.0 && gap_a > 0.0 {
            (gap_a / (gap_a - gap_b)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        found.hit_pos = mix(pa, pb, f);
        m.pixel = m.pixel.min(boundary_gap(found.hit_pos));
        found.hit_pixel = found.hit_pos.floor().as_ivec2().clamp(IVec2::ZERO, res - 1);
    }
    found
}
