//! Structs shared by Rust and GLSL (`glsl/shared/types.glsl`). Each is `#[repr(C)]`
//! and Pod; padding is named `_padN`; sizes are asserted here and member offsets are
//! checked against the compiled SPIR-V by `tests/suite/layout.rs`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};

/// One vertex in world space, pulled by the vertex shaders from a storage buffer
/// (std430, 32 bytes). Later passes (BVH, ray tracing) read the same buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVertex {
    pub position: [f32; 3],
    /// Index into the material buffer.
    pub material: u32,
    /// Unit normal.
    pub normal: [f32; 3],
    /// Dynamic geometry: the index of the body the vertex belongs to (its transform in
    /// `sim.transform`); 0 in static geometry.
    pub object: u32,
}

/// A skinned vertex's influences (std430, 32 bytes): four joint indices, 16 bits each,
/// two to a `u32` (low half first), and their weights (divided by their sum).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuInfluence {
    pub joints: [u32; 2],
    pub pad: [u32; 2],
    pub weights: [f32; 4],
}

impl GpuInfluence {
    pub fn new(joints: [u16; 4], weights: [f32; 4]) -> Self {
        let pack = |a: u16, b: u16| a as u32 | (b as u32) << 16;
        Self {
            joints: [pack(joints[0], joints[1]), pack(joints[2], joints[3])],
            pad: [0; 2],
            weights,
        }
    }

    pub fn joint_indices(&self) -> [u16; 4] {
        let [a, b] = self.joints;
        [a as u16, (a >> 16) as u16, b as u16, (b >> 16) as u16]
    }
}

/// A material (std430, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Linear RGB diffuse albedo in [0, 1].
    pub albedo: [f32; 3],
    /// Perceptual roughness in [0, 1]: 0 is a perfect mirror.
    pub roughness: f32,
    /// Fraction of light reflected specularly in [0, 1] (used by reflection passes).
    pub reflectivity: f32,
    /// Layer of the scene's texture array multiplying `albedo`, or `TEXTURE_NONE`.
    pub texture_layer: u32,
    /// 0: dielectric (specular reflectance 0.04), 1: metal (reflectance = `albedo`).
    pub metallic: f32,
    /// Layer of the scene's texture array whose green channel (linear data) multiplies
    /// `roughness`, or `TEXTURE_NONE`.
    pub roughness_layer: u32,
}

/// Per-frame constants (std140 uniform buffer, 464 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// World → clip of the camera (Vulkan clip space: y down, depth 0..1).
    pub view_proj: Mat4,
    pub inv_view_proj: Mat4,
    /// World → clip of the shadow-casting light.
    pub light_view_proj: Mat4,
    /// World → view of the camera (right-handed, looking down -z).
    pub view: Mat4,
    /// View → clip of the camera.
    pub proj: Mat4,
    /// xyz: camera position in world units; w unused.
    pub camera_pos: Vec4,
    /// xyz: unit vector from a surface towards the light; w unused.
    pub light_dir: Vec4,
    /// rgb: light radiance (colour × intensity); w unused.
    pub light_color: Vec4,
    /// rgb: sky colour straight up; w unused.
    pub sky_zenith: Vec4,
    /// rgb: sky colour at the horizon; w unused.
    pub sky_horizon: Vec4,
    /// Render target size in pixels.
    pub resolution: [u32; 2],
    /// Shadow map edge in texels.
    pub shadow_map_size: u32,
    /// PCF kernel radius in texels: (2r+1)^2 bilinear taps.
    pub pcf_radius: u32,
    /// Depth bias (in light clip-space depth units) subtracted before the compare.
    pub shadow_bias: f32,
    /// Exposure multiplier applied before tonemapping.
    pub exposure: f32,
    /// Strength of the hemispherical sky ambient term.
    pub ambient: f32,
    /// Light clip-space depth distance from the biased compare within which a shadow-map
    /// texel leaves the map unsure (`shadow_map_doubt`): the pixel gets a shadow ray in
    /// the hybrid shadows.
    pub shadow_band: f32,
    /// Frames rendered before this one: the glossy rays' sample sequence advances with it.
    pub frame_index: u32,
    /// Sampled reflection rays per glossy pixel (`reflection_rays`).
    pub reflection_rays: u32,
    /// Perceptual roughness below which a reflective surface is a mirror (`glossy_mirror_max`).
    pub mirror_roughness: f32,
    /// Perceptual roughness from which a surface gets no traced reflection, only the
    /// prefiltered sky (`glossy_rough_max`).
    pub rough_roughness: f32,
    /// Which sample stream the glossy rays draw (0: the renderer's; references use another
    /// so that they are independent of the frames they judge).
    pub sample_stream: u32,
    /// 1: glossy reflections (`glossy`); 0: every reflective surface a mirror, as before
    /// glossy tracing, and neither roughness cut-off applies.
    pub glossy: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

const _: () = assert!(std::mem::size_of::<GpuVertex>() == 32);
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 32);
const _: () = assert!(std::mem::size_of::<GpuInfluence>() == 32);
const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 464);

