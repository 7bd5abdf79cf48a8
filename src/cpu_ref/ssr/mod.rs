//! Reference of `glsl/ssr_classify.comp`, of the march `glsl/ssr_trace.comp`, and of
//! the ray setup they share (`glsl/shared/ssr.glsl`), step for step in f32.

use super::shading::world_from_depth;
use hiz::march_hiz;
use linear::march_linear;

mod hiz;
mod linear;

use crate::gpu_types::FrameUniforms;
use crate::settings::SsrParams;
use crate::shader_defines::{
    FAIL_BACK_FACE, FAIL_BEHIND, FAIL_BLEND, FAIL_FORCED, FAIL_HIT_REFLECTIVE, FAIL_LOW_CONFIDENCE, FAIL_SKIPPED,
    FAIL_UNTRACED, MATERIAL_NONE, TILE_FLIPS_MAX, TILE_FLIPS_SHIFT, TILE_HYSTERESIS, TILE_KNOWN, TILE_ONE,
    TILE_RAYS_ONLY, TILE_SUCCESS,
};
use glam::{IVec2, Mat3, Vec2, Vec2Swizzles, Vec3, Vec4, Vec4Swizzles};

/// The reflected view-space ray of a pixel (`SsrRay`).
#[derive(Clone, Copy, Debug)]
pub struct SsrRay {
    pub vpos: Vec3,
    pub vn: Vec3,
    pub vdir: Vec3,
}

/// `ssr_ray`: pixel `p`'s surface point, normal and reflected direction in view space:
/// the mirror direction, or ray `s` of a glossy surface of perceptual `roughness`.
pub fn ssr_ray(frame: &FrameUniforms, p: IVec2, depth: f32, n_world: Vec3, (roughness, s): (f32, u32)) -> SsrRay {
    let vpos = (frame.view * world_from_depth(frame, p, depth).extend(1.0)).xyz();
    let view = Mat3::from_mat4(frame.view);
    let vn = (view * n_world.normalize()).normalize();
    let vdir = if super::glossy::is_glossy(frame, roughness) {
        let v = view.transpose() * -vpos.normalize();
        let l = super::glossy::glossy_direction(frame, p, n_world.normalize(), v.normalize(), roughness, s);
        (view * l).normalize()
    } else {
        vpos.normalize().reflect(vn).normalize()
    };
    SsrRay { vpos, vn, vdir }
}

/// `heading_confidence`.
pub fn heading_confidence(vdir: Vec3) -> f32 {
    (1.0 - vdir.z).clamp(0.0, 1.0)
}

/// `view_reflection_weight`: the weight of the pixel's own mirror reflection as the
/// camera sees it (reflectivity x Fresnel, the largest channel).
pub fn view_reflection_weight(
    frame: &FrameUniforms,
    ray: &SsrRay,
    n_world: Vec3,
    own: (Vec3, f32),
    reflectivity: f32,
) -> f32 {
    view_reflection(frame, ray, n_world, own, reflectivity).max_element()
}

/// `view_reflection`: that weight per channel.
pub fn view_reflection(
    frame: &FrameUniforms,
    ray: &SsrRay,
    n_world: Vec3,
    (base, metallic): (Vec3, f32),
    reflectivity: f32,
) -> Vec3 {
    let v = Mat3::from_mat4(frame.view).transpose() * -ray.vpos.normalize();
    super::shading::reflection_weight(base, metallic, reflectivity, n_world.normalize(), v)
}

/// `traced_for_block`: whether a weak reflector at `p` is traced for its 2x2 block
/// (its even corner) rather than left untraced.
pub fn traced_for_block(p: IVec2) -> bool {
    (p.x | p.y) & 1 == 0
}

/// `untraced_sky`: the sky in the reflected direction.
pub fn untraced_sky(frame: &FrameUniforms, ray: &SsrRay) -> Vec3 {
    super::shading::sky(frame, Mat3::from_mat4(frame.view).transpose() * ray.vdir)
}

/// What the classification does with a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Class {
    /// Not marched: this fail mask (0: nothing to reflect) and SSR colour (the sky of
    /// an untraced pixel, else 0).
    Done(u32, [f32; 3]),
    /// Appended to the march list.
    March,
}

