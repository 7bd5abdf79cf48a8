#version 460
// lbvh.compact, its order's first step (bvh_order.glsl), after the builder's counts:
// each node's jump state of one step, to its parent: for each depth it may sit at mod
// P, 1 where that is 0 (the placed ancestor before it) plus, after an internal first
// sibling, that sibling's placed nodes (order_placed). Nothing for a tree that keeps
// its slots (order_ordered). The first invocation writes the jump rounds'
// indirect arguments: the rounds the root's height needs get the groups, the rest of
// those recorded none.
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
    uint slots;  // 2: binary, WIDE: wide, WIDE8: compressed wide (order_phases)
    uint rounds; // recorded jump rounds
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    if (i == 0u) {
        uint groups = (pc.node_count + LBVH_WG - 1u) / LBVH_WG;
        uint rounds = order_tree_rounds(counts[0]);
        for (uint r = 0u; r < pc.rounds; ++r) {
            args[r] = uvec4(r < rounds ? groups : 0u, 1u, 1u, 0u);
        }
    }
    if (!order_ordered(counts[0])) {
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
        jump[i] = uvec4(BVH_INVALID, 0u, 0u, ORDER_DEAD << ORDER_FLAGS_SHIFT);
        return;
    }
    uint phases = order_phases(pc.slots);
    uint sib = pn.child0;
    bool after = side == 1u && order_internal(sib);
    uvec4 c = after ? counts[sib] : uvec4(0u);
    uvec3 sum = uvec3(1u, 0u, 0u) + (after ? order_placed(c, phases) : uvec3(0u));
    jump[i] = uvec4(p, sum.x, sum.y, sum.z | ((1u % phases) << ORDER_FLAGS_SHIFT));
}
