#version 460
// lbvh.ploc, round step 4: the clusters close ranks into the other array; the first
// of each mutual pair writes their node (both halves) into its slot (ploc.glsl), links
// both children to it, and goes on as the merged cluster (ploc_merged). Indirect:
// ceil(count / LBVH_WG) workgroups. A node's own parent link is written when it is
// merged in turn; so are its order counts (where pc.order).
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"
#define WG_SCAN_SIZE LBVH_WG
#include "wg_scan.glsl"

layout(local_size_x = LBVH_WG) in;

// The clusters as texels (ploc.glsl: cluster_from_texels).
layout(binding = 0) uniform utextureBuffer cluster_texels;
layout(binding = 1, std430) writeonly buffer NextClusters { Cluster next_clusters[]; };
layout(binding = 2, std430) readonly buffer Nearest { uint nearest[]; };
layout(binding = 3, std430) readonly buffer TileOffsets { uvec2 tile_offsets[]; };
layout(binding = 4, std430) readonly buffer State { PlocState state; };
layout(binding = 5, std430) buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 6, std430) buffer TTris { TraversalTri ttris[]; };
// The order counts (ploc.glsl: PLOC_WRITE_COUNTS).
layout(binding = 7, std430) buffer Counts { uvec4 counts[]; };

void main() {
    uint c = state.count[pc.parity];
    uint i = gl_GlobalInvocationID.x;
    bool keep = false, merge = false;
    uint j = 0u;
    if (i < c) {
        PLOC_FLAGS(nearest, i, k_, m_)
        keep = k_;
        merge = m_;
        j = nn_;
    }
    uint total;
    uint run = wg_exclusive_scan((keep ? 1u : 0u) | (merge ? 1u << 16 : 0u), total);
    if (!keep) {
        return;
    }
    uvec2 off = tile_offsets[gl_WorkGroupID.x];
    uint pos = off.x + (run & 0xffffu);
    Cluster a = cluster_from_texels(cluster_texels, i);
    if (!merge) {
        next_clusters[pos] = a;
        return;
    }
    Cluster b = cluster_from_texels(cluster_texels, j);
    uint slot = pc.n - 2u - (state.base_slot + off.y + (run >> 16));
    PLOC_WRITE_NODE(tnodes, ttris, slot, a, b)
    PLOC_WRITE_COUNTS(counts, slot, a, b)
    next_clusters[pos] = ploc_merged(a, b, slot);
}
