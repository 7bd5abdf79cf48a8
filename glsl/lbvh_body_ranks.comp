#version 460
// lbvh.sort of a rigid-body rebuild (passes/lbvh/rigid.rs): each body's rank among
// the bodies ordered by (Morton code, body index), and the first slot of its triangles
// in key order (the triangles of the bodies ranked before it). Every invocation reads
// every body's code at the same index, four at a time (one fetch for all lanes): bodies
// are few, and a rank needs no sort passes.
// CPU reference: cpu_ref::lbvh::rigid_keys (tests/lbvh.rs).
#extension GL_EXT_samplerless_texture_functions : require
#include "types.glsl"

layout(local_size_x = LBVH_WG) in;

// Every body's code and triangle count, 4 to a texel (whole texels: the tail is
// padding, never counted).
layout(binding = 0) uniform utextureBuffer counts;
layout(binding = 1) uniform utextureBuffer body_keys;
// Per body: (rank, first triangle slot, Morton code, 0), read by lbvh_rigid_keys.comp as
// texels.
layout(binding = 2, std430) writeonly buffer Places { uvec4 places[]; };

layout(push_constant) uniform Push {
    uint body_count;
} pc;

void main() {
    uint b = gl_GlobalInvocationID.x;
    if (b >= pc.body_count) {
        return;
    }
    uint key = texelFetch(body_keys, int(b >> 2u))[b & 3u];
    uint rank = 0u;
    uint first = 0u;
    for (uint j = 0u; j < pc.body_count; j += 4u) {
        uvec4 k = texelFetch(body_keys, int(j >> 2u));
        uvec4 c = texelFetch(counts, int(j >> 2u));
        for (uint q = 0u; q < 4u; ++q) {
            uint i = j + q;
            bool before = i < pc.body_count && (k[q] < key || (k[q] == key && i < b));
            rank += before ? 1u : 0u;
            first += before ? c[q] : 0u;
        }
    }
    places[b] = uvec4(rank, first, key, 0u);
}
