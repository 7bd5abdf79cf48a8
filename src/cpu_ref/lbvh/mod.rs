//! References of the LBVH kernels (`glsl/lbvh_*.comp`, `glsl/radix_*.comp`) and the
//! checks every built BVH must pass.

pub use crate::aabb::{
    cells10, expand_bits10, morton30, ordered_to_float, size_class, unit_at, unit_in, unit_scale, Aabb,
};
use crate::gpu_types::{bvh_leaf_link, GpuVertex, PackedBvh, RigidBody, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, BVH_LEAF_MAX};
use glam::{Mat4, UVec3, Vec3};

mod check;
mod compact;
mod ploc;

pub use check::{check_bvh, sah_cost};
pub use compact::*;
pub use ploc::ploc;

/// Corners of triangle `t`.
pub fn triangle(vertices: &[GpuVertex], indices: &[u32], t: usize) -> [Vec3; 3] {
    [0, 1, 2].map(|k| Vec3::from(vertices[indices[3 * t + k] as usize].position))
}

/// Centroid as the GPU computes it: (a + b + c) * (1/3), in f32.
pub fn centroid(tri: &[Vec3; 3]) -> Vec3 {
    (tri[0] + tri[1] + tri[2]) * (1.0 / 3.0)
}

/// `lbvh.bounds`: (centroid bounds, scene bounds).
pub fn bounds(vertices: &[GpuVertex], indices: &[u32]) -> (Aabb, Aabb) {
    (0..indices.len() / 3).fold((Aabb::EMPTY, Aabb::EMPTY), |(c, s), t| {
        let tri = triangle(vertices, indices, t);
        (c.grow(centroid(&tri)), s.union(Aabb::of_triangle(&tri)))
    })
}

/// 63-bit Morton code, x most significant (bit 3b+2 is bit b of x).
pub fn morton63(q: UVec3) -> u64 {
    (0..21).fold(0u64, |code, b| {
        code | (((q.x as u64 >> b) & 1) << (3 * b + 2))
            | (((q.y as u64 >> b) & 1) << (3 * b + 1))
            | (((q.z as u64 >> b) & 1) << (3 * b))
    })
}

/// `squared_length` of `lbvh_morton.comp`: x², y², z² summed in that order, unfused.
fn squared_length(v: Vec3) -> f32 {
    v.x * v.x + v.y * v.y + v.z * v.z
}

/// `lbvh.morton`: the key of every triangle (as u64; 30-bit codes when `key_words` is
/// 1), its size class in the spare top bits (bits 30-31 above a 30-bit code, bit 63
/// above a 63-bit one).
pub fn morton_keys(vertices: &[GpuVertex], indices: &[u32], key_words: u32) -> Vec<u64> {
    let (cb, _) = bounds(vertices, indices);
    morton_keys_scaled(vertices, indices, key_words, unit_scale(cb.lo, cb.hi))
}

/// `morton_keys` quantizing with `scale` (the centroid bounds' `unit_scale`), such as the
/// one `lbvh.morton` used and stored (`Bvh::read_unit_scale`): given the GPU's quotient,
/// the rest is subtractions and multiplications rounded exactly, so the codes match
/// whatever division the device has.
pub fn morton_keys_scaled(vertices: &[GpuVertex], indices: &[u32], key_words: u32, scale: Vec3) -> Vec<u64> {
    let (cb, sb) = bounds(vertices, indices);
    let s2 = squared_length(sb.hi - sb.lo);
    (0..indices.len() / 3)
        .map(|t| {
            let tri = triangle(vertices, indices, t);
            let c = centroid(&tri);
            let b = Aabb::of_triangle(&tri);
            let d2 = squared_length(b.hi - b.lo);
            let unit = unit_at(c, cb.lo, scale);
            if key_words == 1 {
                ((size_class(d2, s2, 2) << 30) | morton30(cells10(unit))) as u64
            } else {
                ((size_class(d2, s2, 1) as u64) << 63)
                    | morton63((unit * 2_097_152.0).min(Vec3::splat(2_097_151.0)).as_uvec3())
            }
        })
        .collect()
}

