#version 460
// lbvh.fit: the tree and its boxes in one bottom-up pass (Apetrei 2014, "Fast and
// Simple Agglomerative LBVH Construction"). The tree is Karras 2012's binary radix tree
// of the sorted keys, equal keys told apart by their index (extended keys); its
// internal node that splits keys p | p+1 is written to the slot bvh.glsl gives it.
//
// One invocation per leaf climbs towards the root. A node covering keys [l, r] is the
// left child of split r when keys r, r+1 share a longer prefix than keys l-1, l, else
// the right child of split l-1. It writes its box and reference into its half of the
// parent's node, then swaps its outer end into the parent's `ends` word: the first
// child to arrive stops, the second reads its sibling's end and box, unites them and
// goes on as the parent. Each node is thus written once, by the invocation that unites
// it, and no invocation ever waits for another. The `ends` words must be BVH_INVALID
// before the dispatch.
//
// Leaves of up to BVH_LEAF_MAX triangles, chosen by SAH on the way up: each child also
// leaves its subtree's cost (unit costs for a node step and a triangle test, in area)
// beside its half, and the uniting invocation makes its node a leaf when that costs no
// more than the split (Karras & Aila 2013's collapse, decided bottom-up). A leaf is a
// range of triangles in key order; the node stays in its slot, linked to its parent,
// out of the traversal's reach (the refit still keeps its boxes, which it climbs).
//
// For a static BVH (pc.order), each node's counts for lbvh.compact's order too
// (bvh_order.glsl): the climber carries its subtree's (a leaf's are 0) and the uniting
// invocation reads its sibling's, written before the sibling's swap as its half is.
//
// Memory ordering: the half is made visible to the sibling's invocation with
// memoryBarrierBuffer() on `coherent` buffers, between the store and the swap
// (release) and between the swap and the loads (acquire). LOCKSTEP (a specialization,
// for lavapipe before Mesa 25: Mesa 22.3 treats a memory barrier in divergent flow
// like a workgroup barrier and loses invocations) climbs instead in steps whose trip
// count is workgroup-uniform, a vote ending the loop, so that every memory barrier
// sits in uniform control flow.
// CPU reference: cpu_ref::lbvh::build (tests/lbvh.rs).
#include "bvh.glsl"
#include "bvh_order.glsl"

layout(local_size_x = LBVH_WG) in;

// The triangles' vertices and indices as texels (bvh.glsl: TRIANGLE_CORNERS).
layout(binding = 0) uniform utextureBuffer vertices;
layout(binding = 1) uniform utextureBuffer indices;
layout(binding = 2, std430) readonly buffer Keys { uint keys[]; };
layout(binding = 3, std430) readonly buffer Values { uint values[]; };
layout(binding = 4, std430) coherent buffer Ends { uint ends[]; };
layout(binding = 5, std430) coherent buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 6, std430) writeonly buffer TTris { TraversalTri ttris[]; };
// The SAH cost of the subtree whose box is in each half, by link (2 per node).
layout(binding = 7, std430) coherent buffer Costs { float costs[]; };
// Each node's order counts (bvh_order.glsl), where pc.order.
layout(binding = 8, std430) coherent buffer Counts { uvec4 counts[]; };

layout(push_constant) uniform Push {
    uint n;         // triangles (leaves)
    uint key_words; // 1 or 2
    uint order;     // 1: write the order counts
} pc;

// true: the climb in workgroup lockstep (see above).
layout(constant_id = 0) const bool LOCKSTEP = false;

// Triple-buffered vote flags of the lockstep climb: iteration k sets flag k%3 and
// clears flag (k+1)%3 for the next iteration, so one barrier per iteration suffices
// (flag (k+2)%3 was last read before the previous iteration's barrier).
shared uint s_vote[3];

// Sorted key i extended by its index: (high word, low word, i); one-word keys have a
// zero high word.
uvec3 ext_key(uint i) {
    return pc.key_words == 2u ? uvec3(keys[2u * i + 1u], keys[2u * i], i) : uvec3(0u, keys[i], i);
}