/// An internal node of the BVH (std430, 64 bytes; `glsl/shared/bvh.glsl`) with both
/// children's boxes, so one fetch tests both. `child0`/`child1`: an internal node's
/// slot, or a leaf (`bvh_leaf_link`: its triangles' range in `TraversalTri` order).
/// `parent`:
/// `slot << 1 | side` of the parent's half holding this node's box (`BVH_INVALID` at
/// the root, slot 0). `unused` is never written. The fit writes N-1 of them (one for a
/// single triangle, whose two children are that leaf). The static BVH's walk reads the
/// 32-byte compact nodes made from these (`lbvh.compact`) instead.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraversalNode {
    pub lo0: [f32; 3],
    pub child0: u32,
    pub hi0: [f32; 3],
    pub child1: u32,
    pub lo1: [f32; 3],
    pub parent: u32,
    pub hi1: [f32; 3],
    pub unused: u32,
}

/// A rigid body of a rigid-body rebuild (`tracers::lbvh::rigid`; std430, 16 bytes): the
/// center of its object-space box and how many triangles it has.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RigidBody {
    pub center: [f32; 3],
    pub tri_count: u32,
}

/// A triangle of the BVH (std430, 48 bytes), in leaf order: its corners `a`, `b`, `c` as
/// the scene's vertices hold them (the watertight ray test projects each corner on its
/// own, so triangles sharing an edge see the same edge), the scene's triangle id, and
/// the link to its box's half of the parent node (as `TraversalNode::parent`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraversalTri {
    pub a: [f32; 3],
    pub id: u32,
    pub b: [f32; 3],
    pub parent: u32,
    pub c: [f32; 3],
    pub _pad0: u32,
}

/// The child link of a BVH leaf of `count` triangles from leaf position `first`.
pub fn bvh_leaf_link(first: u32, count: u32) -> u32 {
    use crate::shader_defines::{BVH_LEAF_BIT, BVH_LEAF_COUNT_SHIFT};
    BVH_LEAF_BIT | (count - 1) << BVH_LEAF_COUNT_SHIFT | first
}

/// A BVH child link's leaf range (first triangle, count), or `None` for an internal
/// node's slot.
pub fn bvh_leaf(link: u32) -> Option<(u32, u32)> {
    use crate::shader_defines::{BVH_LEAF_BIT, BVH_LEAF_COUNT_SHIFT};
    (link & BVH_LEAF_BIT != 0).then(|| {
        (
            link & ((1 << BVH_LEAF_COUNT_SHIFT) - 1),
            ((link & !BVH_LEAF_BIT) >> BVH_LEAF_COUNT_SHIFT) + 1,
        )
    })
}

/// A BVH as the GPU holds it, read back: the internal nodes by slot and the triangles
/// in leaf order (`glsl/shared/bvh.glsl`).
#[derive(Clone, Debug, PartialEq)]
pub struct PackedBvh {
    pub nodes: Vec<TraversalNode>,
    pub tris: Vec<TraversalTri>,
}

/// A ray for `rt.trace` (std430, 32 bytes). Hits count for `tmin < t < tmax`, with t
/// in units of `dir`'s length.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

impl Ray {
    /// The ray from `origin` through `target` (reached at t = 1), every hit ahead of
    /// the origin counted.
    pub fn through(origin: glam::Vec3, target: glam::Vec3) -> Self {
        Self {
            origin: origin.to_array(),
            tmin: 0.0,
            dir: (target - origin).to_array(),
            tmax: f32::MAX,
        }
    }
}

/// The result of tracing a `Ray` (std430, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Hit {
    /// Hit distance; `tmax` on a miss; -1 if the traversal stack overflowed.
    pub t: f32,
    /// Triangle id with `HIT_DYNAMIC` set for the dynamic BVH; `BVH_INVALID` on a miss.
    pub prim: u32,
    /// Barycentric weights of the triangle's second and third corners.
    pub u: f32,
    pub v: f32,
}

impl Hit {
    /// The hit with the dynamic BVH's bit cleared from its triangle id (a miss stays
    /// `BVH_INVALID`).
    pub fn without_bvh_bit(self) -> Self {
        Self {
            prim: if self.prim == crate::shader_defines::BVH_INVALID {
                self.prim
            } else {
                self.prim & !crate::shader_defines::HIT_DYNAMIC
            },
            ..self
        }
    }
}

const _: () = assert!(std::mem::size_of::<TraversalNode>() == 64);
const _: () = assert!(std::mem::size_of::<TraversalTri>() == 48);
const _: () = assert!(std::mem::size_of::<Ray>() == 32);
const _: () = assert!(std::mem::size_of::<Hit>() == 16);

/// Decodes tightly packed RGBA16F texels.
pub fn rgba16f_to_f32(raw: &[u8]) -> Vec<[f32; 4]> {
    raw.chunks_exact(8)
        .map(|t| {
            let h = |i: usize| half::f16::from_le_bytes([t[2 * i], t[2 * i + 1]]).to_f32();
            [h(0), h(1), h(2), h(3)]
        })
        .collect()
}
