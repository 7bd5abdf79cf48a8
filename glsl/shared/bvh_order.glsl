// Where lbvh.compact puts each node (lbvh_order_*.comp): the static walk's nodes in
// preorder from the root, a node, then its first child's subtree, then its second's,
// so a walk that goes down reads the node just after the one it left. Only the nodes
// the walk can reach are placed: those at a depth divisible by the layout's phases P
// (order_phases: binary 1, every internal node; wide 2, those at an even depth, whose
// wide node's children are its grandchildren; compressed wide 3, its children three
// levels down). Nodes inside a leaf are not placed. Mirrored by
// cpu_ref::lbvh::compact_places (tests/lbvh.rs).
//
// 1. The builder, bottom-up as it makes the tree (lbvh.fit's climb, lbvh.ploc's
//    merges): each internal node's reachable internal nodes below it by depth, itself
//    at depth 0 (a leaf counting 0): at an even and an odd depth (A = 1 + B(child0) +
//    B(child1), B = A(child0) + A(child1)) and at depths 0, 1 and 2 mod 3 (M0 = 1 +
//    M2(child0) + M2(child1), M1 = M0(c0) + M0(c1), M2 = M1(c0) + M1(c1) = A + B - M0 -
//    M1), and its height H, in `counts` (a uvec4 a node: A, B, H | M0 << 8, M1;
//    order_counts: a count is below 2^24, and H stops at ORDER_H_MAX). A node is
//    counted as internal even where it became a leaf (its parent links the leaf, never
//    the node). The root's H says how many jump rounds run (order_tree_rounds, at most
//    order_rounds(ORDER_H_MAX - 1), all a build records). A tree whose root has no
//    counts (H = 0: nodes written by the host), or is ORDER_H_MAX or more deep, keeps
//    the nodes where they are.
// 2. lbvh_order_init: each node's step to its parent: what it adds to its place for
//    each depth it may sit at mod P (1 where that depth is 0 mod P, for the placed
//    ancestor before it, plus the placed nodes of its earlier sibling's subtree), as a
//    jump state (below); and the jump rounds' indirect arguments.
// 3. lbvh_order_jump, order_rounds(H) times: pointer jumping, each node's state
//    composed with its target's, until every target is the root: the place is the sum
//    along the path from the root.
//
// Jump state (uvec4): target node (0, the root, or BVH_INVALID, the root's own: the
// path is summed); the sums if the node sits at a depth 0, 1, 2 mod P (those past P
// unused), the third in the low 24 bits of w; w's top byte the flags: the path's
// length mod P (ORDER_LEN), ORDER_DEAD a node on the path not linked by its parent
// (inside a leaf).
#ifndef BVH_ORDER_GLSL
#define BVH_ORDER_GLSL

#define ORDER_FLAGS_SHIFT 24u
#define ORDER_LEN 3u
#define ORDER_DEAD 4u
#define ORDER_SUM_MASK 0xffffffu

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

// A node's height from its counts (0: none; ORDER_H_MAX, 255: that or more).
uint order_height(uvec4 c) {
    return c.z & ORDER_H_MAX;
}

// Whether the tree whose root has counts c is put in preorder: it has counts (H > 0,
// not nodes written by the host) and a height below ORDER_H_MAX, so that the rounds a
// build records (order_rounds(ORDER_H_MAX - 1) at most: lbvh::order::recorded_rounds)
// reach its deepest node. Else its nodes keep their slots, where a walk reads them as
// well (only its reads lie further apart); no tree the frame walks is that deep.
bool order_ordered(uvec4 c) {
    uint h = order_height(c);
    return h != 0u && h < ORDER_H_MAX;
}

// The jump rounds the tree whose root has counts c needs (lbvh_order_init dispatches
// them; lbvh.compact reads the last): none for a tree that keeps its slots.
uint order_tree_rounds(uvec4 c) {
    return order_ordered(c) ? order_rounds(order_height(c)) : 0u;
}

// A node's internal nodes at depths 0, 1, 2 mod 3 below it, from its counts.
uvec3 order_thirds(uvec4 c) {
    uint m0 = c.z >> 8u;
    return uvec3(m0, c.w, c.x + c.y - m0 - c.w);
}

// A node's counts from its children's (a leaf's are 0).
uvec4 order_counts(uvec4 c0, uvec4 c1) {
    uvec3 t0 = order_thirds(c0), t1 = order_thirds(c1);
    uint h = min(1u + max(order_height(c0), order_height(c1)), ORDER_H_MAX);
    return uvec4(1u + c0.y + c1.y, c0.x + c1.x, h | ((1u + t0.z + t1.z) << 8u), t0.x + t1.x);
}

// The counts of a single triangle's tree: its root, both halves the one leaf.
#define ORDER_ONE_LEAF uvec4(1u, 0u, 1u | (1u << 8u), 0u)

// The depth phases of a layout of `slots` children a node: the nodes placed are those
// at a depth divisible by it.
uint order_phases(uint slots) {
    return slots == WIDE ? 2u : (slots == WIDE8 ? 3u : 1u);
}

// The placed nodes of a subtree whose root (with counts c) sits at a depth 0, 1, 2 mod
// p, as a vector (those past p 0): selects, not a vector indexed per lane, which
// lavapipe keeps as a private array, read and written lane by lane.
uvec3 order_placed(uvec4 c, uint p) {
    if (p == 1u) {
        return uvec3(c.x + c.y, 0u, 0u);
    }
    if (p == 2u) {
        return uvec3(c.x, c.y, 0u);
    }
    return order_thirds(c).xzy;
}

// A jump state's sums for depths 0, 1, 2 mod p turned by `by` places (component k
// takes component (k + p - by) % p; those past p 0), by selects as order_placed.
uvec3 order_turned(uvec3 s, uint p, uint by) {
    uvec3 t = by == 0u ? s : (p == 2u ? s.yxz : (by == 1u ? s.zxy : s.yzx));
    return t * uvec3(1u, p > 1u ? 1u : 0u, p > 2u ? 1u : 0u);
}

#endif