/// `ssr_classify.comp` for one pixel: G-buffer depth, normal.xyz + reflectivity in w,
/// material id, roughness, and its base colour (linear) and metallic. Also returns the heading
/// confidence and the reflection weight it compared (NaN where none was), so a test
/// can tell pixels on a threshold, where float rounding decides.
pub fn classify(
    frame: &FrameUniforms,
    p: IVec2,
    gbuffer: (f32, [f32; 4], u32, f32),
    own: (Vec3, f32),
    params: &SsrParams,
    mask_only: bool,
) -> (Class, [f32; 2]) {
    classify_in_tile(frame, p, gbuffer, own, params, (mask_only, false))
}

/// `classify` in a tile of the adaptive hybrid: with `skip` (a rays-only tile, not a
/// probe) a pixel that would be marched fails with `FAIL_SKIPPED` instead, and is left
/// untraced as a failed one would be.
pub fn classify_in_tile(
    frame: &FrameUniforms,
    p: IVec2,
    gbuffer: (f32, [f32; 4], u32, f32),
    own: (Vec3, f32),
    params: &SsrParams,
    (mask_only, skip): (bool, bool),
) -> (Class, [f32; 2]) {
    let (depth, nr, material, roughness) = gbuffer;
    let reflective = material != MATERIAL_NONE && nr[3] > params.reflective_min;
    let none = [f32::NAN; 2];
    if mask_only {
        return (Class::Done(if reflective { FAIL_FORCED } else { 0 }, [0.0; 3]), none);
    }
    if !reflective {
        return (Class::Done(0, [0.0; 3]), none);
    }
    let n = Vec3::new(nr[0], nr[1], nr[2]);
    let ray = ssr_ray(frame, p, depth, n, (roughness, 0));
    let h = heading_confidence(ray.vdir);
    if h >= params.min_confidence && !skip {
        return (Class::March, [h, f32::NAN]);
    }
    let reason = if h >= params.min_confidence {
        FAIL_SKIPPED
    } else {
        FAIL_LOW_CONFIDENCE
    };
    if params.trace_min_weight > 0.0 && !traced_for_block(p) {
        let w = view_reflection_weight(frame, &ray, n, own, nr[3]);
        if w < params.trace_min_weight {
            let sky = untraced_sky(frame, &ray).to_array();
            return (Class::Done(reason | FAIL_UNTRACED, sky), [h, w]);
        }
        return (Class::Done(reason, [0.0; 3]), [h, w]);
    }
    (Class::Done(reason, [0.0; 3]), [h, f32::NAN])
}

/// `tile_hysteresis` (`glsl/shared/ssr.glsl`): how far a tile's success must pass the
/// rate `rate` to change its class: a quarter of the rate, within 1..=`TILE_HYSTERESIS`.
pub fn tile_hysteresis(rate: u32) -> u32 {
    (rate / 4).clamp(1, TILE_HYSTERESIS)
}

/// `tile_update` (`glsl/shared/ssr.glsl`): a tile's state after a frame in which
/// `marched` of its pixels were marched and `answered` of them answered by SSR, with
/// the exchange rate `rate` (1/`TILE_ONE`; 0: SSR-first). Integers, as the GPU.
pub fn tile_update(state: u32, marched: u32, answered: u32, rate: u32) -> u32 {
    let mut s = state & TILE_SUCCESS;
    let mut known = state & TILE_KNOWN != 0;
    let was_rays_only = state & TILE_RAYS_ONLY != 0;
    let mut flips = state >> TILE_FLIPS_SHIFT;
    if let Some(share) = (answered * TILE_ONE + marched / 2).checked_div(marched) {
        s = if known { (3 * s + share + 2) / 4 } else { share };
        known = true;
    }
    // SSR-first while unknown or under the SSR-first policy; else across the rate with
    // the hysteresis either way.
    let rays_only = match was_rays_only {
        _ if rate == 0 || !known => false,
        true => s <= rate + tile_hysteresis(rate),
        false => s + tile_hysteresis(rate) < rate,
    };
    if rays_only != was_rays_only {
        flips = (flips + 1).min(TILE_FLIPS_MAX);
    }
    s | if known { TILE_KNOWN } else { 0 } | if rays_only { TILE_RAYS_ONLY } else { 0 } | flips << TILE_FLIPS_SHIFT
}

/// `tile_probe`: whether pixel `p` of a rays-only tile is marched anyway in frame
/// `frame` (one pixel of each 4x4 block, cycling through all sixteen in 16 frames).
pub fn tile_probe(p: IVec2, frame: u32) -> bool {
    (p.x as u32 & 3) == (frame & 3) && (p.y as u32 & 3) == ((frame >> 2) & 3)
}

