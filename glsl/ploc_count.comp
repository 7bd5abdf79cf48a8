#version 460
// lbvh.ploc, round step 2: per tile of LBVH_WG clusters, how many stay (kept in place
// or the first of a merged pair) and how many merges, packed (kept | merges << 16).
// Indirect: ceil(count / LBVH_WG) workgroups.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"
#define WG_SCAN_SIZE LBVH_WG
#include "wg_scan.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Nearest { uint nearest[]; };
layout(binding = 1, std430) writeonly buffer TileCounts { uint tile_counts[]; };
layout(binding = 2, std430) readonly buffer State { PlocState state; };

void main() {
    uint c = state.count[pc.parity];
    uint i = gl_GlobalInvocationID.x;
    uint packed = 0u;
    if (i < c) {
        PLOC_FLAGS(nearest, i, keep, merge)
        packed = (keep ? 1u : 0u) | (merge ? 1u << 16 : 0u);
    }
    uint total;
    wg_exclusive_scan(packed, total);
    if (gl_LocalInvocationID.x == 0u) {
        tile_counts[gl_WorkGroupID.x] = total;
    }
}
