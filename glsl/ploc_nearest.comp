#version 460
// lbvh.ploc, round step 1: each cluster's nearest among the PLOC_RADIUS clusters on
// either side, by the area of their union box (ties to the smaller position), each
// box read as 2 texels of the clusters (branch-free fetches on lavapipe; reading the
// boxes from a window in shared memory, per lane and word, the PLOC stage took
// 1.17-1.22x as long on a 200K soup, the bunny and gallery). Indirect:
// ceil(count / LBVH_WG) workgroups.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = LBVH_WG) in;

// The clusters as texels of uvec4, 3 per cluster: lo and ref, hi and cost, the rest.
layout(binding = 0) uniform utextureBuffer cluster_texels;
layout(binding = 1, std430) writeonly buffer Nearest { uint nearest[]; };
layout(binding = 2, std430) readonly buffer State { PlocState state; };

void cluster_box(uint j, out vec3 lo, out vec3 hi) {
    lo = uintBitsToFloat(texelFetch(cluster_texels, int(3u * j)).xyz);
    hi = uintBitsToFloat(texelFetch(cluster_texels, int(3u * j + 1u)).xyz);
}

void main() {
    uint c = state.count[pc.parity];
    uint i = gl_GlobalInvocationID.x;
    if (i >= c) {
        return;
    }
    uint best;
    PLOC_NEAREST(cluster_box, i, c, best)
    nearest[i] = best;
}