/// The G-buffer and lit image a march reads, row-major at the frame's resolution.
pub struct MarchInputs<'a> {
    pub depth: &'a [f32],
    /// xyz: world normal; w: reflectivity (as the GPU reads RGBA16F).
    pub normal: &'a [[f32; 4]],
    pub lit: &'a [[f32; 4]],
    /// G-buffer base colour texels (RGBA8, sRGB-encoded rgb) and material ids.
    pub albedo: &'a [u8],
    pub material: &'a [u32],
    /// The G-buffer's metallic per texel (as the GPU reads RGBA16F; 0 on the sky).
    pub metallic: &'a [f32],
    /// The Hi-Z pyramid of `depth` (`hiz`), for the hierarchical march.
    pub pyramid: &'a [Vec<f32>],
}

impl MarchInputs<'_> {
    /// `surface_at`: the base colour (linear) and metallic of the surface at texel `i`
    /// (row-major; metallic 0 where no material is).
    pub fn surface(&self, i: usize) -> (Vec3, f32) {
        (super::albedo_texel(&self.albedo[4 * i..4 * i + 4]).0, self.metallic[i])
    }
}

/// What the march of one pixel writes, and how close it came to deciding otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct March {
    /// The fail mask (0: SSR answered; `FAIL_BLEND`: a faded hit, kept and traced).
    pub fail: u32,
    /// The SSR colour (rgb) and confidence (a; 0 unless the hit is kept).
    pub color: [f32; 4],
    /// The pixel the (last ray's) hit was taken from, if SSR answered.
    pub hit_pixel: Option<IVec2>,
    /// The mean view-space distance to the rays' hits (`ssr.hit_distance`; `HIT_FAR`
    /// where the pixel failed).
    pub hit_distance: f32,
    /// Steps marched (by all of the pixel's rays).
    pub steps: u32,
    /// The smallest relative margin of any comparison the march decided on (a depth
    /// test, the end of the ray, the back-face and confidence tests). Where it is tiny
    /// (a ray grazing a surface), rounding on the GPU may decide the other way.
    pub margin: f32,
    /// The smallest distance (pixels) from a pixel boundary of any position whose
    /// pixel the march looked up: where a step lands on a boundary, rounding may take
    /// the neighbour's depth (a ray grazing a depth edge).
    pub pixel_margin: f32,
    /// The largest spread (a channel's largest less smallest) of the four lit texels a
    /// kept hit's colour interpolates: how far the colour moves per pixel that the hit
    /// position moves (0 where no hit was kept).
    pub lit_spread: f32,
}

/// GLSL `mix`: x (1 - a) + y a, in that order of operations.
fn mix<T>(x: T, y: T, a: f32) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    x * (1.0 - a) + y * a
}

/// GLSL `sign` (0 for 0, unlike `f32::signum`).
fn sign(x: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn swap_if(v: Vec2, permute: bool) -> Vec2 {
    if permute {
        v.yx()
    } else {
        v
    }
}

/// Relative margin of the comparison `a` vs `b`.
fn gap(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1.0)
}

/// Distance of a coordinate from the nearest pixel boundary (where `floor` flips).
fn boundary_gap(x: Vec2) -> f32 {
    let d = |v: f32| (v - v.round()).abs();
    d(x.x).min(d(x.y))
}

/// Reference of `ssr.hiz`: the min-depth pyramid of a `width` x `height` depth image,
/// one `Vec` per level, row-major: level 0 the depth, each next level
/// `ceil(w / 2) x ceil(h / 2)` with texel (x, y) the minimum of texels 2x..2x+1,
/// 2y..2y+1 below it (clamped to that level), the last 1x1.
pub fn hiz(depth: &[f32], width: u32, height: u32) -> Vec<Vec<f32>> {
    let mut levels = vec![depth.to_vec()];
    let (mut w, mut h) = (width as usize, height as usize);
    while (w, h) != (1, 1) {
        let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
        let below = levels.last().expect("level 0");
        let mut level = vec![0.0f32; nw * nh];
        for y in 0..nh {
            for x in 0..nw {
                let (x0, y0) = (2 * x, 2 * y);
                let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
                let at = |x: usize, y: usize| below[y * w + x];
                level[y * nw + x] = at(x0, y0).min(at(x1, y0)).min(at(x0, y1)).min(at(x1, y1));
            }
        }
        levels.push(level);
        (w, h) = (nw, nh);
    }
    levels
}

