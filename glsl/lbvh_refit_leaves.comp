#version 460
// lbvh.refit (scheduled), first pass: every leaf's box from its triangle.
// CPU reference: cpu_ref::lbvh::fit, the scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Vertices { Vertex vertices[]; };
layout(binding = 1, std430) readonly buffer Indices { uint indices[]; };
layout(binding = 2, std430) buffer Nodes { BvhNode nodes[]; };

layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= pc.n) {
        return;
    }
    uint node = pc.n - 1u + j;
    uint prim = nodes[node].left & ~BVH_LEAF_BIT;
    TRIANGLE_CORNERS(vertices, indices, prim, a, b, c)
    nodes[node].lo = min(a, min(b, c));
    nodes[node].hi = max(a, max(b, c));
}
