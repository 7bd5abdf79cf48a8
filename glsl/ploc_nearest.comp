#version 460
// lbvh.ploc, round step 2: each cluster's nearest among the PLOC_RADIUS clusters on
// either side, by the area of their union box (ties to the smaller position), the
// areas read from ploc_areas (each pair's once: the same float either way, min and
// max being exact). Indirect: ceil(count / LBVH_WG) workgroups.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Areas { float areas[]; };
layout(binding = 1, std430) writeonly buffer Nearest { uint nearest[]; };
layout(binding = 2, std430) readonly buffer State { PlocState state; };

void main() {
    uint c = state.count[pc.parity];
    uint i = gl_GlobalInvocationID.x;
    if (i >= c) {
        return;
    }
    uint best = i;
    float best_area = 1.0 / 0.0;
    // In position order, as the CPU's loop: j below i (its area at j's row), then above.
    for (uint j = i >= PLOC_RADIUS ? i - PLOC_RADIUS : 0u; j < i; ++j) {
        float a = areas[(i - j - 1u) * pc.n + j];
        if (a < best_area) {
            best_area = a;
            best = j;
        }
    }
    uint last = min(c - 1u, i + PLOC_RADIUS);
    for (uint j = i + 1u; j <= last; ++j) {
        float a = areas[(j - i - 1u) * pc.n + i];
        if (a < best_area) {
            best_area = a;
            best = j;
        }
    }
    nearest[i] = best;
}
