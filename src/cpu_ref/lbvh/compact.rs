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
    grid_over(lo, hi, GRID16)
}

/// The last step of the compact nodes' 16-bit grid and of a compressed wide node's
/// 8-bit one.
const GRID16: u32 = 65535;
const GRID8: u32 = 255;

/// `compact_grid` with steps 0..=top (top - 1 of them span the box).
fn grid_over(lo: Vec3, hi: Vec3, top: u32) -> (Vec3, Vec3) {
    let span = (top - 1) as f32;
    let mut st = Vec3::ZERO;
    for a in 0..3 {
        let ext = hi[a] - lo[a];
        let s = pow2_at_least(ext * (1.0 / (top + 1) as f32));
        let s = if s * span < ext { 2.0 * s } else { s };
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

/// `grid_down`: the largest q with `grid_at(q) <= x` (x in the grid's box of steps
/// 0..=top).
fn grid_down(x: f32, g: f32, s: f32, top: u32) -> u32 {
    let mut q = grid_units(x, g, s).floor().clamp(0.0, top as f32) as u32;
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

/// `grid_up`: the smallest q with `grid_at(q) >= x` (x in the grid's box of steps
/// 0..=top).
fn grid_up(x: f32, g: f32, s: f32, top: u32) -> u32 {
    let mut q = grid_units(x, g, s).ceil().clamp(0.0, top as f32) as u32;
    for _ in 0..2 {
        if q < top && grid_at(q, g, s) < x {
            q += 1;
        }
    }
    if grid_at(q, g, s) < x {
        top
    } else {
        q
    }
}

/// `compact_half`: one half of a compact node, the box [lo, hi] rounded outward on
/// the grid (g, st) and the child link.
pub fn compact_half(lo: [f32; 3], hi: [f32; 3], child: u32, g: Vec3, st: Vec3) -> [u32; 4] {
    let l: [u32; 3] = std::array::from_fn(|a| grid_down(lo[a], g[a], st[a], GRID16));
    let h: [u32; 3] = std::array::from_fn(|a| grid_up(hi[a], g[a], st[a], GRID16));
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
    opened_entries(nodes, k, 2)
}

/// The children of compressed wide node `k` (`StaticLayout::Wide8`): `wide_entries`
/// opened once more, up to `WIDE8`, in that order.
pub fn wide8_entries(nodes: &[TraversalNode], k: usize) -> Vec<([f32; 3], [f32; 3], u32)> {
    opened_entries(nodes, k, 3)
}

/// Node `k`'s two children, each internal one opened into its two, `levels - 1` times.
fn opened_entries(nodes: &[TraversalNode], k: usize, levels: u32) -> Vec<([f32; 3], [f32; 3], u32)> {
    let n = &nodes[k];
    let mut out = vec![(n.lo0, n.hi0, n.child0), (n.lo1, n.hi1, n.child1)];
    for _ in 1..levels {
        out = out
            .into_iter()
            .flat_map(|e| match crate::gpu_types::bvh_leaf(e.2) {
                Some(_) => vec![e],
                None => {
                    let m = &nodes[e.2 as usize];
                    vec![(m.lo0, m.hi0, m.child0), (m.lo1, m.hi1, m.child1)]
                }
            })
            .collect();
    }
    out
}

/// A compressed wide node (`WIDE8_TEXELS` texels, `glsl/lbvh_compact.comp`) of
/// `entries` (at most `WIDE8`; links as given): texel 0 the node's grid, its origin
/// the entries' lower corner and each axis's power-of-two step as its exponent byte
/// (`grid_over` with 255 steps); texels 1-3 each entry's box rounded outward to that
/// grid, a byte a coordinate (entry j in byte j % 4 of word j / 4 of each axis's pair
/// of words: lo x, lo y, lo z, hi x, hi y, hi z); texels 4-5 the links, `BVH_INVALID`
/// for an unused slot (its box 0).
pub fn wide8_node(entries: &[([f32; 3], [f32; 3], u32)]) -> [[u32; 4]; 6] {
    let invalid = crate::shader_defines::BVH_INVALID;
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for e in entries {
        lo = lo.min(Vec3::from(e.0));
        hi = hi.max(Vec3::from(e.1));
    }
    let (g, st) = grid_over(lo, hi, GRID8);
    let exp = |a: usize| st[a].to_bits() >> 23;
    let mut words = [0u32; 12];
    let mut links = [invalid; 8];
    for (j, e) in entries.iter().enumerate() {
        let q = [
            grid_down(e.0[0], g.x, st.x, GRID8),
            grid_down(e.0[1], g.y, st.y, GRID8),
            grid_down(e.0[2], g.z, st.z, GRID8),
            grid_up(e.1[0], g.x, st.x, GRID8),
            grid_up(e.1[1], g.y, st.y, GRID8),
            grid_up(e.1[2], g.z, st.z, GRID8),
        ];
        for (c, v) in q.into_iter().enumerate() {
            words[2 * c + j / 4] |= v << (8 * (j % 4));
        }
        links[j] = e.2;
    }
    [
        [
            g.x.to_bits(),
            g.y.to_bits(),
            g.z.to_bits(),
            exp(0) | exp(1) << 8 | exp(2) << 16,
        ],
        [words[0], words[1], words[2], words[3]],
        [words[4], words[5], words[6], words[7]],
        [words[8], words[9], words[10], words[11]],
        [links[0], links[1], links[2], links[3]],
        [links[4], links[5], links[6], links[7]],
    ]
}

/// The boxes and links of a compressed wide node (`wide8_node`) as the walk decodes
/// them, unused slots included.
pub fn wide8_boxes(node: &[[u32; 4]]) -> [(Aabb, u32); 8] {
    let h = node[0];
    let g = Vec3::new(f32::from_bits(h[0]), f32::from_bits(h[1]), f32::from_bits(h[2]));
    let st = Vec3::new(
        f32::from_bits((h[3] & 0xff) << 23),
        f32::from_bits((h[3] >> 8 & 0xff) << 23),
        f32::from_bits((h[3] >> 16 & 0xff) << 23),
    );
    let words: Vec<u32> = node[1..4].iter().flatten().copied().collect();
    std::array::from_fn(|j| {
        let q = |c: usize| words[2 * c + j / 4] >> (8 * (j % 4)) & 0xff;
        let at = |a: usize, c: usize| grid_at(q(c), g[a], st[a]);
        let b = Aabb {
            lo: Vec3::new(at(0, 0), at(1, 1), at(2, 2)),
            hi: Vec3::new(at(0, 3), at(1, 4), at(2, 5)),
        };
        (b, node[4 + j / 4][j % 4])
    })
}

/// An unused slot of a wide node: no box, the link `BVH_INVALID` (never entered).
pub const WIDE_EMPTY: [u32; 4] = [0, 0, 0, crate::shader_defines::BVH_INVALID];

/// Each node's order counts, as the builders leave them (`Bvh::counts`,
/// `glsl/shared/bvh_order.glsl`): its internal nodes below at an even and at an odd depth
/// (A, B) and at depths 0 and 1 mod 3 (M0, M1), itself at depth 0, and its height H,
/// `[A, B, H | M0 << 8, M1]`, by its child links (a leaf counts 0), for every node, also
/// one inside a leaf. None where the links are not a forest (a node reached twice, a
/// cycle, a link past the nodes).
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
            // A child's internal nodes at depths 0, 1, 2 mod 3 below it.
            let thirds = |c: [u32; 4]| [c[2] >> 8, c[3], c[0] + c[1] - (c[2] >> 8) - c[3]];
            let (ta, tb) = (thirds(a), thirds(b));
            // The height stops at ORDER_H_MAX (the tree then keeps its slots).
            let height = (1 + (a[2] & 0xff).max(b[2] & 0xff)).min(crate::shader_defines::ORDER_H_MAX);
            counts[k] = Some([
                1 + a[1] + b[1],
                a[0] + b[0],
                height | (1 + ta[2] + tb[2]) << 8,
                ta[0] + tb[0],
            ]);
            stack.pop();
        }
    }
    counts.into_iter().collect()
}

