//! Reference of `glsl/shared/primary.glsl` (`gbuffer.trace`): what one pixel's primary
//! ray writes into the G-buffer, in the values the targets hold before their storage
//! rounds them (`gbuffer`'s formats: 8-bit sRGB-encoded base colour and roughness,
//! half-float normal and motion).

use super::glossy;
use super::reflect::Triangles;
use super::shading;
use super::texture::{self, TextureArray};
use crate::gpu_types::{FrameUniforms, GpuMaterial, GpuVertex, Hit, Ray};
use crate::shader_defines::{BVH_INVALID, HIT_DYNAMIC, MATERIAL_NONE, TEXTURE_NONE};
use glam::{IVec2, Vec2, Vec3, Vec4, Vec4Swizzles};

/// What the primary rays see: the static triangles, the dynamic ones of this frame with
/// their positions the frame before (by vertex), the materials and the textures.
pub struct PrimaryScene<'a> {
    pub frame: &'a FrameUniforms,
    pub statics: Triangles<'a>,
    pub dynamic: Option<(Triangles<'a>, &'a [GpuVertex])>,
    pub materials: &'a [GpuMaterial],
    pub textures: &'a TextureArray,
}

/// One pixel's G-buffer texels, as the kernel computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// The hit's projected depth (1 for a miss).
    pub depth: f32,
    /// Unit normal facing the viewer, its mirror direction above the facet.
    pub normal: Vec3,
    /// The reflectivity the reflection passes trace (`traced_reflectivity`).
    pub reflectivity: f32,
    /// Linear base colour (the target stores it sRGB-encoded).
    pub base: Vec3,
    pub roughness: f32,
    pub material: u32,
    /// Where the point was the frame before minus where it is.
    pub motion: Vec3,
    pub metallic: f32,
    /// The texture lookups' level of detail (the ray cone's; 0 without textures).
    pub lod: f32,
    /// The hit's texture coordinates (zero without textures).
    pub uv: Vec2,
    /// The hit, as the tracer reports it.
    pub hit: Hit,
}

impl Texel {
    /// The raster's clear values: what a pixel that sees nothing holds.
    pub const MISS: Texel = Texel {
        depth: 1.0,
        normal: Vec3::ZERO,
        reflectivity: 0.0,
        base: Vec3::ZERO,
        roughness: 0.0,
        material: MATERIAL_NONE,
        motion: Vec3::ZERO,
        metallic: 0.0,
        lod: 0.0,
        uv: Vec2::ZERO,
        hit: Hit {
            t: 1.0,
            prim: BVH_INVALID,
            u: 0.0,
            v: 0.0,
        },
    };
}

/// `trace_ray` from `origin` along `dir` for 0 < t < 1 through the static, then the
/// dynamic triangles (a dynamic hit with `HIT_DYNAMIC`).
fn trace(s: &PrimaryScene<'_>, origin: Vec3, dir: Vec3) -> Hit {
    let ray = Ray {
        origin: origin.into(),
        tmin: 0.0,
        dir: dir.into(),
        tmax: 1.0,
    };
    let st = s.statics;
    let hit = st.bvh.trace(&ray, st.vertices, st.indices);
    let Some((d, _)) = &s.dynamic else {
        return hit;
    };
    let dh = d.bvh.trace(&Ray { tmax: hit.t, ..ray }, d.vertices, d.indices);
    match dh.prim {
        BVH_INVALID => hit,
        prim => Hit {
            prim: prim | HIT_DYNAMIC,
            ..dh
        },
    }
}

/// `primary_pixel`: pixel `p`'s texels.
pub fn gbuffer_texel(s: &PrimaryScene<'_>, p: IVec2) -> Texel {
    let frame = s.frame;
    let near = shading::world_from_depth(frame, p, 0.0);
    let dir = shading::world_from_depth(frame, p, 1.0) - near;
    let h = trace(s, near, dir);
    if h.prim == BVH_INVALID {
        return Texel::MISS;
    }
    let (tris, previous) = match (h.prim & HIT_DYNAMIC != 0, &s.dynamic) {
        (false, _) => (s.statics, None),
        (true, Some((d, previous))) => (*d, Some(*previous)),
        (true, None) => unreachable!("a dynamic hit without dynamic triangles"),
    };
    let t = (h.prim & !HIT_DYNAMIC) as usize;
    let corner = |k: usize| tris.indices[3 * t + k] as usize;
    let [a, b, c] = [0, 1, 2].map(|k| tris.vertices[corner(k)]);
    let w = 1.0 - h.u - h.v;
    let bary = |x: Vec3, y: Vec3, z: Vec3| w * x + h.u * y + h.v * z;
    let hp = near + dir * h.t;
    let clip = frame.view_proj * hp.extend(1.0);
    let depth = (clip.z / clip.w).clamp(0.0, 1.0);

    let m = s.materials[a.material as usize];
    let v = (frame.camera_pos.xyz() - hp).normalize();
    let [pa, pb, pc] = [a.position, b.position, c.position].map(Vec3::from);
    let g = (pb - pa).cross(pc - pa);
    let g = if g.dot(v) < 0.0 { -g.normalize() } else { g.normalize() };
    let mut n = bary(a.normal.into(), b.normal.into(), c.normal.into()).normalize();
    if n.dot(v) < 0.0 {
        n = -n;
    }
    if g.is_finite() {
        n = texture::clamp_bent_normal(n, g, v);
    }
    let (mut roughness, mut metallic, mut base) = (m.roughness, m.metallic, Vec3::from(m.albedo));
    let (mut lod, mut uv) = (0.0, Vec2::ZERO);
    if m.texture_layer != TEXTURE_NONE || m.roughness_layer != TEXTURE_NONE {
        let [ta, tb, tc] = [0, 1, 2].map(|k| Vec2::from(tris.uvs[corner(k)]));
        uv = w * ta + h.u * tb + h.v * tc;
        let cone = shading::pixel_spread(frame) * (hp - frame.camera_pos.xyz()).length();
        let cos = g.dot(dir.normalize()).abs();
        lod = texture::ray_cone_lod(cone, cos, [pa, pb, pc], [ta, tb, tc], s.textures.size as f32);
        base = texture::base_color_lod(&m, s.textures, uv, lod);
        if m.roughness_layer != TEXTURE_NONE {
            let t: Vec4 = s.textures.sample_lod(m.roughness_layer, uv, lod);
            roughness *= t.y;
            metallic *= t.z;
        }
    }
    let motion = match previous {
        None => Vec3::ZERO,
        Some(prev) => {
            let [qa, qb, qc] = [0, 1, 2].map(|k| Vec3::from(prev[corner(k)].position));
            bary(qa, qb, qc) - bary(pa, pb, pc)
        }
    };
    Texel {
        depth,
        normal: n,
        reflectivity: glossy::traced_reflectivity(frame, m.reflectivity, roughness),
        base,
        roughness,
        material: a.material,
        motion,
        metallic,
        lod,
        uv,
        hit: h,
    }
}
