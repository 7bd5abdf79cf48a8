#version 460
// lbvh.compact: the static walk's nodes made from a built (or refit) BVH (bvh.glsl: the
// layout, the grid over the root's box, the rounding outward), in one of two layouts
// (tracers::lbvh::StaticLayout), `slots` children a node:
// - 2, binary: node i's two children;
// - WIDE, wide: node i's children, each internal one opened into its two children (up
//   to WIDE, unused slots empty: link BVH_INVALID);
// - WIDE8, compressed wide: node i's children opened twice (up to WIDE8), on the
//   node's own 8-bit grid (bvh.glsl), WIDE8_TEXELS texels a node.
// Each node at its place in preorder (bvh_order.glsl: lbvh_order_* ran before), its
// children's links to their places; nodes not placed (inside a leaf; wide: at an odd
// depth, the opened children; compressed wide: not at a depth divisible by three) are
// not written. A tree that is not ordered (order_ordered: its root has no counts, or
// it is ORDER_H_MAX or more deep) keeps every node in its slot, as are the links.
// One invocation per binary node; the first also writes the header, whose first texel's
// w says `slots` to the walk. Mirrored by cpu_ref::lbvh::compact_nodes (tests/lbvh.rs).
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
layout(binding = 1, std430) writeonly buffer Compact { uvec4 compact[]; };
layout(binding = 2, std430) readonly buffer Counts { uvec4 counts[]; };
// The jump states after an even and after an odd count of rounds.
layout(binding = 3) uniform utextureBuffer jump0;
layout(binding = 4) uniform utextureBuffer jump1;

layout(push_constant) uniform Push {
    uint node_count;
    uint slots;
} pc;

// Node i's place (BVH_INVALID: not written), given whether the tree was ordered and
// after how many rounds.
uint place(uint i, bool ordered, bool odd_rounds) {
    if (!ordered) {
        return i;
    }
    uvec4 st = odd_rounds ? texelFetch(jump1, int(i)) : texelFetch(jump0, int(i));
    uint flags = st.w >> ORDER_FLAGS_SHIFT;
    bool placed = (st.x == 0u || st.x == BVH_INVALID) && (flags & ORDER_DEAD) == 0u && (flags & ORDER_LEN) == 0u;
    return placed && st.y < pc.node_count ? st.y : BVH_INVALID;
}

// A child link with an internal node's slot replaced by its place.
uint placed_link(uint c, bool ordered, bool odd_rounds) {
    return order_internal(c) ? place(c, ordered, odd_rounds) : c;
}

// A compressed wide node as it is made (bvh.glsl): the union of its children's boxes
// (the first pass), then their bytes and links (the second, on the node's grid).
struct Wide8 {
    vec3 lo;
    vec3 hi;
    vec3 g;
    vec3 st;
    uvec4 q0; // lo.x, lo.y: child j in byte j % 4 of word j / 4 of each pair
    uvec4 q1; // lo.z, hi.x
    uvec4 q2; // hi.y, hi.z
    uvec4 links0;
    uvec4 links1;
};

// Child j of the node, [lo, hi] with `link`, into pass `pass` of `w`.
void wide8_child(inout Wide8 w, uint pass, uint j, vec3 lo, vec3 hi, uint link, bool ordered, bool odd_rounds) {
    if (pass == 0u) {
        w.lo = min(w.lo, lo);
        w.hi = max(w.hi, hi);
        return;
    }
    uvec3 l = uvec3(grid_down(lo.x, w.g.x, w.st.x, GRID8), grid_down(lo.y, w.g.y, w.st.y, GRID8),
                    grid_down(lo.z, w.g.z, w.st.z, GRID8));
    uvec3 h = uvec3(grid_up(hi.x, w.g.x, w.st.x, GRID8), grid_up(hi.y, w.g.y, w.st.y, GRID8),
                    grid_up(hi.z, w.g.z, w.st.z, GRID8));
    uint shift = 8u * (j & 3u);
    uvec4 sel = j < 4u ? uvec4(1u, 0u, 1u, 0u) : uvec4(0u, 1u, 0u, 1u);
    w.q0 |= (uvec4(l.x, l.x, l.y, l.y) * sel) << shift;
    w.q1 |= (uvec4(l.z, l.z, h.x, h.x) * sel) << shift;
    w.q2 |= (uvec4(h.y, h.y, h.z, h.z) * sel) << shift;
    uint pl = placed_link(link, ordered, odd_rounds);
    if (j < 4u) {
        w.links0[j] = pl;
    } else {
        w.links1[j - 4u] = pl;
    }
}

