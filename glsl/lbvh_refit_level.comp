#version 460
// lbvh.refit (scheduled): one height level of internal nodes (all their children are
// done), each node's box, the union of its halves, into its parent's half (bvh.glsl,
// REFIT_NODE).
// CPU reference: cpu_ref::lbvh::build of the same keys over the moved vertices, the
// scheduled refit as a whole (tests/lbvh.rs).
#extension GL_EXT_samplerless_texture_functions : require
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };
// The same nodes as texels of uvec4 (4 per node): this level reads halves the earlier
// levels wrote, 4 branch-free fetches on lavapipe instead of 13 per-lane word loads.
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
    uvec4 w0 = texelFetch(node_texels, int(4u * slot));
    uvec4 w1 = texelFetch(node_texels, int(4u * slot + 1u));
    uvec4 w2 = texelFetch(node_texels, int(4u * slot + 2u));
    uvec4 w3 = texelFetch(node_texels, int(4u * slot + 3u));
    uint link = w2.w;
    if (link != BVH_INVALID) {
        vec3 lo = min(uintBitsToFloat(w0.xyz), uintBitsToFloat(w2.xyz));
        vec3 hi = max(uintBitsToFloat(w1.xyz), uintBitsToFloat(w3.xyz));
        STORE_HALF(tnodes, link >> 1u, link & 1u, lo, hi)
    }
}
