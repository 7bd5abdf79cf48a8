// BVH node layout (src/gpu_types.rs: BvhNode), shared by the LBVH kernels and the
// traversal. A BVH over N triangles has 2N-1 nodes: internal nodes 0..N-2 (node 0 is
// the root), leaves N-1..2N-2 (for N = 1 the root is the single leaf).
//
//   node: | lo.x lo.y lo.z | left  | hi.x hi.y hi.z | right |   32 bytes
//   internal: left/right = child node indices
//   leaf:     left = BVH_LEAF_BIT | triangle id, right = BVH_INVALID
//
// The traversal reads a layout the fit and the refit write beside it (src/gpu_types.rs:
// TraversalNode, TraversalTri): N-1 internal nodes (one for N = 1, whose two children
// are that leaf), each holding both children's boxes, written by the invocation that
// computes the node's own box, and the N triangles in leaf order, written with the
// leaf boxes.
//
//   traversal node: | lo0 | child0 | hi0 | child1 | lo1 | 0 | hi1 | 0 |   64 bytes
//   child: an internal node's index, or BVH_LEAF_BIT | the leaf's position
//   traversal triangle: | a | triangle id | b - a | 0 | c - a | 0 |      48 bytes
#ifndef BVH_GLSL
#define BVH_GLSL
#include "types.glsl"

struct BvhNode {
    vec3 lo;
    uint left;
    vec3 hi;
    uint right;
};

struct TraversalNode {
    vec3 lo0;
    uint child0;
    vec3 hi0;
    uint child1;
    vec3 lo1;
    uint _pad0;
    vec3 hi1;
    uint _pad1;
};

struct TraversalTri {
    vec3 a;
    uint id;
    vec3 e1;
    uint _pad0;
    vec3 e2;
    uint _pad1;
};

// The traversal layout's link to node c of a tree over n triangles: internal nodes keep
// their index, leaves become their position in leaf order.
uint traversal_ref(uint c, uint n) {
    return c < n - 1u ? c : (BVH_LEAF_BIT | (c - (n - 1u)));
}

// The traversal node of an internal node with children `l`, `r` and their boxes.
TraversalNode traversal_node(uint l, vec3 l_lo, vec3 l_hi, uint r, vec3 r_lo, vec3 r_hi, uint n) {
    return TraversalNode(l_lo, traversal_ref(l, n), l_hi, traversal_ref(r, n), r_lo, 0u, r_hi, 0u);
}

// The fit's and the refits' two steps, on the includer's buffers (GLSL cannot pass a
// buffer to a function): `nodes` (BvhNode), `tnodes` (TraversalNode), `ttris`
// (TraversalTri), over a tree of `n` triangles.
//
// FIT_LEAF: leaf j (node n - 1 + j) gets its triangle's box, and its traversal triangle;
// a single triangle also gets the one traversal node, whose two children are that leaf.
#define FIT_LEAF(vertices, indices, nodes, tnodes, ttris, j, n)                          \
    {                                                                                     \
        uint leaf_ = (n) - 1u + (j);                                                      \
        uint prim_ = nodes[leaf_].left & ~BVH_LEAF_BIT;                                   \
        TRIANGLE_CORNERS(vertices, indices, prim_, a_, b_, c_)                            \
        vec3 lo_ = min(a_, min(b_, c_)), hi_ = max(a_, max(b_, c_));                      \
        nodes[leaf_].lo = lo_;                                                            \
        nodes[leaf_].hi = hi_;                                                            \
        ttris[j] = TraversalTri(a_, prim_, b_ - a_, 0u, c_ - a_, 0u);                     \
        if ((n) == 1u) {                                                                  \
            tnodes[0] = traversal_node(0u, lo_, hi_, 0u, lo_, hi_, 1u);                   \
        }                                                                                 \
    }
// UNITE: internal node `node`'s box, the union of its children's, and its traversal
// node.
#define UNITE(nodes, tnodes, node, n)                                                     \
    {                                                                                     \
        uint l_ = nodes[node].left, r_ = nodes[node].right;                               \
        vec3 l_lo_ = nodes[l_].lo, l_hi_ = nodes[l_].hi;                                  \
        vec3 r_lo_ = nodes[r_].lo, r_hi_ = nodes[r_].hi;                                  \
        nodes[node].lo = min(l_lo_, r_lo_);                                               \
        nodes[node].hi = max(l_hi_, r_hi_);                                               \
        tnodes[node] = traversal_node(l_, l_lo_, l_hi_, r_, r_lo_, r_hi_, (n));           \
    }

// Float <-> uint mapping that preserves order, so atomicMin/atomicMax on uint act as
// float min/max (negative floats: all bits flipped; positive: the sign bit set).
uint float_to_ordered(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
float ordered_to_float(uint u) {
    return uintBitsToFloat((u & 0x80000000u) != 0u ? (u & 0x7fffffffu) : ~u);
}

// The three corners of triangle `t` from an indexed vertex buffer.
#define TRIANGLE_CORNERS(vertices, indices, t, a, b, c)                                 \
    vec3 a = vertices[indices[3u * (t)]].position;                                      \
    vec3 b = vertices[indices[3u * (t) + 1u]].position;                                 \
    vec3 c = vertices[indices[3u * (t) + 2u]].position;
#endif
