#version 460
// lbvh.compact: the static walk's nodes made from a built (or refit) BVH (bvh.glsl: the
// layout, the grid over the root's box, the rounding outward), in one of two layouts
// (tracers::lbvh::StaticLayout), `slots` children a node:
// - 2, binary: node i's two children;
// - WIDE, wide: node i's children, each internal one opened into its two children (up
//   to WIDE, unused slots empty: link BVH_INVALID). The wide nodes of opened children
//   are written too and never walked (the walk reaches grandchildren only).
// One invocation per binary node; the first also writes the header, whose first texel's
// w says `slots` to the walk. Mirrored by cpu_ref::lbvh::compact_nodes (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
layout(binding = 1, std430) writeonly buffer Compact { uvec4 compact[]; };

layout(push_constant) uniform Push {
    uint node_count;
    uint slots;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    TraversalNode root = node_from_texels(nodes, 0u);
    vec3 g, st;
    compact_grid(min(root.lo0, root.lo1), max(root.hi0, root.hi1), g, st);
    if (i == 0u) {
        compact[0] = uvec4(floatBitsToUint(g), pc.slots);
        compact[1] = uvec4(floatBitsToUint(st), 0u);
    }
    TraversalNode n = node_from_texels(nodes, i);
    uint base = 2u + pc.slots * i;
    if (pc.slots == 2u) {
        compact[base] = compact_half(n.lo0, n.hi0, n.child0, g, st);
        compact[base + 1u] = compact_half(n.lo1, n.hi1, n.child1, g, st);
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
            compact[base + slot] = compact_half(m.lo0, m.hi0, m.child0, g, st);
            compact[base + slot + 1u] = compact_half(m.lo1, m.hi1, m.child1, g, st);
            slot += 2u;
        }
    }
    for (; slot < WIDE; ++slot) {
        compact[base + slot] = uvec4(0u, 0u, 0u, BVH_INVALID);
    }
}
