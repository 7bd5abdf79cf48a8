//! Reference of the hierarchical march (`march_hiz` in `glsl/ssr_trace.comp`): the ray
//! walks the Hi-Z pyramid, a cell at a time.

use super::{boundary_gap, gap, to_pixel, view_z, Found, MarchInputs, Margins};
use crate::gpu_types::FrameUniforms;
use crate::settings::SsrParams;
use crate::shader_defines::{FAIL_BEHIND, FAIL_LEFT_SCREEN, FAIL_OUT_OF_STEPS};
use glam::{IVec2, Vec2, Vec3, Vec3Swizzles, Vec4};

/// `HIZ_NUDGE`, `NO_PLANE` of `ssr_trace.comp`.
const HIZ_NUDGE: f32 = 0.005;
const NO_PLANE: f32 = 3.0e38;

/// `march_hiz`: the hierarchical march through the min-depth pyramid
/// (`inputs.pyramid`, `hiz`'s levels), step for step.
// Long: it mirrors `march_hiz` in `ssr_trace.comp` line by line.
pub(super) fn march_hiz(
    frame: &FrameUniforms,
    h0: Vec4,
    h1: Vec4,
    inputs: &MarchInputs<'_>,
    params: &SsrParams,
    m: &mut Margins,
) -> Found {
    let res = IVec2::new(frame.resolution[0] as i32, frame.resolution[1] as i32);
    let pyramid = inputs.pyramid;
    assert!(!pyramid.is_empty(), "the Hi-Z march needs the pyramid");
    let s0 = to_pixel(frame, h0).extend(h0.z / h0.w);
    let s1 = to_pixel(frame, h1).extend(h1.z / h1.w);
    let dir = s1 - s0;
    let t_end = if s1.z > 1.0 { (1.0 - s0.z) / dir.z } else { 1.0 };
    let inv1 = |d: f32| if d.abs() > 1e-20 { 1.0 / d } else { NO_PLANE };
    let inv = Vec3::new(inv1(dir.x), inv1(dir.y), inv1(dir.z));
    let side = Vec2::new(
        if dir.x >= 0.0 { 1.0 } else { 0.0 },
        if dir.y >= 0.0 { 1.0 } else { 0.0 },
    );
    let nudge = Vec2::new(
        if dir.x >= 0.0 { HIZ_NUDGE } else { -HIZ_NUDGE },
        if dir.y >= 0.0 { HIZ_NUDGE } else { -HIZ_NUDGE },
    );
    let t0 = (s0.xy().floor() + side + nudge - s0.xy()) * inv.xy();
    let mut t = t0.x.min(t0.y);
    let mut pos = s0 + dir * t;
    let top = pyramid.len() - 1;
    let mut mip = 0usize;
    let mut found = Found {
        reason: FAIL_OUT_OF_STEPS,
        hit_pixel: IVec2::splat(-1),
        hit_pos: Vec2::splat(-1.0),
    };
    let resf = res.as_vec2();
    while m.steps < params.max_steps {
        m.margin = m.margin.min(gap(t, t_end));
        // Distances from the screen's edges are boundary distances too.
        m.pixel = m.pixel.min(boundary_gap(pos.xy()));
        if t > t_end || pos.x < 0.0 || pos.y < 0.0 || pos.x >= resf.x || pos.y >= resf.y {
            found.reason = FAIL_LEFT_SCREEN;
            break;
        }
        let size_x = (res.x as u32).div_ceil(1 << mip);
        let cell = (pos.x as u32 >> mip, pos.y as u32 >> mip);
        let surface = pyramid[mip][(cell.1 * size_x + cell.0) as usize];
        let planes = (Vec2::new(cell.0 as f32, cell.1 as f32) + side) * (1u32 << mip) as f32 + nudge;
        let txy = (planes - s0.xy()) * inv.xy();
        let tz = if surface < 1.0 && dir.z > 0.0 {
            (surface - s0.z) * inv.z
        } else {
            NO_PLANE
        };
        let t_min = txy.x.min(txy.y).min(tz);
        m.margin = m.margin.min(gap(pos.z, surface));
        let above = pos.z < surface;
        if above {
            // Whether the surface's depth or a side is reached first.
            m.margin = m.margin.min(gap(tz, txy.x.min(txy.y)));
            t = t_min;
            pos = s0 + dir * t;
        }
        m.steps += 1;
        if above && t_min != tz {
            mip = (mip + 1).min(top);
        } else if mip > 0 {
            mip -= 1;
        } else {
            let p = IVec2::new(cell.0 as i32, cell.1 as i32);
            let depth = pyramid[0][(p.y * res.x + p.x) as usize];
            let scene_z = view_z(frame, depth);
            let ray_z = view_z(frame, pos.z);
            let mut thickness = params.thickness * scene_z.abs();
            if !above {
                // Entered behind the surface: within about a pixel of the ray only.
                let t_px = 1.0 / dir.x.abs().max(dir.y.abs());
                let near = 2.0 * (view_z(frame, s0.z + dir.z * (t + t_px)) - ray_z).abs();
                m.margin = m.margin.min(gap(near, thickness));
                thickness = thickness.min(near);
            }
            let limit = scene_z - thickness;
            m.margin = m.margin.min(gap(ray_z, limit));
            m.pixel = m.pixel.min(boundary_gap(pos.xy()));
            if depth >= 1.0 {
                found.reason = FAIL_LEFT_SCREEN;
            } else if ray_z < limit {
                found.reason = FAIL_BEHIND;
            } else {
                found = Found {
                    reason: 0,
                    hit_pixel: p,
                    hit_pos: pos.xy(),
                };
            }
            break;
        }
    }
    found
}
