//! Reference of `glsl/rt_reflect.comp` (`rt.reflect`): one pixel's
//! reflected path through the scene, shaded as the kernel shades it.

use super::glossy;
use super::shading::{self, ShadowMap};
use super::texture::{self, TextureArray};
use super::trace::CpuBvh;
use crate::gpu_types::{FrameUniforms, GpuMaterial, GpuVertex, Hit, Ray};
use crate::settings::Shadows;
use crate::shader_defines::{BVH_INVALID, HIT_DYNAMIC};
use glam::{IVec2, Vec2, Vec3, Vec4Swizzles};

/// Triangles with their BVH and texture coordinates: the static scene, or the dynamic
/// geometry of one frame (world space).
#[derive(Clone, Copy)]
pub struct Triangles<'a> {
    pub bvh: &'a CpuBvh,
    pub vertices: &'a [GpuVertex],
    pub indices: &'a [u32],
    pub uvs: &'a [[f32; 2]],
}

/// What the path sees: the scene's triangles (one static BVH over them), their
/// texture coordinates, materials and textures, the dynamic geometry if any, and the
/// shadow map (unless shadows come from rays).
pub struct PathScene<'a> {
    pub frame: &'a FrameUniforms,
    pub bvh: &'a CpuBvh,
    pub vertices: &'a [GpuVertex],
    pub indices: &'a [u32],
    pub uvs: &'a [[f32; 2]],
    pub materials: &'a [GpuMaterial],
    pub textures: &'a TextureArray,
    pub shadow_map: &'a ShadowMap<'a>,
    /// How the visible surface and the hits are shadowed (the `shadows` setting).
    pub shadows: Shadows,
    /// The dynamic triangles, traced after the static ones (a tie goes to the static
    /// triangle, as in the kernel); their hits carry `HIT_DYNAMIC`.
    pub dynamic: Option<Triangles<'a>>,
}

/// `offset_scale`: how far a ray's origin is pushed off its surface at `pos`.
pub fn offset_scale(frame: &FrameUniforms, pos: Vec3) -> f32 {
    2e-4 * (pos - frame.camera_pos.xyz()).length().max(1.0)
}

/// `trace_ray` through the static then the dynamic triangles: the closest hit, a
/// dynamic one with `HIT_DYNAMIC` set.
pub fn trace_scene(s: &PathScene<'_>, origin: Vec3, dir: Vec3) -> Hit {
    let ray = Ray {
        origin: origin.into(),
        tmin: 0.0,
        dir: dir.into(),
        tmax: 3.0e38,
    };
    let hit = s.bvh.trace(&ray, s.vertices, s.indices);
    match &s.dynamic {
        Some(d) => {
            let closer = Ray { tmax: hit.t, ..ray };
            let dh = d.bvh.trace(&closer, d.vertices, d.indices);
            if dh.prim == BVH_INVALID {
                hit
            } else {
                Hit {
                    prim: dh.prim | HIT_DYNAMIC,
                    ..dh
                }
            }
        }
        None => hit,
    }
}

/// A shadow ray from `pos`, pushed off along `n`, toward the sun: 1 when nothing is in
/// the way, else 0.
pub fn shadow_ray(s: &PathScene<'_>, pos: Vec3, n: Vec3) -> f32 {
    let origin = pos + n * offset_scale(s.frame, pos);
    if trace_scene(s, origin, s.frame.light_dir.xyz()).prim == BVH_INVALID {
        1.0
    } else {
        0.0
    }
}

/// The reflected radiance of pixel `p` (G-buffer depth, world normal as stored,
/// perceptual roughness): the mirror path, or the mean of a glossy pixel's paths
/// (`glossy::glossy_direction`), each of up to `max_bounces` rays; the number of rays
/// traced, and the mean distance to the paths' first hits (`HIT_FAR` for a miss).
pub fn reflected_radiance(
    s: &PathScene<'_>,
    p: IVec2,
    (depth, normal, roughness): (f32, Vec3, f32),
    max_bounces: u32,
) -> (Vec3, u32, f32) {
    let frame = s.frame;
    let pos = shading::world_from_depth(frame, p, depth);
    let n = normal.normalize();
    let view_dir = (pos - frame.camera_pos.xyz()).normalize();
    let origin = pos + n * offset_scale(frame, pos);
    let spread = shading::pixel_spread(frame);
    let cone = spread * (pos - frame.camera_pos.xyz()).length();
    if !glossy::is_glossy(frame, roughness) {
        return trace_path(s, (origin, view_dir.reflect(n)), (cone, spread), max_bounces);
    }
    let rays = glossy::reflection_rays(frame, roughness);
    let (mut radiance, mut traced, mut first) = (Vec3::ZERO, 0, 0.0);
    for k in 0..rays {
        let dir = glossy::glossy_direction(frame, p, n, -view_dir, roughness, k);
        let (l, t, f) = trace_path(s, (origin, dir), (cone, spread), max_bounces);
        radiance += l;
        traced += t;
        first += f.min(hit_far());
    }
    (radiance / rays as f32, traced, first / rays as f32)
}