/// `lbvh_body_keys.comp`: a body's center in the world, its pose applied to its
/// object-space center in the kernel's order, unfused.
pub fn body_center(pose: &Mat4, center: [f32; 3]) -> Vec3 {
    let p = Vec3::from(center);
    ((pose.x_axis.truncate() * p.x + pose.y_axis.truncate() * p.y) + pose.z_axis.truncate() * p.z)
        + pose.w_axis.truncate()
}

/// A rigid rebuild's keys (`tracers::lbvh::rigid`: `lbvh_body_keys`, `lbvh_body_ranks`,
/// `lbvh_rigid_keys`): the sorted (key, triangle) pairs of bodies `bodies` posed by
/// `poses`, their triangles described by `tri_info` ([body, place in the body's order,
/// object-space key, 0] per triangle): from the top, `cell_bits` of the body's code,
/// `rank_bits` of its rank, the object-space key's first bits. The bodies' codes are
/// quantized with `scale` when given (the GPU's own quotient, `RigidKeys::read_scale`),
/// else with the IEEE `unit_scale` of their centers' bounds.
pub fn rigid_keys(
    bodies: &[RigidBody],
    poses: &[Mat4],
    tri_info: &[[u32; 4]],
    rank_bits: u32,
    cell_bits: u32,
    scale: Option<Vec3>,
) -> (Vec<u32>, Vec<u32>) {
    let centers: Vec<Vec3> = bodies
        .iter()
        .zip(poses)
        .map(|(b, p)| body_center(p, b.center))
        .collect();
    let (lo, hi) = centers.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &c| (lo.min(c), hi.max(c)),
    );
    let scale = scale.unwrap_or_else(|| unit_scale(lo, hi));
    let codes: Vec<u32> = centers
        .iter()
        .map(|&c| morton30(cells10(unit_at(c, lo, scale))))
        .collect();
    let mut order: Vec<usize> = (0..bodies.len()).collect();
    order.sort_by_key(|&b| (codes[b], b));
    let mut place = vec![(0u32, 0u32); bodies.len()];
    let mut first = 0;
    for (rank, &b) in order.iter().enumerate() {
        place[b] = (rank as u32, first);
        first += bodies[b].tri_count;
    }
    let top = rank_bits + cell_bits;
    assert!(top < 32 && cell_bits <= 30);
    let mut keys = vec![0u32; tri_info.len()];
    let mut values = vec![0u32; tri_info.len()];
    for (t, info) in tri_info.iter().enumerate() {
        let (rank, first) = place[info[0] as usize];
        let slot = (first + info[1]) as usize;
        let cell = if cell_bits == 0 {
            0
        } else {
            (codes[info[0] as usize] >> (30 - cell_bits)) << (32 - cell_bits)
        };
        let rank = if rank_bits == 0 { 0 } else { rank << (32 - top) };
        keys[slot] = cell | rank | (info[2] >> top);
        values[slot] = t as u32;
    }
    (keys, values)
}