// Length of the common prefix of two different extended keys.
int prefix(uvec3 a, uvec3 b) {
    uvec3 x = a ^ b;
    return x.x != 0u ? 31 - findMSB(x.x) : (x.y != 0u ? 63 - findMSB(x.y) : 95 - findMSB(x.z));
}

// Bit b of an extended key, counted from the top.
uint key_bit(uvec3 k, int b) {
    uint w = b < 32 ? k.x : (b < 64 ? k.y : k.z);
    return (w >> uint(31 - (b & 31))) & 1u;
}

// A node on its way up: its key range, the extended keys at its ends, its box, its
// subtree's SAH cost, its reference (a leaf's or its slot), its order counts, and the
// split of its parent.
struct Climber {
    uint l;
    uint r;
    uvec3 kl;
    uvec3 kr;
    vec3 lo;
    vec3 hi;
    float cost;
    uint ref;
    uvec4 counts; // order counts (bvh_order.glsl): 0 for a leaf
    uint p;
    bool left;
};

// The climber's parent: sets c.p and c.left, returns the link to the parent's half
// (bvh.glsl), or BVH_INVALID when the climber is the root. `root_bit`: the first bit
// in which the first and last extended keys differ; keys left of the root's split
// have it clear.
uint find_parent(inout Climber c, int root_bit) {
    int before = -1, after = -1;
    uvec3 k_before = uvec3(0u), k_after = uvec3(0u);
    if (c.l > 0u) {
        k_before = ext_key(c.l - 1u);
        before = prefix(k_before, c.kl);
    }
    if (c.r + 1u < pc.n) {
        k_after = ext_key(c.r + 1u);
        after = prefix(c.kr, k_after);
    }
    if (before < 0 && after < 0) {
        return BVH_INVALID;
    }
    c.left = after > before;
    c.p = c.left ? c.r : c.l - 1u;
    // Keys p and p + 1: the root's split is where root_bit turns from 0 to 1.
    uvec3 kp = c.left ? c.kr : k_before;
    uvec3 kq = c.left ? k_after : c.kl;
    uint slot = key_bit(kp, root_bit) == 1u ? c.p : (key_bit(kq, root_bit) == 1u ? 0u : c.p + 1u);
    return (slot << 1u) | (c.left ? 0u : 1u);
}

// The climber's box and reference into its half of the parent's node, its cost beside.
void store_half(Climber c, uint link) {
    uint slot = link >> 1u;
    costs[link] = c.cost;
    if ((link & 1u) == 0u) {
        tnodes[slot].lo0 = c.lo;
        tnodes[slot].child0 = c.ref;
        tnodes[slot].hi0 = c.hi;
    } else {
        tnodes[slot].lo1 = c.lo;
        tnodes[slot].child1 = c.ref;
        tnodes[slot].hi1 = c.hi;
    }
}

// The second child at its parent: the climber becomes the parent, covering up to the
// sibling's end `other` and the sibling's box, a leaf of its triangles when that
// costs no more than the split (bvh.glsl: bvh_collapse).
void unite(inout Climber c, uint link, uint other) {
    uint slot = link >> 1u;
    float sibling = costs[link ^ 1u];
    float left_cost = c.left ? c.cost : sibling;
    float right_cost = c.left ? sibling : c.cost;
    vec3 lo, hi;
    if (c.left) {
        lo = tnodes[slot].lo1;
        hi = tnodes[slot].hi1;
        c.r = other;
        c.kr = ext_key(other);
    } else {
        lo = tnodes[slot].lo0;
        hi = tnodes[slot].hi0;
        c.l = other;
        c.kl = ext_key(other);
    }
    c.lo = min(c.lo, lo);
    c.hi = max(c.hi, hi);
    uint count = c.r - c.l + 1u;
    bool leaf = bvh_collapse(bvh_area(c.lo, c.hi), left_cost, right_cost, count, true, c.cost);
    c.ref = leaf ? bvh_leaf_ref(c.l, count) : slot;
    if (pc.order != 0u) {
        uint sib = c.left ? tnodes[slot].child1 : tnodes[slot].child0;
        uvec4 v = order_counts(c.counts, order_internal(sib) ? counts[sib] : uvec4(0u));
        counts[slot] = v;
        c.counts = leaf ? uvec4(0u) : v;
    }
}

