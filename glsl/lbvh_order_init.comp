#version 460
// lbvh.compact, its order's first step (bvh_order.glsl), after the builder's counts:
// each node's jump state of one step, to its parent. A node after an internal first
// sibling adds that sibling's subtree: binary and compressed wide, all its nodes (A + B); wide, at an even
// depth its wide nodes (A) and at an odd one those of its children (B). Nothing when
// the root has no counts (the nodes stay in place). The first invocation writes the
// jump rounds' indirect arguments: the rounds the root's height needs get the groups,
// the rest of those recorded none.
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
layout(binding = 1, std430) readonly buffer Counts { uvec4 counts[]; };
layout(binding = 2, std430) writeonly buffer Jump { uvec4 jump[]; };
// The jump rounds' VkDispatchIndirectCommands, 4 words apart.
layout(binding = 3, std430) writeonly buffer Args { uvec4 args[]; };

layout(push_constant) uniform Push {
    uint node_count;
    uint slots;  // 2: binary, WIDE: wide, WIDE8: compressed wide (placed as binary)
    uint rounds; // recorded jump rounds
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    uint height = counts[0].z;
    if (i == 0u) {
        uint groups = (pc.node_count + LBVH_WG - 1u) / LBVH_WG;
        uint rounds = order_rounds(height);
        for (uint r = 0u; r < pc.rounds; ++r) {
            args[r] = uvec4(r < rounds ? groups : 0u, 1u, 1u, 0u);
        }
    }
    if (height == 0u) {
        return;
    }
    if (i == 0u) {
        jump[0] = uvec4(BVH_INVALID, 0u, 0u, 0u);
        return;
    }
    TraversalNode n = node_from_texels(nodes, i);
    uint p = n.parent >> 1u;
    uint side = n.parent & 1u;
    TraversalNode pn = node_from_texels(nodes, min(p, pc.node_count - 1u));
    if (n.parent == BVH_INVALID || p >= pc.node_count || (side == 0u ? pn.child0 : pn.child1) != i) {
        jump[i] = uvec4(BVH_INVALID, 0u, 0u, ORDER_DEAD);
        return;
    }
    uint sib = pn.child0;
    uvec2 ab = uvec2(0u);
    if (side == 1u && order_internal(sib)) {
        ab = counts[sib].xy;
    }
    uint even = 1u + (pc.slots != WIDE ? ab.x + ab.y : ab.x);
    uint odd = pc.slots != WIDE ? even : ab.y;
    jump[i] = uvec4(p, even, odd, ORDER_ODD);
}
