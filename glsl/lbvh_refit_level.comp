#version 460
// lbvh.refit (scheduled): the boxes of one height level of internal nodes (all their
// children are done), each the union of its children's, and its traversal node.
// CPU reference: cpu_ref::lbvh::fit, the scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) buffer Nodes { BvhNode nodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };
layout(binding = 2, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };

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
    uint node = order[pc.first + i];
    UNITE(nodes, tnodes, node, pc.n)
}
