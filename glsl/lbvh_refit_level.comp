#version 460
// lbvh.refit (scheduled): one height level of internal nodes (all their children are
// done), each node's box, the union of its halves, into its parent's half (bvh.glsl,
// REFIT_NODE).
// CPU reference: cpu_ref::lbvh::build of the same keys over the moved vertices, the
// scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };
// The same nodes as texels (bvh.glsl: node_from_texels): this level reads halves the
// earlier levels wrote, 4 branch-free fetches on lavapipe instead of 13 per-lane word
// loads.
layout(binding = 2) uniform utextureBuffer node_texels;

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
    TraversalNode nd = node_from_texels(node_texels, slot);
    REFIT_UNION(tnodes, nd.parent, nd.lo0, nd.hi0, nd.lo1, nd.hi1)
}
