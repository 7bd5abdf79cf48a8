#version 460
// lbvh.ploc, round step 1: each cluster's nearest among the PLOC_RADIUS clusters on
// either side, by the area of their union box (ties to the smaller position), read
// from a window in shared memory. Indirect: ceil(count / LBVH_WG) workgroups.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Clusters { Cluster clusters[]; };
layout(binding = 1, std430) writeonly buffer Nearest { uint nearest[]; };
layout(binding = 2, std430) readonly buffer State { PlocState state; };

#define WINDOW (LBVH_WG + 2u * PLOC_RADIUS)
shared vec3 s_lo[WINDOW];
shared vec3 s_hi[WINDOW];

void main() {
    uint c = state.count[pc.parity];
    uint l = gl_LocalInvocationID.x;
    // The window starts PLOC_RADIUS before the workgroup's first cluster.
    int first = int(gl_WorkGroupID.x * LBVH_WG) - int(PLOC_RADIUS);
    for (uint k = l; k < WINDOW; k += LBVH_WG) {
        int g = first + int(k);
        if (g >= 0 && g < int(c)) {
            s_lo[k] = clusters[g].lo;
            s_hi[k] = clusters[g].hi;
        }
    }
    barrier();
    uint i = gl_GlobalInvocationID.x;
    if (i >= c) {
        return;
    }
    uint me = l + PLOC_RADIUS;
    vec3 lo = s_lo[me], hi = s_hi[me];
    uint lo_j = i >= PLOC_RADIUS ? i - PLOC_RADIUS : 0u;
    uint hi_j = min(c - 1u, i + PLOC_RADIUS);
    uint best = i;
    float best_area = 1.0 / 0.0;
    for (uint j = lo_j; j <= hi_j; ++j) {
        if (j == i) {
            continue;
        }
        uint k = j - i + me; // j's place in the window
        float a = bvh_area(min(lo, s_lo[k]), max(hi, s_hi[k]));
        if (a < best_area) {
            best_area = a;
            best = j;
        }
    }
    nearest[i] = best;
}
