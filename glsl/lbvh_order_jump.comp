#version 460
// lbvh.compact, its order's jump round (bvh_order.glsl): each node's state composed
// with its target's, so its path to the root halves in steps. A state whose target
// is the root is final (the root's own adds nothing). Dispatched indirectly:
// lbvh_order_init gives the rounds a tree needs their groups and the rest none.
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer From { uvec4 from_state[]; };
layout(binding = 1, std430) writeonly buffer To { uvec4 to_state[]; };

layout(push_constant) uniform Push {
    uint node_count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    uvec4 me = from_state[i];
    if (me.x != 0u && me.x != BVH_INVALID) {
        uvec4 t = from_state[me.x];
        bool odd = (me.w & ORDER_ODD) != 0u;
        me = uvec4(t.x, me.y + (odd ? t.z : t.y), me.z + (odd ? t.y : t.z),
                   ((me.w ^ t.w) & ORDER_ODD) | ((me.w | t.w) & ORDER_DEAD));
    }
    to_state[i] = me;
}