/// Where `lbvh.compact` puts each of `nodes` (`glsl/shared/bvh_order.glsl`): its
/// place in preorder from the root (a node, its first child's subtree, its second's),
/// counting only the nodes the walk in a layout of `slots` children reaches (binary:
/// the internal nodes outside leaves; wide: those at an even depth; compressed wide:
/// those at a depth divisible by three), `BVH_INVALID` for
/// the rest. None where the nodes from the root are not a tree whose every internal
/// child links back to its parent's half (a cycle, a planted tree without parent
/// links), which no builder makes.
pub fn compact_places(nodes: &[TraversalNode], slots: u32) -> Option<Vec<u32>> {
    let invalid = crate::shader_defines::BVH_INVALID;
    let phases = match slots {
        s if s == WIDE as u32 => 2,
        crate::shader_defines::WIDE8 => 3,
        _ => 1,
    };
    let mut place = vec![invalid; nodes.len()];
    let mut next = 0;
    let mut stack = vec![(0usize, 0u32)];
    while let Some((k, depth)) = stack.pop() {
        if place[k] != invalid {
            return None;
        }
        if depth % phases == 0 {
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
/// builder's counts; a tree `ORDER_H_MAX` or more deep, and nodes planted without
/// counts, keep their slots there (`compact_nodes_placed` with each node's own).
pub fn compact_nodes(nodes: &[TraversalNode], slots: u32) -> Vec<[u32; 4]> {
    compact_nodes_placed(nodes, slots, &written_places(nodes, slots))
}

/// Where `lbvh.compact` writes each node of a built tree (`compact_nodes`): its place
/// in preorder (`compact_places`), or its own slot in a tree `ORDER_H_MAX` or more
/// deep, which the order's jump rounds do not reach through.
pub fn written_places(nodes: &[TraversalNode], slots: u32) -> Vec<u32> {
    let h_max = crate::shader_defines::ORDER_H_MAX;
    match order_counts(nodes).is_some_and(|c| c[0][2] & 0xff >= h_max) {
        true => (0..nodes.len() as u32).collect(),
        false => compact_places(nodes, slots).expect("compact_nodes of a tree from the root with parent links back"),
    }
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
    let texels = if slots == crate::shader_defines::WIDE8 {
        crate::shader_defines::WIDE8_TEXELS as usize
    } else {
        slots as usize
    };
    let mut out = vec![[0u32; 4]; 2 + texels * placed];
    out[0] = [g.x.to_bits(), g.y.to_bits(), g.z.to_bits(), slots];
    out[1] = [st.x.to_bits(), st.y.to_bits(), st.z.to_bits(), 0];
    for (k, n) in nodes.iter().enumerate() {
        let Some(at) = place.get(k).filter(|&&p| p != crate::shader_defines::BVH_INVALID) else {
            continue;
        };
        let base = 2 + texels * *at as usize;
        if slots == crate::shader_defines::WIDE8 {
            let entries: Vec<_> = wide8_entries(nodes, k)
                .into_iter()
                .map(|(lo, hi, c)| (lo, hi, link(c)))
                .collect();
            out[base..base + texels].copy_from_slice(&wide8_node(&entries));
            continue;
        }
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
