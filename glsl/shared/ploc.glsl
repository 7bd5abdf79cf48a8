// lbvh.ploc's shared pieces (PLOC: Meister & Bittner 2018, "Parallel Locally-Ordered
// Clustering for Bounding Volume Hierarchy Construction"). Clusters are ping-ponged
// between two arrays in key order; each round: ploc_nearest (every cluster's nearest
// within PLOC_RADIUS positions), ploc_count (per tile: clusters kept, merges),
// ploc_scan (one workgroup: tile offsets, the next round's count and dispatch),
// ploc_scatter (merges write their node, clusters close ranks). The round's count
// and dispatch sizes live on the GPU (PlocState, indirect arguments), so a recorded
// round after the last merge does nothing. CPU reference: cpu_ref::lbvh::ploc.
#ifndef PLOC_GLSL
#define PLOC_GLSL
#include "bvh.glsl"

// A cluster: its box and its child reference (a leaf's, or its node's slot).
struct Cluster {
    vec3 lo;
    uint ref;
    vec3 hi;
    uint _pad0;
};

// The build's state. Round r reads count[r % 2] and writes count[(r + 1) % 2].
struct PlocState {
    uint count[2];
    uint next_slot; // slots taken by the merges so far
    uint base_slot; // the first slot of this round's merges
};

layout(push_constant) uniform Push {
    uint n;      // triangles
    uint parity; // the round's parity: clusters and counts it reads
} pc;

// A cluster's decision, from the nearest-neighbour array: kept (in place, or as the
// first of a merged pair) and merged (the first of a pair).
#define PLOC_FLAGS(nearest, i, keep, merge)                                              \
    uint nn_ = nearest[i];                                                                \
    bool mutual_ = nearest[nn_] == (i);                                                   \
    bool keep = !mutual_ || (i) < nn_;                                                    \
    bool merge = mutual_ && (i) < nn_;
// The parent link `link` into child `ref`'s node or triangle, on the includer's
// buffers.
#define LINK_CHILD(tnodes, ttris, ref, link)                                             \
    {                                                                                     \
        uint ref_ = (ref);                                                                \
        if ((ref_ & BVH_LEAF_BIT) != 0u) {                                                \
            ttris[bvh_leaf_first(ref_)].parent = (link);                                  \
        } else {                                                                          \
            tnodes[ref_].parent = (link);                                                 \
        }                                                                                 \
    }
#endif
