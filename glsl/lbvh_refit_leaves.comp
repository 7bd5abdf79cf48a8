#version 460
// lbvh.refit (scheduled), first pass: every leaf's box from its triangle, and the
// triangle in the traversal layout (bvh.glsl); a single triangle's node too.
// CPU reference: cpu_ref::lbvh::fit, the scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Vertices { Vertex vertices[]; };
layout(binding = 1, std430) readonly buffer Indices { uint indices[]; };
layout(binding = 2, std430) buffer Nodes { BvhNode nodes[]; };
layout(binding = 3, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 4, std430) writeonly buffer TTris { TraversalTri ttris[]; };

layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= pc.n) {
        return;
    }
    FIT_LEAF(vertices, indices, nodes, tnodes, ttris, j, pc.n)
}
