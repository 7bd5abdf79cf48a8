#version 460
// lbvh.compact: the static walk's nodes made from a built (or refit) BVH (bvh.glsl: the
// layout, the grid over the root's box, the rounding outward), in one of two layouts
// (tracers::lbvh::StaticLayout), `slots` children a node:
// - 2, binary: node i's two children;
// - WIDE, wide: node i's children, each internal one opened into its two children (up
//   to WIDE, unused slots empty: link BVH_INVALID).
// Each node at its place in preorder (bvh_order.glsl: lbvh_order_* ran before), its
// children's links to their places; nodes not placed (inside a leaf; wide: at an odd
// depth, the opened children) are not written. A tree whose root has no counts keeps
// every node in its slot, as are the links.
// One invocation per binary node; the first also writes the header, whose first texel's
// w says `slots` to the walk. Mirrored by cpu_ref::lbvh::compact_nodes (tests/lbvh.rs).
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
layout(binding = 1, std430) writeonly buffer Compact { uvec4 compact[]; };
layout(binding = 2, std430) readonly buffer Counts { uvec4 counts[]; };
// The jump states after an even and after an odd count of rounds.
layout(binding = 3, std430) readonly buffer Jump0 { uvec4 jump0[]; };
layout(binding = 4, std430) readonly buffer Jump1 { uvec4 jump1[]; };

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
    uvec4 st = odd_rounds ? jump1[i] : jump0[i];
    bool placed = (st.x == 0u || st.x == BVH_INVALID) && (st.w & ORDER_DEAD) == 0u && (pc.slots == 2u || (st.w & ORDER_ODD) == 0u);
    return placed && st.y < pc.node_count ? st.y : BVH_INVALID;
}

// A child link with an internal node's slot replaced by its place.
uint placed_link(uint c, bool ordered, bool odd_rounds) {
    return order_internal(c) ? place(c, ordered, odd_rounds) : c;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    uint height = counts[0].z;
    bool ordered = height != 0u;
    bool odd_rounds = (order_rounds(height) & 1u) != 0u;
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
