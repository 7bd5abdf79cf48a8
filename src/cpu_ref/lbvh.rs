//! References of the LBVH kernels (`glsl/lbvh_*.comp`, `glsl/radix_*.comp`) and the
//! checks every built BVH must pass.

pub use crate::aabb::{cells10, expand_bits10, morton30, ordered_to_float, size_class, unit_in, Aabb};
use crate::gpu_types::{bvh_leaf, bvh_leaf_link, GpuVertex, PackedBvh, RigidBody, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, BVH_LEAF_MAX};
use glam::{Mat4, UVec3, Vec3};

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
    let (cb, sb) = bounds(vertices, indices);
    let s2 = squared_length(sb.hi - sb.lo);
    (0..indices.len() / 3)
        .map(|t| {
            let tri = triangle(vertices, indices, t);
            let c = centroid(&tri);
            let b = Aabb::of_triangle(&tri);
            let d2 = squared_length(b.hi - b.lo);
            let unit = unit_in(c, cb.lo, cb.hi);
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

/// A rigid rebuild's keys (`passes::lbvh::rigid`: `lbvh_body_keys`, `lbvh_body_ranks`,
/// `lbvh_rigid_keys`): the sorted (key, triangle) pairs of bodies `bodies` posed by
/// `poses`, their triangles described by `tri_info` ([body, place in the body's order,
/// object-space key, 0] per triangle): from the top, `cell_bits` of the body's code,
/// `rank_bits` of its rank, the object-space key's first bits.
pub fn rigid_keys(
    bodies: &[RigidBody],
    poses: &[Mat4],
    tri_info: &[[u32; 4]],
    rank_bits: u32,
    cell_bits: u32,
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
    let codes: Vec<u32> = centers.iter().map(|&c| morton30(cells10(unit_in(c, lo, hi)))).collect();
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

/// Triangle `id` as the BVH holds it (corner, edges, id; parent link 0) and its box.
fn packed_triangle(vertices: &[GpuVertex], indices: &[u32], id: u32) -> (TraversalTri, Aabb) {
    let [a, b, c] = triangle(vertices, indices, id as usize);
    let t = TraversalTri {
        a: a.to_array(),
        id,
        e1: (b - a).to_array(),
        e2: (c - a).to_array(),
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

/// Checks what every BVH over `vertices`/`indices` must satisfy:
/// - N-1 nodes (one for a single triangle) and N triangle records, each its scene
///   triangle (corner, edges, id), every id once;
/// - from slot 0, every node is reached at most once and every leaf position exactly
///   once, in leaves of 1 to `BVH_LEAF_MAX` triangles; each half's box is the union of
///   what it holds (a child node's halves, a leaf's triangles' boxes); a reached node
///   or lone triangle links back to the half it was reached from;
/// - the binary tree the refit climbs: each half is named by exactly one parent link
///   (of a node or triangle, also inside leaves of several triangles) and holds that
///   one's box; the nodes out of reach are as many as the leaves hide (k - 1 for a leaf
///   of k triangles);
/// - the root has no parent link and its box is the scene box.
pub fn check_bvh(bvh: &PackedBvh, vertices: &[GpuVertex], indices: &[u32]) -> Result<(), String> {
    let n = indices.len() / 3;
    let (nodes, tris) = (&bvh.nodes, &bvh.tris);
    if nodes.len() != (n - 1).max(1) || tris.len() != n {
        return Err(format!(
            "{} nodes and {} triangles for {n} triangles (want {} and {n})",
            nodes.len(),
            tris.len(),
            (n - 1).max(1)
        ));
    }
    let mut seen_id = vec![false; n];
    let mut tri_box = Vec::with_capacity(n);
    for (j, t) in tris.iter().enumerate() {
        let id = t.id as usize;
        if id >= n || std::mem::replace(&mut seen_id[id], true) {
            return Err(format!(
                "leaf position {j}: triangle {id} out of range or in two leaves"
            ));
        }
        let (want, b) = packed_triangle(vertices, indices, t.id);
        let want = TraversalTri {
            parent: t.parent,
            ..want
        };
        if *t != want {
            return Err(format!("leaf position {j}: {t:?} is not triangle {id} ({want:?})"));
        }
        tri_box.push(b);
    }
    let (_, scene) = bounds(vertices, indices);
    if n == 1 {
        let want = TraversalNode {
            unused: nodes[0].unused,
            ..single(vertices, indices, tris[0].id).nodes[0]
        };
        if nodes[0] != want || tris[0].parent != 0 {
            return Err(format!("a single triangle's node {:?} (want {want:?})", nodes[0]));
        }
        return Ok(());
    }
    // The tree the traversal walks.
    let mut seen_node = vec![false; nodes.len()];
    let mut seen_leaf = vec![false; n];
    let mut hidden = 0;
    let mut stack = vec![0usize];
    while let Some(s) = stack.pop() {
        if std::mem::replace(&mut seen_node[s], true) {
            return Err(format!("node {s} is reached twice"));
        }
        for (side, c) in [(0u32, nodes[s].child0), (1, nodes[s].child1)] {
            let half = Aabb::of_half(&nodes[s], side);
            let link = (s as u32) << 1 | side;
            match bvh_leaf(c) {
                Some((first, count)) => {
                    let (first, count) = (first as usize, count as usize);
                    if count > BVH_LEAF_MAX as usize || first + count > n {
                        return Err(format!("node {s}: leaf of {count} triangles from {first}"));
                    }
                    let mut b = Aabb::EMPTY;
                    for j in first..first + count {
                        if std::mem::replace(&mut seen_leaf[j], true) {
                            return Err(format!("leaf position {j} is reached twice"));
                        }
                        b = b.union(tri_box[j]);
                    }
                    if half != b {
                        return Err(format!(
                            "node {s}: box {half:?} of leaf {first}+{count} is not its triangles' {b:?}"
                        ));
                    }
                    if count == 1 && tris[first].parent != link {
                        return Err(format!(
                            "leaf position {first}: parent link {} (want {link})",
                            tris[first].parent
                        ));
                    }
                    hidden += count - 1;
                }
                None => {
                    let child = nodes
                        .get(c as usize)
                        .ok_or(format!("node {s}: child {c} out of range"))?;
                    if child.parent != link {
                        return Err(format!("node {c}: parent link {} (want {link})", child.parent));
                    }
                    stack.push(c as usize);
                }
            }
        }
    }
    if let Some(j) = seen_leaf.iter().position(|s| !s) {
        return Err(format!("leaf position {j} is in no leaf"));
    }
    let unreached = seen_node.iter().filter(|s| !**s).count();
    if unreached != hidden {
        return Err(format!(
            "{unreached} nodes are out of the traversal's reach, but its leaves hide {hidden}"
        ));
    }
    // The binary tree of parent links.
    let mut named = vec![false; 2 * nodes.len()];
    let links = nodes[1..]
        .iter()
        .enumerate()
        .map(|(k, nd)| (format!("node {}", k + 1), nd.parent, Aabb::of_node(nd)))
        .chain(
            tris.iter()
                .enumerate()
                .map(|(j, t)| (format!("leaf position {j}"), t.parent, tri_box[j])),
        );
    for (what, link, b) in links {
        let s = (link >> 1) as usize;
        if s >= nodes.len() || std::mem::replace(&mut named[link as usize], true) {
            return Err(format!("{what}: parent link {link} out of range or named twice"));
        }
        if Aabb::of_half(&nodes[s], link & 1) != b {
            return Err(format!(
                "{what}: its box {b:?} is not in the half its link {link} names"
            ));
        }
    }
    if nodes[0].parent != BVH_INVALID {
        return Err(format!("the root has a parent link {}", nodes[0].parent));
    }
    if Aabb::of_node(&nodes[0]) != scene {
        return Err(format!(
            "root box {:?} is not the scene box {scene:?}",
            Aabb::of_node(&nodes[0])
        ));
    }
    Ok(())
}

/// Surface-area-heuristic cost of a tree (MacDonald & Booth 1990) with unit costs for
/// a traversal step and a triangle test, relative to the root's area: the root, and
/// every box the traversal can reach, times its triangles for a leaf.
pub fn sah_cost(nodes: &[TraversalNode], tri_count: usize) -> f64 {
    if tri_count == 1 {
        return 1.0;
    }
    let root = Aabb::of_node(&nodes[0]).area() as f64;
    let mut cost = 1.0;
    let mut stack = vec![0usize];
    while let Some(s) = stack.pop() {
        for (side, c) in [(0u32, nodes[s].child0), (1, nodes[s].child1)] {
            let area = Aabb::of_half(&nodes[s], side).area() as f64 / root;
            match bvh_leaf(c) {
                Some((_, count)) => cost += area * count as f64,
                None => {
                    cost += area;
                    stack.push(c as usize);
                }
            }
        }
    }
    cost
}

/// The smallest power of two at least `x` (>= 0, finite), at least the smallest
/// normal float (`pow2_at_least` in `glsl/shared/bvh.glsl`).
fn pow2_at_least(x: f32) -> f32 {
    let b = x.to_bits();
    let e = b & 0x7f80_0000;
    if e == 0 {
        return f32::from_bits(0x0080_0000);
    }
    f32::from_bits(if b & 0x007f_ffff != 0 { e + 0x0080_0000 } else { e })
}

/// Two units in the last place of floats with `x`'s exponent, at least the smallest
/// normal (`two_ulps`).
fn two_ulps(x: f32) -> f32 {
    let e = x.to_bits() & 0x7f80_0000;
    f32::from_bits(if e >= 23 << 23 { e - (22 << 23) } else { 0x0080_0000 })
}

/// `compact_grid`: the grid of the compact nodes over the box [lo, hi] (the root's):
/// origin `lo`, per axis the smallest power-of-two step whose 65,534 steps span the
/// box, at least `two_ulps` of its largest coordinate. Returns (origin, step).
pub fn compact_grid(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let mut st = Vec3::ZERO;
    for a in 0..3 {
        let ext = hi[a] - lo[a];
        let s = pow2_at_least(ext * (1.0 / 65536.0));
        let s = if s * 65534.0 < ext { 2.0 * s } else { s };
        st[a] = s.max(two_ulps(lo[a].abs().max(hi[a].abs())));
    }
    (lo, st)
}

/// `grid_at`: grid coordinate `q` along an axis (origin `g`, step `s`); `q * s` is
/// exact, so this is one rounding, as a fused multiply-add would give.
fn grid_at(q: u32, g: f32, s: f32) -> f32 {
    g + q as f32 * s
}

/// `grid_units`: (x - g) / s in steps of the grid (s a power of two: 1 / s is exact).
fn grid_units(x: f32, g: f32, s: f32) -> f32 {
    (x - g) * f32::from_bits(0x7f00_0000 - s.to_bits())
}

/// `grid_down`: the largest q with `grid_at(q) <= x` (x in the grid's box).
fn grid_down(x: f32, g: f32, s: f32) -> u32 {
    let mut q = grid_units(x, g, s).floor().clamp(0.0, 65535.0) as u32;
    for _ in 0..2 {
        if q > 0 && grid_at(q, g, s) > x {
            q -= 1;
        }
    }
    if grid_at(q, g, s) > x {
        0
    } else {
        q
    }
}

/// `grid_up`: the smallest q with `grid_at(q) >= x` (x in the grid's box).
fn grid_up(x: f32, g: f32, s: f32) -> u32 {
    let mut q = grid_units(x, g, s).ceil().clamp(0.0, 65535.0) as u32;
    for _ in 0..2 {
        if q < 65535 && grid_at(q, g, s) < x {
            q += 1;
        }
    }
    if grid_at(q, g, s) < x {
        65535
    } else {
        q
    }
}

/// `compact_half`: one half of a compact node, the box [lo, hi] rounded outward on
/// the grid (g, st) and the child link.
pub fn compact_half(lo: [f32; 3], hi: [f32; 3], child: u32, g: Vec3, st: Vec3) -> [u32; 4] {
    let l: [u32; 3] = std::array::from_fn(|a| grid_down(lo[a], g[a], st[a]));
    let h: [u32; 3] = std::array::from_fn(|a| grid_up(hi[a], g[a], st[a]));
    [l[0] | l[1] << 16, l[2] | h[0] << 16, h[1] | h[2] << 16, child]
}

/// The box of a compact half on the grid (g, st), as the walk decodes it.
pub fn compact_box(half: [u32; 4], g: Vec3, st: Vec3) -> Aabb {
    let q = |w: u32, high: bool| if high { w >> 16 } else { w & 0xffff };
    let at = |a: usize, q: u32| grid_at(q, g[a], st[a]);
    Aabb {
        lo: Vec3::new(
            at(0, q(half[0], false)),
            at(1, q(half[0], true)),
            at(2, q(half[1], false)),
        ),
        hi: Vec3::new(
            at(0, q(half[1], true)),
            at(1, q(half[2], false)),
            at(2, q(half[2], true)),
        ),
    }
}

/// `lbvh.compact`: the compact nodes of `nodes` (`glsl/shared/bvh.glsl`), as texels of
/// 4 words: the grid's origin and step over the root's box, then each node's two
/// halves.
pub fn compact_nodes(nodes: &[TraversalNode]) -> Vec<[u32; 4]> {
    let root = Aabb::of_node(&nodes[0]);
    let (g, st) = compact_grid(root.lo, root.hi);
    let mut out = vec![
        [g.x.to_bits(), g.y.to_bits(), g.z.to_bits(), 0],
        [st.x.to_bits(), st.y.to_bits(), st.z.to_bits(), 0],
    ];
    for n in nodes {
        out.push(compact_half(n.lo0, n.hi0, n.child0, g, st));
        out.push(compact_half(n.lo1, n.hi1, n.child1, g, st));
    }
    out
}

/// `lbvh.ploc`: the tree of PLOC (Meister & Bittner 2018, "Parallel Locally-Ordered
/// Clustering for Bounding Volume Hierarchy Construction") over the triangles in key
/// order, in the layout of `glsl/shared/bvh.glsl`. Clusters start as the leaves in key
/// order; each round every cluster finds the one within `radius` positions whose union
/// box has the least area (ties to the smaller position), mutual pairs merge into a
/// node at the first one's position, and the clusters close ranks. The k-th merge (by
/// round, then position) takes slot N-2-k, so the root is slot 0. A merged cluster of at
/// most `BVH_LEAF_MAX` triangles whose leaf positions are one run becomes a leaf where
/// that costs no more SAH than its split (as `build` decides; its node stays).
pub fn ploc(values: &[u32], vertices: &[GpuVertex], indices: &[u32], radius: usize) -> PackedBvh {
    let n = values.len();
    assert!(n >= 1 && indices.len() == 3 * n && radius >= 1);
    if n == 1 {
        return single(vertices, indices, values[0]);
    }
    let mut out = PackedBvh {
        nodes: vec![TraversalNode::default(); n - 1],
        tris: Vec::with_capacity(n),
    };
    let mut clusters: Vec<Cluster> = Vec::with_capacity(n);
    for (j, &id) in values.iter().enumerate() {
        let (t, bounds) = packed_triangle(vertices, indices, id);
        out.tris.push(t);
        clusters.push(Cluster {
            link: bvh_leaf_link(j as u32, 1),
            node: Binary::Tri(j),
            bounds,
            cost: bounds.area(),
            first: j,
            count: 1,
            run: true,
        });
    }
    let mut merges = 0usize;
    while clusters.len() > 1 {
        let c = clusters.len();
        let nearest: Vec<usize> = (0..c)
            .map(|i| {
                let (mut best, mut area) = (usize::MAX, f32::INFINITY);
                for j in i.saturating_sub(radius)..(i + radius + 1).min(c) {
                    if j != i {
                        let a = clusters[i].bounds.union(clusters[j].bounds).area();
                        if a < area {
                            (best, area) = (j, a);
                        }
                    }
                }
                best
            })
            .collect();
        let mut merged = Vec::with_capacity(c);
        for i in 0..c {
            let j = nearest[i];
            if nearest[j] != i {
                merged.push(clusters[i]);
            } else if i < j {
                let (a, b) = (clusters[i], clusters[j]);
                let slot = n - 2 - merges;
                merges += 1;
                out.nodes[slot] = halves(a.link, a.bounds, b.link, b.bounds, out.nodes[slot].parent);
                for (side, node) in [(0u32, a.node), (1, b.node)] {
                    let link = (slot as u32) << 1 | side;
                    match node {
                        Binary::Tri(t) => out.tris[t].parent = link,
                        Binary::Node(s) => out.nodes[s].parent = link,
                    }
                }
                let bounds = a.bounds.union(b.bounds);
                let count = a.count + b.count;
                let run = a.run && b.run && (a.first + a.count == b.first || b.first + b.count == a.first);
                let first = a.first.min(b.first);
                let (leaf, cost) = collapse(bounds.area(), a.cost, b.cost, count, run);
                merged.push(Cluster {
                    link: if leaf {
                        bvh_leaf_link(first as u32, count as u32)
                    } else {
                        slot as u32
                    },
                    node: Binary::Node(slot),
                    bounds,
                    cost,
                    first,
                    count,
                    run,
                });
            }
        }
        clusters = merged;
    }
    out.nodes[0].parent = BVH_INVALID;
    out
}

/// A PLOC cluster: its child link for the traversal, its node in the binary tree, its
/// box and SAH cost, and its leaf positions (`run`: they are first..first+count).
#[derive(Clone, Copy)]
struct Cluster {
    link: u32,
    node: Binary,
    bounds: Aabb,
    cost: f32,
    first: usize,
    count: usize,
    run: bool,
}

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
