#version 460
// lbvh.fit (and lbvh.refit): leaf boxes from the triangles, then bottom-up unions.
// Each leaf's invocation climbs towards the root; at every internal node the first
// child to arrive stops (atomic visit counter), the second computes the union and
// goes on, so each node is written exactly once, after both children (Karras 2012,
// section 4; Lauterbach et al. 2009). No invocation ever waits for another.
// The visit counters must be zero before the dispatch.
//
// Memory ordering: box stores are made visible to the sibling's invocation with
// memoryBarrierBuffer() on a `coherent` buffer, between the store and the visit
// (release) and between the visit and the loads (acquire). Each invocation climbs on
// its own (Apetrei 2014's bottom-up pass): no workgroup barrier, no vote, nothing
// waits. LOCKSTEP (a specialization, for lavapipe before Mesa 25: Mesa 22.3 treats a
// memory barrier in divergent flow like a workgroup barrier and loses invocations)
// climbs instead in steps whose trip count is workgroup-uniform, a vote ending the
// loop, so that every memory barrier sits in uniform control flow. The traversal layout (bvh.glsl) is written on the way: each leaf's
// triangle, and each internal node with its children's boxes by the invocation that
// unites them.
// CPU reference: cpu_ref::lbvh::fit (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Vertices { Vertex vertices[]; };
layout(binding = 1, std430) readonly buffer Indices { uint indices[]; };
layout(binding = 2, std430) coherent buffer Nodes { BvhNode nodes[]; };
layout(binding = 3, std430) readonly buffer Parents { uint parents[]; };
layout(binding = 4, std430) coherent buffer Visits { uint visits[]; };
layout(binding = 5, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 6, std430) writeonly buffer TTris { TraversalTri ttris[]; };

layout(push_constant) uniform Push { uint n; } pc;

// true: the climb in workgroup lockstep (see above).
layout(constant_id = 0) const bool LOCKSTEP = false;

// Triple-buffered vote flags of the lockstep climb: iteration k sets flag k%3 and
// clears flag (k+1)%3 for the next iteration, so one barrier per iteration suffices
// (flag (k+2)%3 was last read before the previous iteration's barrier).
shared uint s_vote[3];

// Leaf j's box and traversal triangle (and for a single triangle its node); returns
// the leaf's parent.
uint fit_leaf(uint j) {
    uint node = pc.n - 1u + j;
    uint prim = nodes[node].left & ~BVH_LEAF_BIT;
    TRIANGLE_CORNERS(vertices, indices, prim, a, b, c)
    vec3 lo = min(a, min(b, c)), hi = max(a, max(b, c));
    nodes[node].lo = lo;
    nodes[node].hi = hi;
    ttris[j] = TraversalTri(a, prim, b - a, 0u, c - a, 0u);
    if (pc.n == 1u) {
        tnodes[0] = traversal_node(0u, lo, hi, 0u, lo, hi, 1u); // both children: the leaf
    }
    return parents[node];
}

// The second child's invocation at `parent`: its box (and traversal node) from the
// children's; returns the next parent.
uint unite(uint parent) {
    uint l = nodes[parent].left;
    uint r = nodes[parent].right;
    vec3 l_lo = nodes[l].lo, l_hi = nodes[l].hi, r_lo = nodes[r].lo, r_hi = nodes[r].hi;
    nodes[parent].lo = min(l_lo, r_lo);
    nodes[parent].hi = max(l_hi, r_hi);
    tnodes[parent] = traversal_node(l, l_lo, l_hi, r, r_lo, r_hi, pc.n);
    return parents[parent];
}

void climb_free(uint j) {
    if (j >= pc.n) {
        return;
    }
    uint parent = fit_leaf(j);
    while (parent != BVH_INVALID) {
        // Release: this invocation's last box is visible before its visit is counted.
        memoryBarrierBuffer();
        if (atomicAdd(visits[parent], 1u) == 0u) {
            break; // first child here: the sibling's invocation continues
        }
        // Acquire: the sibling's box, stored before its visit, is visible now.
        memoryBarrierBuffer();
        parent = unite(parent);
    }
}

void climb_lockstep(uint j) {
    bool climbing = j < pc.n;
    uint parent = BVH_INVALID;
    if (climbing) {
        parent = fit_leaf(j);
        climbing = parent != BVH_INVALID;
    }
    if (gl_LocalInvocationID.x == 0u) {
        s_vote[0] = 0u;
    }
    barrier();
    for (uint it = 0u;; ++it) {
        memoryBarrierBuffer(); // release
        if (climbing && atomicAdd(visits[parent], 1u) == 0u) {
            climbing = false;
        }
        memoryBarrierBuffer(); // acquire
        if (climbing) {
            parent = unite(parent);
            climbing = parent != BVH_INVALID;
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
    if (LOCKSTEP) {
        climb_lockstep(gl_GlobalInvocationID.x);
    } else {
        climb_free(gl_GlobalInvocationID.x);
    }
}
