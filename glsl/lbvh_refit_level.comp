#version 460
// lbvh.refit (scheduled): one height level of internal nodes (all their children are
// done), each node's box, the union of its halves, into its parent's half (bvh.glsl,
// REFIT_NODE).
// CPU reference: cpu_ref::lbvh::build of the same keys over the moved vertices, the
// scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };

layout(push_constant) uniform Push {
    uint first;
    uint count;
    uint n; // triangles
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    uint slot = order[pc.first + i];
    REFIT_NODE(tnodes, slot)
}
