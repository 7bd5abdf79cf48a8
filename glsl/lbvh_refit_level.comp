#version 460
// lbvh.refit (scheduled): the boxes of one height level of internal nodes (all their
// children are done), each the union of its children's.
// CPU reference: cpu_ref::lbvh::fit, the scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) buffer Nodes { BvhNode nodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };

layout(push_constant) uniform Push {
    uint first;
    uint count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    uint node = order[pc.first + i];
    uint l = nodes[node].left;
    uint r = nodes[node].right;
    nodes[node].lo = min(nodes[l].lo, nodes[r].lo);
    nodes[node].hi = max(nodes[l].hi, nodes[r].hi);
}
