//! Axis-aligned boxes, shared by the GPU LBVH (reading back its bounds), the CPU
//! references and the scene code.

use crate::gpu_types::TraversalNode;
use glam::Vec3;

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