/// `lbvh.sort`: a stable sort of (key, value) pairs by key.
pub fn sort_pairs(keys: &[u64], values: &[u32]) -> (Vec<u64>, Vec<u32>) {
    let mut pairs: Vec<(u64, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    pairs.sort_by_key(|p| p.0); // stable
    pairs.into_iter().unzip()
}

/// Sorted key `i` extended by its index (Karras 2012, section 4), so that every two
/// positions differ: (key << 32) | i.
fn ext_key(keys: &[u64], i: usize) -> u128 {
    ((keys[i] as u128) << 32) | i as u128
}

/// Triangle `id` as the BVH holds it (corners, id; parent link 0) and its box.
fn packed_triangle(vertices: &[GpuVertex], indices: &[u32], id: u32) -> (TraversalTri, Aabb) {
    let [a, b, c] = triangle(vertices, indices, id as usize);
    let t = TraversalTri {
        a: a.to_array(),
        id,
        b: b.to_array(),
        c: c.to_array(),
        ..Default::default()
    };
    (t, Aabb::of_triangle(&[a, b, c]))
}

/// The leaf rule of both builders (`bvh_collapse` in bvh.glsl, the same additions in
/// f32): a node of `count` triangles with this `area` and children's costs becomes a
/// leaf when its triangles are `one_run` in key order, it holds at most `BVH_LEAF_MAX`
/// and that costs no more than the split. Returns whether it does and the node's cost.
fn collapse(area: f32, left_cost: f32, right_cost: f32, count: usize, one_run: bool) -> (bool, f32) {
    let split = area + (left_cost + right_cost);
    let leaf = area * count as f32;
    if one_run && count <= BVH_LEAF_MAX as usize && leaf <= split {
        (true, leaf)
    } else {
        (false, split)
    }
}

/// A single triangle's tree: one node whose two children are that leaf.
fn single(vertices: &[GpuVertex], indices: &[u32], id: u32) -> PackedBvh {
    let (t, b) = packed_triangle(vertices, indices, id);
    let leaf = bvh_leaf_link(0, 1);
    PackedBvh {
        nodes: vec![halves(leaf, b, leaf, b, BVH_INVALID)],
        tris: vec![t],
    }
}

/// `lbvh.fit`: the binary radix tree of the sorted keys (Karras 2012; equal keys apart by
/// their index) over their primitive ids, with every box, in the layout of
/// `glsl/shared/bvh.glsl`; a node of at most `BVH_LEAF_MAX` triangles becomes a leaf
/// where that costs no more SAH than its split (its slot and links stay). Built
/// top-down here: a range [l, r] splits after the last key whose first bit differing
/// between keys l and r is clear; the GPU climbs it bottom-up (Apetrei 2014). `unused`
/// is 0.
pub fn build(keys: &[u64], values: &[u32], vertices: &[GpuVertex], indices: &[u32]) -> PackedBvh {
    let n = keys.len();
    assert!(n >= 1 && values.len() == n && indices.len() == 3 * n);
    let tri = |j: usize| packed_triangle(vertices, indices, values[j]);
    if n == 1 {
        return single(vertices, indices, values[0]);
    }
    let mut b = Builder {
        keys,
        tri: &tri,
        root_split: 0,
        out: PackedBvh {
            nodes: vec![TraversalNode::default(); n - 1],
            tris: vec![TraversalTri::default(); n],
        },
    };
    b.root_split = b.split(0, n - 1);
    b.subtree(0, n - 1);
    b.out.nodes[0].parent = BVH_INVALID;
    b.out
}

struct Builder<'a> {
    keys: &'a [u64],
    tri: &'a dyn Fn(usize) -> (TraversalTri, Aabb),
    root_split: usize,
    out: PackedBvh,
}

