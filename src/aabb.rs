//! Axis-aligned boxes and Morton codes of points in them, shared by the GPU LBVH
//! (reading back its bounds; the rigid bodies' order, `tracers::lbvh::rigid`), the CPU
//! references and the scene code.

use crate::gpu_types::TraversalNode;
use glam::{UVec3, Vec3};

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: Vec3::splat(f32::MAX),
        hi: Vec3::splat(f32::MIN),
    };

    pub fn of_triangle(tri: &[Vec3; 3]) -> Self {
        Self {
            lo: tri[0].min(tri[1]).min(tri[2]),
            hi: tri[0].max(tri[1]).max(tri[2]),
        }
    }
    pub fn union(self, o: Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            lo: self.lo.min(p),
            hi: self.hi.max(p),
        }
    }
    pub fn contains(&self, o: &Self) -> bool {
        self.lo.cmple(o.lo).all() && self.hi.cmpge(o.hi).all()
    }
    /// Surface area (0 for empty or flat-in-two-axes boxes).
    pub fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
    /// The box a BVH node holds for its child `side` (0: `child0`, 1: `child1`).
    pub fn of_half(n: &TraversalNode, side: u32) -> Self {
        let (lo, hi) = if side == 0 { (n.lo0, n.hi0) } else { (n.lo1, n.hi1) };
        Self {
            lo: Vec3::from(lo),
            hi: Vec3::from(hi),
        }
    }
    /// A BVH node's own box: the union of its halves.
    pub fn of_node(n: &TraversalNode) -> Self {
        Self::of_half(n, 0).union(Self::of_half(n, 1))
    }
}

/// Inverse of the kernels' order-preserving float → uint mapping (`bvh.glsl`).
pub fn ordered_to_float(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 { u & 0x7fff_ffff } else { !u })
}

/// Spreads the low 10 bits of x to every third bit (`expand_bits10` in `bvh.glsl`).
pub fn expand_bits10(mut x: u32) -> u32 {
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    x = (x | (x << 2)) & 0x0924_9249;
    x
}

/// 30-bit Morton code of 10-bit cells, x most significant.
pub fn morton30(q: UVec3) -> u32 {
    (expand_bits10(q.x) << 2) | (expand_bits10(q.y) << 1) | expand_bits10(q.z)
}

/// `unit_scale` of `bvh.glsl`: the per-axis scale that maps [lo, hi] onto [0, 1], the
/// one division of the Morton codes (IEEE here; a GPU may round it otherwise, within
/// 2.5 ULP, which is why `lbvh.morton` stores the one it used).
pub fn unit_scale(lo: Vec3, hi: Vec3) -> Vec3 {
    Vec3::ONE / (hi - lo).max(Vec3::splat(1e-30))
}

/// `unit_at` of `bvh.glsl`: point p's place in the box from `lo` with `scale` as
/// fractions in [0, 1] per axis (a flat axis gives 0): one subtraction and one
/// multiplication, each rounded exactly, as the GPU's (`precise`).
pub fn unit_at(p: Vec3, lo: Vec3, scale: Vec3) -> Vec3 {
    ((p - lo) * scale).clamp(Vec3::ZERO, Vec3::ONE)
}

/// `unit_at` in the box [lo, hi] with the IEEE `unit_scale` (the CPU's own codes, such
/// as a rigid body's object-space order); `morton30` of its 10-bit cells is the GLSL
/// `morton30(unit)`.
pub fn unit_in(p: Vec3, lo: Vec3, hi: Vec3) -> Vec3 {
    unit_at(p, lo, unit_scale(lo, hi))
}

/// The 10-bit cells of a point at `unit` (`unit_in`).
pub fn cells10(unit: Vec3) -> UVec3 {
    (unit * 1024.0).min(Vec3::splat(1023.0)).as_uvec3()
}

/// `size_class` of `lbvh_morton.comp`: a triangle whose box has squared diagonal `d2`
/// in a scene whose box has `s2`, in `bits` bits (2: 0 for a diagonal of at least half
/// the scene's, 1 a quarter, 2 an eighth, else 3; 1: 0 for a quarter, else 1).
pub fn size_class(d2: f32, s2: f32, bits: u32) -> u32 {
    if bits == 1 {
        return if d2 >= s2 * 0.0625 { 0 } else { 1 };
    }
    if d2 >= s2 * 0.25 {
        0
    } else if d2 >= s2 * 0.0625 {
        1
    } else if d2 >= s2 * 0.015625 {
        2
    } else {
        3
    }
}
