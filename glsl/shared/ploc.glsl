// lbvh.ploc's shared pieces (PLOC: Meister & Bittner 2018, "Parallel Locally-Ordered
// Clustering for Bounding Volume Hierarchy Construction"). Clusters are ping-ponged
// between two arrays in key order; each round: ploc_nearest (every cluster's nearest
// within PLOC_RADIUS positions), ploc_count (per tile: clusters kept, merges),
// ploc_scan (one workgroup: tile offsets, the next round's count and dispatch),
// ploc_scatter (merges write their node, clusters close ranks). The k-th merge of the
// build takes slot N-2-k, so the last one, the root, is slot 0. A merged cluster of
// at most BVH_LEAF_MAX triangles whose leaf positions are one run becomes a leaf where
// that costs no more SAH than its split (its node stays, out of the traversal's
// reach, as in the LBVH). The round's count
// and dispatch sizes live on the GPU (PlocState, indirect arguments), so a recorded
// round after the last merge does nothing. CPU reference: cpu_ref::lbvh::ploc.
#ifndef PLOC_GLSL
#define PLOC_GLSL
#include "bvh.glsl"

// A cluster: its box, its traversal reference (a leaf's range of triangles, or its
// node's slot), its subtree's SAH cost, its node in the binary tree (where its parent
// link goes: BVH_LEAF_BIT | position for one triangle, else its slot), and the leaf
// positions it covers (first, count; bit 31 of count set when they are not one run).
struct Cluster {
    vec3 lo;
    uint ref;
    vec3 hi;
    float cost;
    uint node;
    uint first;
    uint count;
    uint _pad0;
};

#define PLOC_SCATTERED 0x80000000u

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
// The parent link `link` into a cluster's node (`Cluster::node`), on the includer's
// buffers.
#define LINK_NODE(tnodes, ttris, node, link)                                              \
    {                                                                                     \
        uint node_ = (node);                                                              \
        if ((node_ & BVH_LEAF_BIT) != 0u) {                                               \
            ttris[node_ & ~BVH_LEAF_BIT].parent = (link);                                 \
        } else {                                                                          \
            tnodes[node_].parent = (link);                                                \
        }                                                                                 \
    }
#endif
