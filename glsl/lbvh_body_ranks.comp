#version 460
// lbvh.sort of a rigid-body rebuild (passes/lbvh/rigid.rs): each body's rank among
// the bodies ordered by (Morton code, body index), and the first slot of its triangles
// in key order (the triangles of the bodies ranked before it). Every invocation reads
// every body's code at the same index (one load for all lanes): bodies are few, and a
// rank needs no sort passes.
// CPU reference: cpu_ref::lbvh::rigid_keys (tests/lbvh.rs).
#include "types.glsl"

layout(local_size_x = LBVH_WG) in;

struct Body {
    vec3 center;
    uint tri_count;
};

layout(binding = 0, std430) readonly buffer Bodies { Body bodies[]; };
layout(binding = 1, std430) readonly buffer BodyKeys { uint body_keys[]; };
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
    uint key = body_keys[b];
    uint rank = 0u;
    uint first = 0u;
    for (uint j = 0u; j < pc.body_count; ++j) {
        uint k = body_keys[j];
        bool before = k < key || (k == key && j < b);
        rank += before ? 1u : 0u;
        first += before ? bodies[j].tri_count : 0u;
    }
    places[b] = uvec4(rank, first, key, 0u);
}
