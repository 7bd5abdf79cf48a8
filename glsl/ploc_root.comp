#version 460
// lbvh.ploc, after the rounds (one invocation): the last merge, the root, took slot
// N-2; it trades slots with slot 0 (bvh.glsl: the root is slot 0). The half that held
// slot 0 now holds N-2, and the children of both link to their new slots. Does
// nothing until one cluster is left (the caller records more rounds then).
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = 1) in;

layout(binding = 0, std430) readonly buffer State { PlocState state; };
layout(binding = 1, std430) buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 2, std430) buffer TTris { TraversalTri ttris[]; };


void link_children(uint s) {
    LINK_CHILD(tnodes, ttris, tnodes[s].child0, s << 1u);
    LINK_CHILD(tnodes, ttris, tnodes[s].child1, (s << 1u) | 1u);
}

void main() {
    if (pc.n < 2u || state.count[pc.parity] != 1u) {
        return;
    }
    uint root = pc.n - 2u;
    if (root != 0u) {
        TraversalNode top = tnodes[root];
        TraversalNode moved = tnodes[0];
        tnodes[0] = top;
        tnodes[root] = moved;
        uint p = moved.parent >> 1u;
        p = p == root ? 0u : p;
        if ((moved.parent & 1u) == 0u) {
            tnodes[p].child0 = root;
        } else {
            tnodes[p].child1 = root;
        }
        link_children(0u);
        link_children(root);
    }
    tnodes[0].parent = BVH_INVALID;
}