/// Where a march ended (`Found` in `ssr_trace.comp`): `reason` 0 with the hit's pixel
/// and sub-pixel position, or why it found none.
struct Found {
    reason: u32,
    hit_pixel: IVec2,
    hit_pos: Vec2,
}

/// The decisions' closest calls over a march (see `March`).
struct Margins {
    margin: f32,
    pixel: f32,
    steps: u32,
    lit_spread: f32,
}

/// `ssr_trace.comp` for listed pixel `p`: the reflected ray marched over the depth
/// buffer, through the Hi-Z pyramid or by the linear DDA as `params.hiz` says, then the
/// hit judged (back face, reflective surface, confidence).
pub fn march(frame: &FrameUniforms, p: IVec2, inputs: &MarchInputs<'_>, params: &SsrParams) -> March {
    let res = IVec2::new(frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * res.x + q.x) as usize;
    let nr = inputs.normal[at(p)];
    let n = Vec3::new(nr[0], nr[1], nr[2]);
    let roughness = inputs.albedo[4 * at(p) + 3] as f32 / 255.0;
    let rays = super::glossy::reflection_rays(frame, roughness);
    let mut m = Margins {
        margin: f32::INFINITY,
        pixel: f32::INFINITY,
        steps: 0,
        lit_spread: 0.0,
    };
    // Every ray of the pixel: SSR answers it only if it answers each (the mean colour,
    // the least confidence); the first it cannot answer fails the pixel.
    let (mut fail, mut confidence, mut sum) = (0u32, 1.0f32, Vec3::ZERO);
    let (mut hit_pixel, mut distance_sum) = (None, 0.0f32);
    let mut ray = ssr_ray(frame, p, inputs.depth[at(p)], n, (roughness, 0));
    let mut own = Vec3::ZERO;
    let mut steps = 0;
    for s in 0..rays {
        ray = ssr_ray(frame, p, inputs.depth[at(p)], n, (roughness, s));
        // Each ray has the whole step budget.
        m.steps = 0;
        let found = march_ray(frame, &ray, inputs, params, &mut m);
        steps += m.steps;
        own = view_reflection(frame, &ray, n, inputs.surface(at(p)), nr[3]);
        let (f, c) = judge(frame, &found, (&ray, own), inputs, params, &mut m.margin);
        if f != 0 && f != FAIL_BLEND {
            (fail, sum) = (f, Vec3::ZERO);
            hit_pixel = (found.reason == 0).then_some(found.hit_pixel);
            break;
        }
        fail |= f;
        m.lit_spread = m.lit_spread.max(lit_spread(inputs.lit, found.hit_pos, res));
        confidence = confidence.min(c[3]);
        sum += Vec3::new(c[0], c[1], c[2]);
        hit_pixel = Some(found.hit_pixel);
        let hp = found.hit_pixel;
        let hit = (frame.view * world_from_depth(frame, hp, inputs.depth[at(hp)]).extend(1.0)).xyz();
        distance_sum += (hit - ray.vpos).length();
    }
    let kept = fail == 0 || fail == FAIL_BLEND;
    let mean = if kept { sum / rays as f32 } else { sum };
    let mut color = [mean.x, mean.y, mean.z, if kept { confidence } else { 0.0 }];
    if fail != 0 && params.trace_min_weight > 0.0 {
        let w = own.max_element();
        m.margin = m.margin.min(gap(w, params.trace_min_weight));
        if w < params.trace_min_weight {
            if fail == FAIL_BLEND {
                fail = 0;
            } else if !traced_for_block(p) {
                fail |= FAIL_UNTRACED;
                let sky = untraced_sky(frame, &ray);
                color = [sky.x, sky.y, sky.z, 0.0];
            }
        }
    }
    let kept = fail == 0 || fail == FAIL_BLEND;
    March {
        fail,
        color,
        hit_pixel,
        hit_distance: if kept {
            distance_sum / rays as f32
        } else {
            super::reflect::hit_far()
        },
        steps,
        margin: m.margin,
        pixel_margin: m.pixel,
        lit_spread: m.lit_spread,
    }
}

