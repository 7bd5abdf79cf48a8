#version 460
// lbvh.ploc, round step 1: each cluster's union-box areas with the PLOC_RADIUS clusters
// after it, each pair's area computed once (ploc_nearest reads both sides of a cluster
// from here). areas[k * n + i]: cluster i with cluster i + k + 1, for k < PLOC_RADIUS
// and i + k + 1 < count (the rest unwritten, never read). Each box is read as 2 texels
// of the clusters. Indirect: ceil(count / LBVH_WG) workgroups.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = LBVH_WG) in;

// The clusters as texels (ploc.glsl: cluster_box_from_texels).
layout(binding = 0) uniform utextureBuffer cluster_texels;
layout(binding = 1, std430) writeonly buffer Areas { float areas[]; };
layout(binding = 2, std430) readonly buffer State { PlocState state; };

void main() {
    uint c = state.count[pc.parity];
    uint i = gl_GlobalInvocationID.x;
    if (i >= c) {
        return;
    }
    vec3 lo, hi;
    cluster_box_from_texels(cluster_texels, i, lo, hi);
    uint last = min(c - 1u, i + PLOC_RADIUS);
    for (uint j = i + 1u; j <= last; ++j) {
        vec3 jlo, jhi;
        cluster_box_from_texels(cluster_texels, j, jlo, jhi);
        areas[(j - i - 1u) * pc.n + i] = bvh_area(min(lo, jlo), max(hi, jhi));
    }
}
