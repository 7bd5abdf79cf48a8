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
#include "bvh_order.glsl"

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

// Cluster i from a cluster array seen as texels of uvec4, 3 a cluster (lo and ref, hi
// and cost, the rest): what the rounds read of the clusters the last round wrote
// (lavapipe loads a storage buffer lane by lane and word by word, each behind a
// branch). Its box alone: the first two texels.
void cluster_box_from_texels(utextureBuffer clusters, uint i, out vec3 lo, out vec3 hi) {
    lo = uintBitsToFloat(texelFetch(clusters, int(3u * i)).xyz);
    hi = uintBitsToFloat(texelFetch(clusters, int(3u * i + 1u)).xyz);
}

Cluster cluster_from_texels(utextureBuffer clusters, uint i) {
    uvec4 t0 = texelFetch(clusters, int(3u * i));
    uvec4 t1 = texelFetch(clusters, int(3u * i + 1u));
    uvec4 t2 = texelFetch(clusters, int(3u * i + 2u));
    return Cluster(uintBitsToFloat(t0.xyz), t0.w, uintBitsToFloat(t1.xyz), uintBitsToFloat(t1.w), t2.x, t2.y, t2.z,
                   t2.w);
}

#define PLOC_SCATTERED 0x80000000u

// The build's state. Round r reads count[r % 2] and writes count[(r + 1) % 2].
struct PlocState {
    uint count[2];
    uint next_slot; // slots taken by the merges so far
    uint base_slot; // the first slot of this round's merges
    uint live;      // the cluster array the last round that ran wrote (a round with at
                    // most PLOC_TAIL_CAP clusters leaves the arrays as they are)
};

layout(push_constant) uniform Push {
    uint n;      // triangles
    uint parity; // the round's parity: clusters and counts it reads
    uint order;  // 1: each merge writes its node's order counts (bvh_order.glsl)
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

// `best`: cluster i's nearest of the `c` among the PLOC_RADIUS on either side, by the
// area of their union box, ties to the smaller position; `box(j, lo, hi)` is the
// includer's read of a cluster's box.
#define PLOC_NEAREST(box, i, c, best)                                                     \
    {                                                                                     \
        vec3 lo_, hi_;                                                                    \
        box(i, lo_, hi_);                                                                 \
        uint last_ = min(c - 1u, i + PLOC_RADIUS);                                        \
        float best_area_ = 1.0 / 0.0;                                                     \
        best = i;                                                                         \
        for (uint j_ = i >= PLOC_RADIUS ? i - PLOC_RADIUS : 0u; j_ <= last_; ++j_) {      \
            if (j_ != i) {                                                                \
                vec3 jlo_, jhi_;                                                          \
                box(j_, jlo_, jhi_);                                                      \
                float a_ = bvh_area(min(lo_, jlo_), max(hi_, jhi_));                      \
                if (a_ < best_area_) {                                                    \
                    best_area_ = a_;                                                      \
                    best = j_;                                                            \
                }                                                                         \
            }                                                                             \
        }                                                                                 \
    }

// The first of a mutual pair `a`, `b` merged into node `slot`: the node's two halves and
// both children's parent links, on the includer's buffers.
#define PLOC_WRITE_NODE(tnodes, ttris, slot, a, b)                                        \
    {                                                                                     \
        tnodes[slot].lo0 = a.lo;                                                          \
        tnodes[slot].child0 = a.ref;                                                      \
        tnodes[slot].hi0 = a.hi;                                                          \
        tnodes[slot].child1 = b.ref;                                                      \
        tnodes[slot].lo1 = b.lo;                                                          \
        tnodes[slot].hi1 = b.hi;                                                          \
        LINK_NODE(tnodes, ttris, a.node, slot << 1u);                                     \
        LINK_NODE(tnodes, ttris, b.node, (slot << 1u) | 1u);                              \
    }

// Where pc.order: the order counts (bvh_order.glsl) of node `slot`, which `a` and `b`
// merge into, from theirs (written by their merges, in earlier rounds; a leaf's are 0),
// on the includer's `counts`.
#define PLOC_WRITE_COUNTS(counts, slot, a, b)                                             \
    if (pc.order != 0u) {                                                                 \
        uvec4 ca_ = order_internal(a.ref) ? counts[a.ref] : uvec4(0u);                    \
        uvec4 cb_ = order_internal(b.ref) ? counts[b.ref] : uvec4(0u);                    \
        counts[slot] = order_counts(ca_, cb_);                                            \
    }

// The cluster `a` and `b` merge into at node `slot`: a leaf when their triangles are one
// run of at most BVH_LEAF_MAX and that costs no more SAH than the split.
Cluster ploc_merged(Cluster a, Cluster b, uint slot) {
    vec3 lo = min(a.lo, b.lo), hi = max(a.hi, b.hi);
    uint count = (a.count & ~PLOC_SCATTERED) + (b.count & ~PLOC_SCATTERED);
    bool run_of_leaves = ((a.count | b.count) & PLOC_SCATTERED) == 0u
        && (a.first + a.count == b.first || b.first + b.count == a.first);
    uint first = min(a.first, b.first);
    float cost;
    bool leaf = bvh_collapse(bvh_area(lo, hi), a.cost, b.cost, count, run_of_leaves, cost);
    return Cluster(lo, leaf ? bvh_leaf_ref(first, count) : slot, hi, cost, slot, first,
                   count | (run_of_leaves ? 0u : PLOC_SCATTERED), 0u);
}
#endif
