#version 460
// lbvh.bounds: bounds of all triangle centroids (for Morton quantization) and of all
// triangles (the scene box). Workgroup reduction in shared memory, then one atomic
// per value per workgroup on order-preserving uints. The output must be reset to
// (min = 0xffffffff, max = 0) before the dispatch.
// CPU reference: cpu_ref::lbvh::bounds (tests/lbvh.rs).
#extension GL_EXT_control_flow_attributes : require
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Vertices { Vertex vertices[]; };
layout(binding = 1, std430) readonly buffer Indices { uint indices[]; };
// [0..2] center min, [3..5] center max, [6..8] scene min, [9..11] scene max.
layout(binding = 2, std430) buffer Bounds { uint bounds[15]; }; // 12-14: lbvh.morton's scale

layout(push_constant) uniform Push { uint tri_count; } pc;

shared vec3 s_cmin[LBVH_WG];
shared vec3 s_cmax[LBVH_WG];
shared vec3 s_smin[LBVH_WG];
shared vec3 s_smax[LBVH_WG];

void main() {
    uint l = gl_LocalInvocationID.x;
    vec3 cmin = vec3(3.4e38), cmax = vec3(-3.4e38), smin = vec3(3.4e38), smax = vec3(-3.4e38);
    // Each invocation folds LBVH_BOUNDS_ITEMS triangles (strided by the workgroup size,
    // so neighbouring invocations read neighbouring triangles) before the reduction.
    // Not unrolled: lavapipe runs an unrolled copy of the body per trip, masked, and
    // took 2x as long (1M triangles: 20 ms unrolled, 9-10 ms rolled, 16 per thread).
    uint first = gl_WorkGroupID.x * LBVH_WG * LBVH_BOUNDS_ITEMS + l;
    [[dont_unroll]] for (uint k = 0u; k < LBVH_BOUNDS_ITEMS; ++k) {
        uint t = first + k * LBVH_WG;
        if (t < pc.tri_count) {
            TRIANGLE_CORNERS_STORAGE(vertices, indices, t, a, b, c)
            vec3 center = (a + b + c) * (1.0 / 3.0);
            cmin = min(cmin, center);
            cmax = max(cmax, center);
            smin = min(smin, min(a, min(b, c)));
            smax = max(smax, max(a, max(b, c)));
        }
    }
    s_cmin[l] = cmin; s_cmax[l] = cmax; s_smin[l] = smin; s_smax[l] = smax;
    barrier();
    for (uint stride = LBVH_WG / 2u; stride > 0u; stride >>= 1) {
        if (l < stride) {
            s_cmin[l] = min(s_cmin[l], s_cmin[l + stride]);
            s_cmax[l] = max(s_cmax[l], s_cmax[l + stride]);
            s_smin[l] = min(s_smin[l], s_smin[l + stride]);
            s_smax[l] = max(s_smax[l], s_smax[l + stride]);
        }
        barrier();
    }
    if (l == 0u) {
        for (int k = 0; k < 3; ++k) {
            atomicMin(bounds[k], float_to_ordered(s_cmin[0][k]));
            atomicMax(bounds[3 + k], float_to_ordered(s_cmax[0][k]));
            atomicMin(bounds[6 + k], float_to_ordered(s_smin[0][k]));
            atomicMax(bounds[9 + k], float_to_ordered(s_smax[0][k]));
        }
    }
}