/// One ray of `ssr_trace.comp`'s march, from just off the surface to its end, through
/// the Hi-Z pyramid or by the linear DDA as `params.hiz` says.
fn march_ray(
    frame: &FrameUniforms,
    ray: &SsrRay,
    inputs: &MarchInputs<'_>,
    params: &SsrParams,
    m: &mut Margins,
) -> Found {
    let proj = frame.proj;
    let vdir = ray.vdir;
    let origin = ray_origin(ray);
    let near_z = -proj.w_axis.z / proj.z_axis.z;
    let max_len = params.max_distance * origin.z.abs();
    let ray_len = if origin.z + vdir.z * max_len > near_z {
        (near_z - origin.z) / vdir.z
    } else {
        max_len
    };
    let end_point = origin + vdir * ray_len;
    let h0 = proj * origin.extend(1.0);
    let h1 = proj * end_point.extend(1.0);
    if params.hiz {
        march_hiz(frame, h0, h1, inputs, params, m)
    } else {
        march_linear(frame, (h0, h1), (origin, end_point), inputs, params, m)
    }
}

/// `view_z` of `ssr_trace.comp`: the view-space z of depth `d`.
fn view_z(frame: &FrameUniforms, d: f32) -> f32 {
    -frame.proj.w_axis.z / (d + frame.proj.z_axis.z)
}

/// `to_pixel`: pixel coordinates of a clip-space point.
fn to_pixel(frame: &FrameUniforms, h: Vec4) -> Vec2 {
    (h.xy() / h.w * 0.5 + 0.5) * Vec2::new(frame.resolution[0] as f32, frame.resolution[1] as f32)
}

/// `SSR_PLANE_PX` of `ssr_trace.comp`: how far (pixels) from the hit position a true
/// hit's ray may cross the plane of the hit pixel's surface.
pub const SSR_PLANE_PX: f32 = 1.0;

/// `ray_origin`: where the march starts, a little off the surface.
fn ray_origin(ray: &SsrRay) -> Vec3 {
    ray.vpos + ray.vn * (1e-3 * ray.vpos.z.abs())
}

/// `plane_crossing`: where (pixels) the ray from `origin` along `vdir` crosses the
/// plane of the surface at pixel `q` (its depth, normal `n`); far off the screen when
/// it runs along it.
fn plane_crossing(frame: &FrameUniforms, (origin, vdir): (Vec3, Vec3), q: IVec2, depth: f32, n: Vec3) -> Vec2 {
    let hv = (frame.view * world_from_depth(frame, q, depth).extend(1.0)).xyz();
    let vn = Mat3::from_mat4(frame.view) * n;
    let along = vn.dot(vdir);
    if along.abs() < 1e-6 {
        return Vec2::splat(-1e9);
    }
    let s = vn.dot(hv - origin) / along;
    to_pixel(frame, frame.proj * (origin + vdir * s).extend(1.0))
}

/// `judge`: the fail mask and colour (rgb) + confidence (a) of a march's outcome.
fn judge(
    frame: &FrameUniforms,
    found: &Found,
    (ray, own): (&SsrRay, Vec3),
    inputs: &MarchInputs<'_>,
    params: &SsrParams,
    margin: &mut f32,
) -> (u32, [f32; 4]) {
    let vdir = ray.vdir;
    let res = IVec2::new(frame.resolution[0] as i32, frame.resolution[1] as i32);
    let at = |q: IVec2| (q.y * res.x + q.x) as usize;
    let (mut confidence, mut color) = (0.0, Vec3::ZERO);
    let fail = if found.reason != 0 {
        found.reason
    } else {
        let hit_pixel = found.hit_pixel;
        let hit_nr = inputs.normal[at(hit_pixel)];
        let hit_n = Vec3::new(hit_nr[0], hit_nr[1], hit_nr[2]).normalize();
        let world_dir = Mat3::from_mat4(frame.view).transpose() * vdir;
        *margin = margin.min(hit_n.dot(world_dir).abs());
        // Where the ray crosses the hit surface's plane, against where it found the hit
        // (decided on a front face SSR may answer; its margin counted on every front face).
        let crossing = plane_crossing(
            frame,
            (ray_origin(ray), vdir),
            hit_pixel,
            inputs.depth[at(hit_pixel)],
            hit_n,
        )
        .distance(found.hit_pos);
        if hit_n.dot(world_dir) <= 0.0 {
            *margin = margin.min(gap(crossing, SSR_PLANE_PX));
        }
        // `hit_reflection_weight`: the hit surface's own reflection seen along the ray,
        // as the pixel shows it.
        let mut own_reflection = |q: IVec2, n: Vec3| {
            let (base, metallic) = inputs.surface(at(q));
            let w = (own * super::shading::reflection_weight(base, metallic, hit_nr[3], n, -world_dir)).max_element();
            *margin = margin.min(gap(w, params.recursion_min));
            w
        };
        if hit_n.dot(world_dir) > 0.0 {
            FAIL_BACK_FACE
        } else if own_reflection(hit_pixel, hit_n) > params.recursion_min {
            FAIL_HIT_REFLECTIVE
        } else if crossing > SSR_PLANE_PX {
            FAIL_BEHIND
        } else {
            let hp = hit_pixel.as_vec2() + 0.5;
            let edge = hp.x.min(res.x as f32 - hp.x).min(hp.y.min(res.y as f32 - hp.y));
            let fade_px = (params.edge_fade * res.x.min(res.y) as f32).max(1.0);
            confidence = (edge / fade_px).clamp(0.0, 1.0) * heading_confidence(vdir);
            *margin = margin.min(gap(confidence, params.min_confidence));
            if confidence < params.min_confidence {
                FAIL_LOW_CONFIDENCE
            } else {
                color = lit_bilinear(inputs.lit, found.hit_pos, res);
                if confidence < 1.0 {
                    FAIL_BLEND
                } else {
                    0
                }
            }
        }
    };
    let kept = fail == 0 || fail == FAIL_BLEND;
    (fail, [color.x, color.y, color.z, if kept { confidence } else { 0.0 }])
}

