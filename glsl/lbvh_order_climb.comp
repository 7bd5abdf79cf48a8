#version 460
// lbvh.compact, its order's first step (bvh_order.glsl): each reachable node's A, B
// and H, bottom-up. One invocation per node whose children are both leaves climbs
// through its parent links; at a parent with two internal children the first to
// arrive stops and the second goes on (the arrivals word, zeroed before the
// dispatch), as lbvh.fit's climb. A node its parent does not link back (inside a
// leaf, or a corrupted link) stops the climb; a climb is bounded by the node count.
// The root's climber writes the jump rounds' indirect arguments (zeroed before: a
// root never reached runs no rounds).
// Memory ordering: the counts are made visible to the sibling's invocation with
// memoryBarrierBuffer() on a `coherent` buffer between the stores and the atomic
// (release) and between the atomic and the loads (acquire).
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
// 4 words a node: A, B, H, arrivals.
layout(binding = 1, std430) coherent buffer Counts { uint counts[]; };
// The jump rounds' VkDispatchIndirectCommands, 4 words apart.
layout(binding = 2, std430) writeonly buffer Args { uvec4 args[]; };

layout(push_constant) uniform Push {
    uint node_count;
    uint rounds; // recorded jump rounds
} pc;

// A child's (A, B, H): a leaf's are 0.
uvec3 child_counts(uint c) {
    return order_internal(c) ? uvec3(counts[4u * c], counts[4u * c + 1u], counts[4u * c + 2u]) : uvec3(0u);
}

void main() {
    uint s = gl_GlobalInvocationID.x;
    if (s >= pc.node_count) {
        return;
    }
    TraversalNode n = node_from_texels(nodes, s);
    if (order_internal(n.child0) || order_internal(n.child1)) {
        return;
    }
    uvec3 v = uvec3(1u, 0u, 1u);
    for (uint step = 0u; step < pc.node_count; ++step) {
        counts[4u * s] = v.x;
        counts[4u * s + 1u] = v.y;
        counts[4u * s + 2u] = v.z;
        if (n.parent == BVH_INVALID) {
            if (s == 0u) {
                uint groups = (pc.node_count + LBVH_WG - 1u) / LBVH_WG;
                uint rounds = order_rounds(v.z);
                for (uint r = 0u; r < pc.rounds; ++r) {
                    args[r] = uvec4(r < rounds ? groups : 0u, 1u, 1u, 0u);
                }
            }
            return;
        }
        uint p = n.parent >> 1u;
        if (p >= pc.node_count) {
            return;
        }
        TraversalNode pn = node_from_texels(nodes, p);
        if (((n.parent & 1u) == 0u ? pn.child0 : pn.child1) != s) {
            return; // inside a leaf: its parent links a leaf there
        }
        uint internal = uint(order_internal(pn.child0)) + uint(order_internal(pn.child1));
        memoryBarrierBuffer(); // release: the counts are visible before the arrival
        if (atomicAdd(counts[4u * p + 3u], 1u) + 1u < internal) {
            return; // first child here: the sibling's invocation goes on
        }
        memoryBarrierBuffer(); // acquire: the sibling's counts, stored before its arrival
        uvec3 a = child_counts(pn.child0);
        uvec3 b = child_counts(pn.child1);
        v = uvec3(1u + a.y + b.y, a.x + b.x, 1u + max(a.z, b.z));
        s = p;
        n = pn;
    }
}