/// `HIT_FAR`: the hit distance of a miss.
pub fn hit_far() -> f32 {
    f32::from_bits(crate::shader_defines::HIT_FAR)
}

/// `trace_path`: the radiance one path from `origin` in direction `dir` gathers in up
/// to `max_bounces` rays (its ray cone `cone` wide at the origin, spreading by
/// `spread`), the rays traced and the distance to its first hit.
fn trace_path(
    s: &PathScene<'_>,
    (mut origin, mut dir): (Vec3, Vec3),
    (mut cone, spread): (f32, f32),
    max_bounces: u32,
) -> (Vec3, u32, f32) {
    let frame = s.frame;
    let trace = |origin: Vec3, dir: Vec3| trace_scene(s, origin, dir);
    let statics = Triangles {
        bvh: s.bvh,
        vertices: s.vertices,
        indices: s.indices,
        uvs: s.uvs,
    };
    let mut first = hit_far();
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let mut rays = 0;
    for bounce in 0..max_bounces {
        rays += 1;
        let h = trace(origin, dir);
        if h.prim == BVH_INVALID {
            radiance += throughput * shading::sky(frame, dir);
            break;
        }
        if bounce == 0 {
            first = h.t;
        }
        let tris = if h.prim & HIT_DYNAMIC != 0 {
            s.dynamic.expect("a dynamic hit needs dynamic triangles")
        } else {
            statics
        };
        let prim = (h.prim & !HIT_DYNAMIC) as usize;
        let index = |k: usize| tris.indices[3 * prim + k] as usize;
        let corner = |k: usize| &tris.vertices[index(k)];
        let (a, b, c) = (corner(0), corner(1), corner(2));
        let m = &s.materials[a.material as usize];
        let p = [a, b, c].map(|v| Vec3::from(v.position));
        let mut g = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        if g.dot(dir) > 0.0 {
            g = -g;
        }
        cone += spread * h.t;
        let mut albedo = Vec3::from(m.albedo);
        if m.texture_layer != crate::shader_defines::TEXTURE_NONE {
            let t = [0, 1, 2].map(|k| Vec2::from(tris.uvs[index(k)]));
            let uv = (1.0 - h.u - h.v) * t[0] + h.u * t[1] + h.v * t[2];
            let lod = texture::ray_cone_lod(cone, g.dot(dir).abs(), p, t, s.textures.size as f32);
            albedo = texture::base_color_lod(m, s.textures, uv, lod);
        }
        let mut hn =
            ((1.0 - h.u - h.v) * Vec3::from(a.normal) + h.u * Vec3::from(b.normal) + h.v * Vec3::from(c.normal))
                .normalize();
        if hn.dot(dir) > 0.0 {
            hn = -hn;
        }
        hn = texture::clamp_bent_normal(hn, g, -dir);
        let hp = origin + dir * h.t;
        let vis = if s.shadows == Shadows::Map {
            shading::shadow_visibility(frame, s.shadow_map, hp)
        } else {
            let ndl = hn.dot(frame.light_dir.xyz());
            match shading::shadow_ray_reasons(frame, s.shadow_map, hp, ndl, s.shadows) {
                (0, vis) => vis,
                _ => shadow_ray(s, hp, g),
            }
        };
        // Past the rough cut-off a hit reflects only the prefiltered sky.
        let reflectivity = glossy::traced_reflectivity(frame, m.reflectivity, m.roughness);
        let surface = shading::Surface {
            base: albedo,
            roughness: m.roughness,
            reflectivity,
            metallic: m.metallic,
        };
        radiance += throughput * shading::shade_direct(frame, surface, hn, -dir, vis);
        if reflectivity <= 0.0 {
            break;
        }
        throughput *= shading::reflection_weight(albedo, m.metallic, reflectivity, hn, -dir);
        dir = dir.reflect(hn);
        origin = hp + g * offset_scale(frame, hp);
    }
    (radiance, rays, first)
}