/// The largest channel spread of the four lit texels `lit_bilinear` weighs at `x`.
fn lit_spread(lit: &[[f32; 4]], x: Vec2, res: IVec2) -> f32 {
    let i0 = (x - 0.5).floor().as_ivec2();
    let c = |d: IVec2| {
        let q = (i0 + d).clamp(IVec2::ZERO, res - 1);
        Vec4::from(lit[(q.y * res.x + q.x) as usize]).xyz()
    };
    let t = [c(IVec2::ZERO), c(IVec2::X), c(IVec2::Y), c(IVec2::ONE)];
    let (lo, hi) = t.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(*v), hi.max(*v))
    });
    (hi - lo).max_element()
}

/// The lit colour at sub-pixel position `x` (texel centres at +0.5), bilinear, edges
/// clamped.
fn lit_bilinear(lit: &[[f32; 4]], x: Vec2, res: IVec2) -> Vec3 {
    let t = x - 0.5;
    let i0 = t.floor().as_ivec2();
    let f = t - i0.as_vec2();
    let lo = i0.clamp(IVec2::ZERO, res - 1);
    let hi = (i0 + 1).clamp(IVec2::ZERO, res - 1);
    let c = |q: IVec2| Vec4::from(lit[(q.y * res.x + q.x) as usize]).xyz();
    let (c00, c10) = (c(lo), c(IVec2::new(hi.x, lo.y)));
    let (c01, c11) = (c(IVec2::new(lo.x, hi.y)), c(hi));
    mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tile turns rays-only below the rate less the hysteresis and back above it plus
    /// the hysteresis, each change counted in its flips (which hold at their end).
    #[test]
    fn tile_update_turns_with_hysteresis_and_counts_flips() {
        let rate = 128;
        let flips = |s: u32| s >> TILE_FLIPS_SHIFT;
        // Known at 0.5 success: SSR-first; 30 of 64 answered keeps it (within the band).
        let s = tile_update(0, 64, 32, rate);
        assert_eq!((s & TILE_RAYS_ONLY, flips(s)), (0, 0));
        let s = tile_update(s, 64, 30, rate);
        assert_eq!((s & TILE_RAYS_ONLY, flips(s)), (0, 0), "{s:#x}");
        // Nothing answered: the success falls below 128 - 16, rays-only, one flip.
        let s = tile_update(s, 64, 0, rate);
        assert_eq!((s & TILE_RAYS_ONLY != 0, flips(s)), (true, 1), "{s:#x}");
        // No probe marched: it keeps its class and count.
        assert_eq!(tile_update(s, 0, 0, rate), s);
        // Everything answered twice: back to SSR-first, two flips.
        let s = tile_update(tile_update(s, 64, 64, rate), 64, 64, rate);
        assert_eq!((s & TILE_RAYS_ONLY, flips(s)), (0, 2), "{s:#x}");
        // The count holds at its end.
        let full = s | TILE_FLIPS_MAX << TILE_FLIPS_SHIFT;
        assert_eq!(flips(tile_update(full, 64, 0, rate)), TILE_FLIPS_MAX);
    }
}