impl Builder<'_> {
    /// The split of [l, r]: the last position whose extended key has the first bit in
    /// which keys l and r differ clear.
    fn split(&self, l: usize, r: usize) -> usize {
        let bit = 127 - (ext_key(self.keys, l) ^ ext_key(self.keys, r)).leading_zeros();
        // The bit is clear at lo and set at hi (keys are sorted and share the bits above).
        let (mut lo, mut hi) = (l, r);
        while hi - lo > 1 {
            let m = (lo + hi) / 2;
            if ext_key(self.keys, m) >> bit & 1 == 0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        lo
    }

    /// The slot of the node that splits p | p+1.
    fn slot(&self, p: usize) -> usize {
        match p.cmp(&self.root_split) {
            std::cmp::Ordering::Equal => 0,
            std::cmp::Ordering::Less => p + 1,
            std::cmp::Ordering::Greater => p,
        }
    }

    /// Writes the subtree of [l, r] (post-order: a node once both children are done);
    /// returns its node in the binary tree, its child link (a leaf's, once collapsed),
    /// box and SAH cost (in area; unit costs for a node step and a triangle test).
    fn subtree(&mut self, l: usize, r: usize) -> (Binary, u32, Aabb, f32) {
        if l == r {
            let (t, b) = (self.tri)(l);
            self.out.tris[l] = t;
            return (Binary::Tri(l), bvh_leaf_link(l as u32, 1), b, b.area());
        }
        let p = self.split(l, r);
        let s = self.slot(p);
        let (n0, c0, b0, cost0) = self.subtree(l, p);
        let (n1, c1, b1, cost1) = self.subtree(p + 1, r);
        // Links of the binary tree, also under a leaf of several triangles: the refit
        // climbs them.
        for (side, child) in [(0u32, n0), (1, n1)] {
            let link = (s as u32) << 1 | side;
            match child {
                Binary::Tri(j) => self.out.tris[j].parent = link,
                Binary::Node(c) => self.out.nodes[c].parent = link,
            }
        }
        self.out.nodes[s] = halves(c0, b0, c1, b1, self.out.nodes[s].parent);
        let b = b0.union(b1);
        let count = r - l + 1;
        match collapse(b.area(), cost0, cost1, count, true) {
            (true, cost) => (Binary::Node(s), bvh_leaf_link(l as u32, count as u32), b, cost),
            (false, cost) => (Binary::Node(s), s as u32, b, cost),
        }
    }
}

/// `lbvh.refit` (scheduled): the same tree, links and leaves over moved vertices: every
/// triangle record and every box recomputed through the binary tree of parent links.
pub fn refit(bvh: &PackedBvh, vertices: &[GpuVertex], indices: &[u32]) -> PackedBvh {
    if bvh.tris.len() == 1 {
        return single(vertices, indices, bvh.tris[0].id);
    }
    let mut out = bvh.clone();
    let mut boxes = Vec::with_capacity(out.tris.len());
    for t in &mut out.tris {
        let (moved, b) = packed_triangle(vertices, indices, t.id);
        *t = TraversalTri {
            parent: t.parent,
            ..moved
        };
        boxes.push(b);
    }
    let mut kids = vec![[Binary::Tri(usize::MAX); 2]; out.nodes.len()];
    for (j, t) in out.tris.iter().enumerate() {
        kids[(t.parent >> 1) as usize][(t.parent & 1) as usize] = Binary::Tri(j);
    }
    for (s, nd) in out.nodes.iter().enumerate().skip(1) {
        kids[(nd.parent >> 1) as usize][(nd.parent & 1) as usize] = Binary::Node(s);
    }
    fn fit(s: usize, kids: &[[Binary; 2]], boxes: &[Aabb], nodes: &mut [TraversalNode]) -> Aabb {
        let [b0, b1] = kids[s].map(|k| match k {
            Binary::Tri(j) => boxes[j],
            Binary::Node(c) => fit(c, kids, boxes, nodes),
        });
        let nd = nodes[s];
        nodes[s] = halves(nd.child0, b0, nd.child1, b1, nd.parent);
        b0.union(b1)
    }
    fit(0, &kids, &boxes, &mut out.nodes);
    out
}

/// A node of the binary radix tree: a triangle (leaf position) or an internal slot.
#[derive(Clone, Copy)]
enum Binary {
    Tri(usize),
    Node(usize),
}

/// A node of two halves: each child's link and box, and the node's parent link.
fn halves(r0: u32, b0: Aabb, r1: u32, b1: Aabb, parent: u32) -> TraversalNode {
    TraversalNode {
        lo0: b0.lo.to_array(),
        child0: r0,
        hi0: b0.hi.to_array(),
        child1: r1,
        lo1: b1.lo.to_array(),
        parent,
        hi1: b1.hi.to_array(),
        unused: 0,
    }
}
