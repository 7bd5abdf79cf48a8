//! References of the LBVH kernels (`glsl/lbvh_*.comp`, `glsl/radix_*.comp`) and the
//! checks every built BVH must pass.

pub use crate::aabb::{ordered_to_float, Aabb};
use crate::gpu_types::{BvhNode, GpuVertex, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, BVH_LEAF_BIT};
use glam::{UVec3, Vec3};

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

/// Spreads the low 10 bits of x to every third bit (see `expand_bits10` in GLSL).
pub fn expand_bits10(mut x: u32) -> u32 {
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    x = (x | (x << 2)) & 0x0924_9249;
    x
}

/// 30-bit Morton code, x most significant.
pub fn morton30(q: UVec3) -> u32 {
    (expand_bits10(q.x) << 2) | (expand_bits10(q.y) << 1) | expand_bits10(q.z)
}

/// 63-bit Morton code, x most significant (bit 3b+2 is bit b of x).
pub fn morton63(q: UVec3) -> u64 {
    (0..21).fold(0u64, |code, b| {
        code | (((q.x as u64 >> b) & 1) << (3 * b + 2))
            | (((q.y as u64 >> b) & 1) << (3 * b + 1))
            | (((q.z as u64 >> b) & 1) << (3 * b))
    })
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

/// `squared_length` of `lbvh_morton.comp`: x², y², z² summed in that order, unfused.
fn squared_length(v: Vec3) -> f32 {
    v.x * v.x + v.y * v.y + v.z * v.z
}

/// `lbvh.morton`: the key of every triangle (as u64; 30-bit codes when `key_words` is
/// 1), its size class in the spare top bits (bits 30-31 above a 30-bit code, bit 63
/// above a 63-bit one).
pub fn morton_keys(vertices: &[GpuVertex], indices: &[u32], key_words: u32) -> Vec<u64> {
    let (cb, sb) = bounds(vertices, indices);
    let extent = cb.hi - cb.lo;
    let s2 = squared_length(sb.hi - sb.lo);
    (0..indices.len() / 3)
        .map(|t| {
            let tri = triangle(vertices, indices, t);
            let c = centroid(&tri);
            let b = Aabb::of_triangle(&tri);
            let d2 = squared_length(b.hi - b.lo);
            let unit = ((c - cb.lo) / extent.max(Vec3::splat(1e-30))).clamp(Vec3::ZERO, Vec3::ONE);
            if key_words == 1 {
                ((size_class(d2, s2, 2) << 30) | morton30((unit * 1024.0).min(Vec3::splat(1023.0)).as_uvec3())) as u64
            } else {
                ((size_class(d2, s2, 1) as u64) << 63)
                    | morton63((unit * 2_097_152.0).min(Vec3::splat(2_097_151.0)).as_uvec3())
            }
        })
        .collect()
}

/// `lbvh.sort`: a stable sort of (key, value) pairs by key.
pub fn sort_pairs(keys: &[u64], values: &[u32]) -> (Vec<u64>, Vec<u32>) {
    let mut pairs: Vec<(u64, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    pairs.sort_by_key(|p| p.0); // stable
    pairs.into_iter().unzip()
}

fn delta(keys: &[u64], key_words: u32, i: i64, j: i64) -> i64 {
    if j < 0 || j >= keys.len() as i64 {
        return -1;
    }
    let bits = 32 * key_words as i64;
    let x = keys[i as usize] ^ keys[j as usize];
    if x != 0 {
        x.leading_zeros() as i64 - (64 - bits)
    } else {
        bits + (i as u32 ^ j as u32).leading_zeros() as i64
    }
}

/// `lbvh.hierarchy` (Karras 2012): child links of the 2N-1 nodes (boxes left zero) and
/// the parent of every node, from sorted keys and their primitive ids.
pub fn hierarchy(keys: &[u64], values: &[u32], key_words: u32) -> (Vec<BvhNode>, Vec<u32>) {
    let n = keys.len() as i64;
    let mut nodes = vec![BvhNode::default(); (2 * n - 1).max(0) as usize];
    let mut parents = vec![0u32; nodes.len()];
    if n == 0 {
        return (nodes, parents);
    }
    for (i, v) in values.iter().enumerate() {
        nodes[(n - 1) as usize + i].left = BVH_LEAF_BIT | v;
        nodes[(n - 1) as usize + i].right = BVH_INVALID;
    }
    parents[0] = BVH_INVALID;
    let delta = |i: i64, j: i64| delta(keys, key_words, i, j);
    for i in 0..n - 1 {
        let d = if delta(i, i + 1) - delta(i, i - 1) >= 0 { 1 } else { -1 };
        let delta_min = delta(i, i - d);
        let mut l_max = 2;
        while delta(i, i + l_max * d) > delta_min {
            l_max *= 2;
        }
        let mut l = 0;
        let mut t = l_max / 2;
        while t >= 1 {
            if delta(i, i + (l + t) * d) > delta_min {
                l += t;
            }
            t /= 2;
        }
        let j = i + l * d;
        let delta_node = delta(i, j);
        let mut s = 0;
        let mut div = 2;
        loop {
            let t = (l + div - 1) / div;
            if delta(i, i + (s + t) * d) > delta_node {
                s += t;
            }
            if t == 1 {
                break;
            }
            div *= 2;
        }
        let gamma = i + s * d + d.min(0);
        let left = if i.min(j) == gamma { n - 1 + gamma } else { gamma } as u32;
        let right = if i.max(j) == gamma + 1 {
            n - 1 + gamma + 1
        } else {
            gamma + 1
        } as u32;
        nodes[i as usize].left = left;
        nodes[i as usize].right = right;
        parents[left as usize] = i as u32;
        parents[right as usize] = i as u32;
    }
    (nodes, parents)
}

/// `lbvh.fit`: fills the boxes of a tree whose links are set.
pub fn fit(nodes: &mut [BvhNode], vertices: &[GpuVertex], indices: &[u32]) {
    fn visit(nodes: &mut [BvhNode], i: usize, vertices: &[GpuVertex], indices: &[u32]) -> Aabb {
        let nd = nodes[i];
        let b = if nd.left & BVH_LEAF_BIT != 0 {
            Aabb::of_triangle(&triangle(vertices, indices, (nd.left & !BVH_LEAF_BIT) as usize))
        } else {
            let l = visit(nodes, nd.left as usize, vertices, indices);
            let r = visit(nodes, nd.right as usize, vertices, indices);
            l.union(r)
        };
        nodes[i].lo = b.lo.to_array();
        nodes[i].hi = b.hi.to_array();
        b
    }
    if !nodes.is_empty() {
        visit(nodes, 0, vertices, indices);
    }
}

/// The traversal layout `lbvh.fit` and `lbvh.refit` write beside the nodes, from a
/// fitted tree over `indices.len() / 3` triangles: each internal node with both
/// children's boxes (a single triangle: one node whose two children are that leaf),
/// and the triangles in leaf order with their edges.
pub fn pack(nodes: &[BvhNode], vertices: &[GpuVertex], indices: &[u32]) -> (Vec<TraversalNode>, Vec<TraversalTri>) {
    let n = indices.len() / 3;
    let internal = n - 1;
    let child = |c: u32| {
        if (c as usize) < internal {
            c
        } else {
            BVH_LEAF_BIT | (c - internal as u32)
        }
    };
    let packed = |l: u32, r: u32| {
        let (a, b) = (&nodes[l as usize], &nodes[r as usize]);
        TraversalNode {
            lo0: a.lo,
            child0: child(l),
            hi0: a.hi,
            child1: child(r),
            lo1: b.lo,
            hi1: b.hi,
            ..Default::default()
        }
    };
    let tnodes = if internal == 0 {
        vec![packed(0, 0)]
    } else {
        nodes[..internal].iter().map(|nd| packed(nd.left, nd.right)).collect()
    };
    let tris = nodes[internal..]
        .iter()
        .map(|leaf| {
            let t = leaf.left & !BVH_LEAF_BIT;
            let [a, b, c] = triangle(vertices, indices, t as usize);
            TraversalTri {
                a: a.to_array(),
                id: t,
                e1: (b - a).to_array(),
                e2: (c - a).to_array(),
                ..Default::default()
            }
        })
        .collect();
    (tnodes, tris)
}

/// Checks what every BVH over `vertices`/`indices` must satisfy: 2N-1 nodes forming
/// one tree rooted at 0; every triangle in exactly one leaf; each leaf box equal to its
/// triangle's box; each parent box containing its children; the root box equal to the
/// scene box; `parents` consistent with the links (when given).
pub fn check_bvh(
    nodes: &[BvhNode],
    parents: Option<&[u32]>,
    vertices: &[GpuVertex],
    indices: &[u32],
) -> Result<(), String> {
    let n = indices.len() / 3;
    if nodes.len() != 2 * n - 1 {
        return Err(format!("{} nodes for {n} triangles (want {})", nodes.len(), 2 * n - 1));
    }
    let mut seen_node = vec![false; nodes.len()];
    let mut seen_tri = vec![false; n];
    let mut stack = vec![(0usize, BVH_INVALID)];
    while let Some((i, parent)) = stack.pop() {
        if i >= nodes.len() {
            return Err(format!("link to node {i} past the end"));
        }
        if std::mem::replace(&mut seen_node[i], true) {
            return Err(format!("node {i} is reached twice"));
        }
        if let Some(p) = parents {
            if p[i] != parent {
                return Err(format!("parent of node {i} is {} (want {parent})", p[i]));
            }
        }
        let nd = &nodes[i];
        let b = Aabb::of_node(nd);
        if nd.left & BVH_LEAF_BIT != 0 {
            let t = (nd.left & !BVH_LEAF_BIT) as usize;
            if t >= n || std::mem::replace(&mut seen_tri[t], true) {
                return Err(format!("leaf {i}: triangle {t} out of range or in two leaves"));
            }
            let want = Aabb::of_triangle(&triangle(vertices, indices, t));
            if b != want {
                return Err(format!("leaf {i}: box {b:?} is not its triangle's {want:?}"));
            }
        } else {
            for c in [nd.left, nd.right] {
                let cb = Aabb::of_node(
                    nodes
                        .get(c as usize)
                        .ok_or(format!("node {i}: child {c} out of range"))?,
                );
                if !b.contains(&cb) {
                    return Err(format!("node {i}: box {b:?} does not contain child {c}'s {cb:?}"));
                }
                stack.push((c as usize, i as u32));
            }
        }
    }
    if let Some(i) = seen_node.iter().position(|s| !s) {
        return Err(format!("node {i} is not in the tree"));
    }
    if let Some(t) = seen_tri.iter().position(|s| !s) {
        return Err(format!("triangle {t} is in no leaf"));
    }
    let (_, scene) = bounds(vertices, indices);
    if Aabb::of_node(&nodes[0]) != scene {
        return Err(format!(
            "root box {:?} is not the scene box {scene:?}",
            Aabb::of_node(&nodes[0])
        ));
    }
    Ok(())
}

/// Surface-area-heuristic cost of a tree (MacDonald & Booth 1990) with unit costs for
/// a traversal step and a triangle test, relative to the root's area.
pub fn sah_cost_nodes(nodes: &[BvhNode]) -> f64 {
    let root = Aabb::of_node(&nodes[0]).area() as f64;
    nodes
        .iter()
        .map(|nd| Aabb::of_node(nd).area() as f64 / root)
        .sum::<f64>()
}
