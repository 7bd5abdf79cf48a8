//! Reference of `lbvh.compact`: the static walk's nodes, binary (32 bytes) or wide (64
//! bytes: a binary node's children, each internal one opened into its two: up to four),
//! each child's box rounded outward to 16-bit steps of a power-of-two grid over the
//! root's box.

use crate::aabb::Aabb;
use crate::gpu_types::TraversalNode;
use glam::Vec3;

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

/// Slots of a wide node: a binary node's children, each internal one opened into its
/// own two (`WIDE` in `glsl/shared/bvh.glsl`).
pub const WIDE: usize = 4;

/// The children of wide node `k` (made from binary node `k`): each child of node `k`
/// that is a leaf as it is, each internal one opened into its two children; (lo, hi,
/// link), in that order (`wide_entries` in `glsl/lbvh_compact.comp`). Unused slots
/// are not listed.
pub fn wide_entries(nodes: &[TraversalNode], k: usize) -> Vec<([f32; 3], [f32; 3], u32)> {
    let n = &nodes[k];
    let mut out = Vec::with_capacity(WIDE);
    for (lo, hi, c) in [(n.lo0, n.hi0, n.child0), (n.lo1, n.hi1, n.child1)] {
        if crate::gpu_types::bvh_leaf(c).is_some() {
            out.push((lo, hi, c));
        } else {
            let m = &nodes[c as usize];
            out.push((m.lo0, m.hi0, m.child0));
            out.push((m.lo1, m.hi1, m.child1));
        }
    }
    out
}

/// An unused slot of a wide node: no box, the link `BVH_INVALID` (never entered).
pub const WIDE_EMPTY: [u32; 4] = [0, 0, 0, crate::shader_defines::BVH_INVALID];

/// Each node's order counts, as the builders leave them (`Bvh::counts`,
/// `glsl/shared/bvh_order.glsl`): its internal nodes below at an even and at an odd depth,
/// itself included, and its height, `[A, B, H, 0]`, by its child links (a leaf counts
/// 0), for every node, also one inside a leaf. None where the links are not a forest (a
/// node reached twice, a cycle, a link past the nodes).
pub fn order_counts(nodes: &[TraversalNode]) -> Option<Vec<[u32; 4]>> {
    let internal = |c: u32| crate::gpu_types::bvh_leaf(c).is_none();
    let mut counts = vec![None::<[u32; 4]>; nodes.len()];
    let mut seen = vec![false; nodes.len()];
    let mut linked = vec![false; nodes.len()];
    for top in 0..nodes.len() {
        let mut stack = vec![top];
        while let Some(&k) = stack.last() {
            if counts[k].is_some() {
                stack.pop();
                continue;
            }
            let children = [nodes[k].child0, nodes[k].child1];
            if !seen[k] {
                seen[k] = true;
                for c in children.into_iter().filter(|&c| internal(c)).map(|c| c as usize) {
                    if c >= nodes.len() || linked[c] || (seen[c] && counts[c].is_none()) {
                        return None; // past the nodes, a second parent, a cycle
                    }
                    linked[c] = true;
                    stack.push(c);
                }
                continue;
            }
            let [a, b] = children.map(|c| {
                if internal(c) {
                    counts[c as usize].unwrap()
                } else {
                    [0; 4]
                }
            });
            counts[k] = Some([1 + a[1] + b[1], a[0] + b[0], 1 + a[2].max(b[2]), 0]);
            stack.pop();
        }
    }
    counts.into_iter().collect()
}

/// Where `lbvh.compact` puts each of `nodes` (`glsl/shared/bvh_order.glsl`): its
/// place in preorder from the root (a node, its first child's subtree, its second's),
/// counting only the nodes the walk in a layout of `slots` children reaches (binary:
/// the internal nodes outside leaves; wide: those at an even depth), `BVH_INVALID` for
/// the rest. None where the nodes from the root are not a tree whose every internal
/// child links back to its parent's half (a cycle, a planted tree without parent
/// links), which no builder makes.
pub fn compact_places(nodes: &[TraversalNode], slots: u32) -> Option<Vec<u32>> {
    let invalid = crate::shader_defines::BVH_INVALID;
    let mut place = vec![invalid; nodes.len()];
    let mut next = 0;
    let mut stack = vec![(0usize, 0u32)];
    while let Some((k, depth)) = stack.pop() {
        if place[k] != invalid {
            return None;
        }
        if slots == 2 || depth % 2 == 0 {
            place[k] = next;
            next += 1;
        }
        let n = &nodes[k];
        for (side, c) in [(1, n.child1), (0, n.child0)] {
            if crate::gpu_types::bvh_leaf(c).is_some() {
                continue;
            }
            if c as usize >= nodes.len() || nodes[c as usize].parent != (k as u32) << 1 | side {
                return None;
            }
            stack.push((c as usize, depth + 1));
        }
    }
    Some(place)
}

/// `lbvh.compact`: the static walk's nodes made from `nodes` (`glsl/shared/bvh.glsl`),
/// each at its place (`compact_places`), its internal children's links to theirs: the
/// header and the nodes placed, as many as are written (the rest of the buffer is
/// left as it was). For a tree `compact_places` orders, as the GPU does by its
/// builder's counts; nodes planted without counts keep their slots there
/// (`compact_nodes_placed` with each node's own).
pub fn compact_nodes(nodes: &[TraversalNode], slots: u32) -> Vec<[u32; 4]> {
    let place = compact_places(nodes, slots).expect("compact_nodes of a tree from the root with parent links back");
    compact_nodes_placed(nodes, slots, &place)
}

/// `compact_nodes` with each node at `place` (`BVH_INVALID`: not written); the places
/// written must be 0 to some count, each once.
pub fn compact_nodes_placed(nodes: &[TraversalNode], slots: u32, place: &[u32]) -> Vec<[u32; 4]> {
    let root = Aabb::of_node(&nodes[0]);
    let (g, st) = compact_grid(root.lo, root.hi);
    let link = |c: u32| match crate::gpu_types::bvh_leaf(c) {
        Some(_) => c,
        None => place[c as usize],
    };
    let placed = place
        .iter()
        .filter(|&&p| p != crate::shader_defines::BVH_INVALID)
        .count();
    let mut out = vec![[0u32; 4]; 2 + slots as usize * placed];
    out[0] = [g.x.to_bits(), g.y.to_bits(), g.z.to_bits(), slots];
    out[1] = [st.x.to_bits(), st.y.to_bits(), st.z.to_bits(), 0];
    for (k, n) in nodes.iter().enumerate() {
        let Some(at) = place.get(k).filter(|&&p| p != crate::shader_defines::BVH_INVALID) else {
            continue;
        };
        let base = 2 + slots as usize * *at as usize;
        if slots == 2 {
            out[base] = compact_half(n.lo0, n.hi0, link(n.child0), g, st);
            out[base + 1] = compact_half(n.lo1, n.hi1, link(n.child1), g, st);
            continue;
        }
        let entries = wide_entries(nodes, k);
        for slot in 0..WIDE {
            out[base + slot] = match entries.get(slot) {
                Some(&(lo, hi, c)) => compact_half(lo, hi, link(c), g, st),
                None => WIDE_EMPTY,
            };
        }
    }
    out
}
