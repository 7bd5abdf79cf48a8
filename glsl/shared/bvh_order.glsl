// Where lbvh.compact puts each node (lbvh_order_*.comp): the static walk's nodes in
// preorder from the root, a node, then its first child's subtree, then its second's,
// so a walk that goes down reads the node just after the one it left. Binary (and
// compressed wide, whose walk reaches a third of them): every internal node the walk
// can reach; wide: those at an even depth (the wide nodes: a
// wide node's children are its binary node's grandchildren). Nodes inside a leaf are
// not placed. Mirrored by cpu_ref::lbvh::compact_places (tests/lbvh.rs).
//
// 1. The builder, bottom-up as it makes the tree (lbvh.fit's climb, lbvh.ploc's
//    merges): each internal node's reachable internal nodes at an even and at an odd
//    depth below it (A, B: A = 1 + B(child0) + B(child1), B = A(child0) + A(child1),
//    a leaf counting 0) and its height H, in `counts` (a uvec4 a node: A, B, H, 0;
//    order_counts). A node is counted as internal even where it became a leaf (its
//    parent links the leaf, never the node). The root's H says how many jump rounds
//    run. A tree whose root has no counts (H = 0: nodes written by the host) keeps the
//    nodes where they are.
// 2. lbvh_order_init: each node's step to its parent: what it adds to its place if it
//    sits at an even depth (1, plus the earlier siblings' subtrees) and if at an odd
//    one, as a jump state (below); and the jump rounds' indirect arguments.
// 3. lbvh_order_jump, order_rounds(H) times: pointer jumping, each node's state
//    composed with its target's, until every target is the root: the place is the sum
//    along the path from the root.
//
// Jump state (uvec4): target node (0, the root, or BVH_INVALID, the root's own: the
// path is summed), sum if the node
// sits at an even depth, sum if at an odd one, flags: bit 0 the path's length odd,
// ORDER_DEAD a node on the path not linked by its parent (inside a leaf).
#ifndef BVH_ORDER_GLSL
#define BVH_ORDER_GLSL

#define ORDER_ODD 1u
#define ORDER_DEAD 2u

// Jump rounds a tree of height h needs (the deepest node is h - 1 steps below the
// root; after init a state spans one step, after r rounds 2^r: a state whose target
// is the root is final).
uint order_rounds(uint h) {
    return h <= 2u ? 0u : uint(findMSB(h - 2u)) + 1u;
}

// Whether a child link is an internal node's (not a leaf's).
bool order_internal(uint c) {
    return (c & BVH_LEAF_BIT) == 0u;
}

// A node's (A, B, H) from its children's (a leaf's are 0).
uvec3 order_counts(uvec3 c0, uvec3 c1) {
    return uvec3(1u + c0.y + c1.y, c0.x + c1.x, 1u + max(c0.z, c1.z));
}

// The counts of a single triangle's tree: its root, both halves the one leaf.
#define ORDER_ONE_LEAF uvec4(1u, 0u, 1u, 0u)

#endif
