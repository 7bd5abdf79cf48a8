#version 460
// lbvh.refit (scheduled), first pass: every leaf's triangle in the traversal layout
// from the moved vertices, and its box into its parent's half (bvh.glsl, REFIT_LEAF).
// CPU reference: cpu_ref::lbvh::build of the same keys over the moved vertices, the
// scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

// The triangles' vertices and indices as texels (bvh.glsl: TRIANGLE_CORNERS).
layout(binding = 0) uniform utextureBuffer vertices;
layout(binding = 1) uniform utextureBuffer indices;
layout(binding = 2, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 3, std430) buffer TTris { TraversalTri ttris[]; };

layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= pc.n) {
        return;
    }
    REFIT_LEAF(vertices, indices, tnodes, ttris, j, pc.n)
}
