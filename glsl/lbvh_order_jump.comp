#version 460
// lbvh.compact, its order's jump round (bvh_order.glsl): each node's state composed
// with its target's, so its path to the root halves in steps. A state whose target
// is the root is final (the root's own adds nothing). Dispatched indirectly:
// lbvh_order_init gives the rounds a tree needs their groups and the rest none. The
// states are read as texels (written by the dispatch before): lavapipe loads a storage
// buffer lane by lane and word by word, each behind a branch.
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer from_state;
layout(binding = 1, std430) writeonly buffer To { uvec4 to_state[]; };

layout(push_constant) uniform Push {
    uint node_count;
    uint slots; // the layout's (order_phases)
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    uvec4 me = texelFetch(from_state, int(i));
    if (me.x != 0u && me.x != BVH_INVALID) {
        uint p = order_phases(pc.slots);
        uvec4 t = texelFetch(from_state, int(me.x));
        uint lm = (me.w >> ORDER_FLAGS_SHIFT) & ORDER_LEN;
        uint lt = (t.w >> ORDER_FLAGS_SHIFT) & ORDER_LEN;
        // The target sits lm steps above: where this node's depth is k mod p, its is
        // k - lm.
        uvec3 ms = uvec3(me.yz, me.w & ORDER_SUM_MASK), ts = uvec3(t.yz, t.w & ORDER_SUM_MASK);
        uvec3 sum = ms + order_turned(ts, p, lm); // both 0 past p
        uint flags = ((lm + lt) % p) | (((me.w | t.w) >> ORDER_FLAGS_SHIFT) & ORDER_DEAD);
        me = uvec4(t.x, sum.x, sum.y, sum.z | (flags << ORDER_FLAGS_SHIFT));
    }
    to_state[i] = me;
}