// The compressed wide node of binary node n at texel `base`: n's children opened
// twice (cpu_ref::lbvh::wide8_entries), in order (a leaf as it is, an internal node's
// two children in its place), each internal one's link its place. Two passes over the
// subtree, reading its nodes again, instead of arrays of children (which lavapipe keeps
// in memory, read and written lane by lane).
void write_wide8(TraversalNode n, uint base, bool ordered, bool odd_rounds) {
    Wide8 w;
    w.lo = vec3(1.0 / 0.0);
    w.hi = vec3(-1.0 / 0.0);
    w.q0 = uvec4(0u);
    w.q1 = uvec4(0u);
    w.q2 = uvec4(0u);
    w.links0 = uvec4(BVH_INVALID);
    w.links1 = uvec4(BVH_INVALID);
    for (uint pass = 0u; pass < 2u; ++pass) {
        if (pass == 1u) {
            grid_over(w.lo, w.hi, GRID8, w.g, w.st);
        }
        uint j = 0u;
        for (uint a = 0u; a < 2u; ++a) {
            uint ca = a == 0u ? n.child0 : n.child1;
            if (!order_internal(ca)) {
                wide8_child(w, pass, j++, a == 0u ? n.lo0 : n.lo1, a == 0u ? n.hi0 : n.hi1, ca, ordered, odd_rounds);
                continue;
            }
            TraversalNode na = node_from_texels(nodes, ca);
            for (uint b = 0u; b < 2u; ++b) {
                uint cb = b == 0u ? na.child0 : na.child1;
                if (!order_internal(cb)) {
                    wide8_child(w, pass, j++, b == 0u ? na.lo0 : na.lo1, b == 0u ? na.hi0 : na.hi1, cb, ordered,
                                odd_rounds);
                    continue;
                }
                TraversalNode nb = node_from_texels(nodes, cb);
                wide8_child(w, pass, j++, nb.lo0, nb.hi0, nb.child0, ordered, odd_rounds);
                wide8_child(w, pass, j++, nb.lo1, nb.hi1, nb.child1, ordered, odd_rounds);
            }
        }
    }
    uvec3 ex = floatBitsToUint(w.st) >> 23u;
    compact[base] = uvec4(floatBitsToUint(w.g), ex.x | (ex.y << 8u) | (ex.z << 16u));
    compact[base + 1u] = w.q0;
    compact[base + 2u] = w.q1;
    compact[base + 3u] = w.q2;
    compact[base + 4u] = w.links0;
    compact[base + 5u] = w.links1;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    bool ordered = order_ordered(counts[0]);
    bool odd_rounds = (order_tree_rounds(counts[0]) & 1u) != 0u;
    TraversalNode root = node_from_texels(nodes, 0u);
    vec3 g, st;
    compact_grid(min(root.lo0, root.lo1), max(root.hi0, root.hi1), g, st);
    if (i == 0u) {
        compact[0] = uvec4(floatBitsToUint(g), pc.slots);
        compact[1] = uvec4(floatBitsToUint(st), 0u);
    }
    uint at = place(i, ordered, odd_rounds);
    if (at == BVH_INVALID) {
        return;
    }
    TraversalNode n = node_from_texels(nodes, i);
    if (pc.slots == WIDE8) {
        write_wide8(n, 2u + WIDE8_TEXELS * at, ordered, odd_rounds);
        return;
    }
    uint base = 2u + pc.slots * at;
    if (pc.slots == 2u) {
        compact[base] = compact_half(n.lo0, n.hi0, placed_link(n.child0, ordered, odd_rounds), g, st);
        compact[base + 1u] = compact_half(n.lo1, n.hi1, placed_link(n.child1, ordered, odd_rounds), g, st);
        return;
    }
    uint slot = 0u;
    for (uint side = 0u; side < 2u; ++side) {
        uint c = side == 0u ? n.child0 : n.child1;
        if ((c & BVH_LEAF_BIT) != 0u) {
            vec3 lo = side == 0u ? n.lo0 : n.lo1;
            vec3 hi = side == 0u ? n.hi0 : n.hi1;
            compact[base + slot] = compact_half(lo, hi, c, g, st);
            slot += 1u;
        } else {
            TraversalNode m = node_from_texels(nodes, c);
            compact[base + slot] = compact_half(m.lo0, m.hi0, placed_link(m.child0, ordered, odd_rounds), g, st);
            compact[base + slot + 1u] =
                compact_half(m.lo1, m.hi1, placed_link(m.child1, ordered, odd_rounds), g, st);
            slot += 2u;
        }
    }
    for (; slot < WIDE; ++slot) {
        compact[base + slot] = uvec4(0u, 0u, 0u, BVH_INVALID);
    }
}
