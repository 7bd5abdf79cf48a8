#version 460
// lbvh.bounds of a rigid-body rebuild (passes/lbvh/rigid.rs): each body's center in
// the world (its pose applied to its object-space center, unfused, in the order the
// CPU computes it), the bounds of those centers, and each body's 30-bit Morton code in
// them. One workgroup: bodies are few, and the bounds are one reduction. The codes'
// one division (the bounds' unit scale) is stored, so the reference uses the GPU's.
// CPU reference: cpu_ref::lbvh::rigid_keys (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = RIGID_WG) in;

struct Body {
    vec3 center; // object space
    uint tri_count;
};

layout(binding = 0, std430) readonly buffer Bodies { Body bodies[]; };
layout(binding = 1, std430) readonly buffer Poses { mat4 poses[]; };
layout(binding = 2, std430) writeonly buffer BodyKeys { uint body_keys[]; };
// The unit_scale of the centers' bounds the codes were made with (the codes' one
// division), for the CPU reference to multiply by (bvh.glsl: unit_scale).
layout(binding = 3, std430) writeonly buffer Scale { float scale_out[3]; };

layout(push_constant) uniform Push {
    uint body_count;
} pc;

shared vec3 s_lo[RIGID_WG];
shared vec3 s_hi[RIGID_WG];

vec3 world_center(uint b) {
    mat4 m = poses[b];
    vec3 p = bodies[b].center;
    precise vec3 c = ((m[0].xyz * p.x + m[1].xyz * p.y) + m[2].xyz * p.z) + m[3].xyz;
    return c;
}

void main() {
    uint l = gl_LocalInvocationID.x;
    vec3 lo = vec3(1.0 / 0.0), hi = vec3(-1.0 / 0.0);
    for (uint b = l; b < pc.body_count; b += RIGID_WG) {
        vec3 c = world_center(b);
        lo = min(lo, c);
        hi = max(hi, c);
    }
    s_lo[l] = lo;
    s_hi[l] = hi;
    barrier();
    if (l == 0u) {
        for (uint k = 1u; k < RIGID_WG; ++k) {
            lo = min(lo, s_lo[k]);
            hi = max(hi, s_hi[k]);
        }
        s_lo[0] = lo;
        s_hi[0] = unit_scale(lo, hi);
        scale_out[0] = s_hi[0].x;
        scale_out[1] = s_hi[0].y;
        scale_out[2] = s_hi[0].z;
    }
    barrier();
    lo = s_lo[0];
    vec3 scale = s_hi[0];
    for (uint b = l; b < pc.body_count; b += RIGID_WG) {
        body_keys[b] = morton30(unit_at(world_center(b), lo, scale));
    }
}
