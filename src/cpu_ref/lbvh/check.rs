//! The checks every built BVH must pass (`check_bvh`), and its SAH cost.

use super::{bounds, packed_triangle, single};
use crate::aabb::Aabb;
use crate::gpu_types::{bvh_leaf, GpuVertex, PackedBvh, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, BVH_LEAF_MAX};

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
    let tri_box = check_leaf_triangles(tris, vertices, indices)?;
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
    check_walk(nodes, tris, &tri_box)?;
    check_parent_links(nodes, tris, &tri_box, scene)
}

/// Each leaf position holds a distinct triangle, packed as `packed_triangle` packs it;
/// returns their boxes in leaf order.
fn check_leaf_triangles(tris: &[TraversalTri], vertices: &[GpuVertex], indices: &[u32]) -> Result<Vec<Aabb>, String> {
    let n = indices.len() / 3;
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
    Ok(tri_box)
}

/// The tree the traversal walks from the root: every node reached once, every leaf
/// position once in leaves of 1 to `BVH_LEAF_MAX`, each half's box its contents', each
/// reached node or lone triangle linked back to its half; as many nodes out of reach
/// as the leaves hide.
fn check_walk(nodes: &[TraversalNode], tris: &[TraversalTri], tri_box: &[Aabb]) -> Result<(), String> {
    let n = tris.len();
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
    Ok(())
}

/// The binary tree of parent links the refit climbs: each half named by one link and
/// holding that one's box; the root unlinked, its box the scene's.
fn check_parent_links(
    nodes: &[TraversalNode],
    tris: &[TraversalTri],
    tri_box: &[Aabb],
    scene: Aabb,
) -> Result<(), String> {
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