// Leaf j: its triangle in the traversal layout, and the climber it starts; returns the
// link to its parent's half (for a single triangle: the one node, written here whole).
uint start_leaf(uint j, int root_bit, out Climber c) {
    uint prim = values[j];
    TRIANGLE_CORNERS(vertices, indices, prim, a, b, v)
    c.l = j;
    c.r = j;
    c.kl = ext_key(j);
    c.kr = c.kl;
    c.lo = min(a, min(b, v));
    c.hi = max(a, max(b, v));
    c.cost = bvh_area(c.lo, c.hi);
    c.ref = bvh_leaf_ref(j, 1u);
    c.counts = uvec4(0u);
    c.p = 0u;
    c.left = true;
    uint link = pc.n == 1u ? 0u : find_parent(c, root_bit);
    ttris[j] = TraversalTri(a, prim, b, link, v, 0u);
    if (pc.n == 1u) {
        tnodes[0] = TraversalNode(c.lo, c.ref, c.hi, c.ref, c.lo, BVH_INVALID, c.hi, 0u);
        if (pc.order != 0u) {
            counts[0] = ORDER_ONE_LEAF;
        }
    }
    return link;
}

// The climber's outer end into the parent's `ends` word; returns the sibling's end,
// or BVH_INVALID when the climber is first at the parent.
uint swap_end(Climber c) {
    return atomicExchange(ends[c.p], c.left ? c.l : c.r);
}

// The second child at its parent goes on as the parent (unite), whose own link it
// writes; returns that link (BVH_INVALID at the root, where the climb ends).
uint go_up(inout Climber c, uint link, uint other, int root_bit) {
    unite(c, link, other);
    uint up = find_parent(c, root_bit);
    tnodes[link >> 1u].parent = up; // the node just united, also when it became a leaf
    return up;
}

void climb_free(uint j, int root_bit) {
    if (j >= pc.n) {
        return;
    }
    Climber c;
    uint link = start_leaf(j, root_bit, c);
    if (pc.n == 1u) {
        return;
    }
    while (link != BVH_INVALID) {
        store_half(c, link);
        memoryBarrierBuffer(); // release: the half is visible before the swap
        uint other = swap_end(c);
        if (other == BVH_INVALID) {
            break; // first child here: the sibling's invocation continues
        }
        memoryBarrierBuffer(); // acquire: the sibling's half, stored before its swap
        link = go_up(c, link, other, root_bit);
    }
}

void climb_lockstep(uint j, int root_bit) {
    bool climbing = j < pc.n;
    Climber c;
    uint link = BVH_INVALID;
    if (climbing) {
        link = start_leaf(j, root_bit, c);
        climbing = pc.n > 1u;
    }
    if (gl_LocalInvocationID.x == 0u) {
        s_vote[0] = 0u;
    }
    barrier();
    for (uint it = 0u;; ++it) {
        if (climbing) {
            store_half(c, link);
        }
        memoryBarrierBuffer(); // release
        uint other = BVH_INVALID;
        if (climbing) {
            other = swap_end(c);
            climbing = other != BVH_INVALID;
        }
        memoryBarrierBuffer(); // acquire
        if (climbing) {
            link = go_up(c, link, other, root_bit);
            climbing = link != BVH_INVALID;
        }
        // Workgroup vote: stop when no invocation of the group is still climbing.
        if (climbing) {
            s_vote[it % 3u] = 1u;
        }
        if (gl_LocalInvocationID.x == 0u) {
            s_vote[(it + 1u) % 3u] = 0u;
        }
        barrier();
        if (s_vote[it % 3u] == 0u) {
            break;
        }
    }
}

void main() {
    int root_bit = pc.n > 1u ? prefix(ext_key(0u), ext_key(pc.n - 1u)) : 0;
    if (LOCKSTEP) {
        climb_lockstep(gl_GlobalInvocationID.x, root_bit);
    } else {
        climb_free(gl_GlobalInvocationID.x, root_bit);
    }
}
