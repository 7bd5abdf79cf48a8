//! Reference of `lbvh.ploc` (Meister & Bittner 2018), bit for bit.

use super::{collapse, halves, packed_triangle, single, Binary};
use crate::aabb::Aabb;
use crate::gpu_types::{bvh_leaf_link, GpuVertex, PackedBvh, TraversalNode};
use crate::shader_defines::BVH_INVALID;

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
