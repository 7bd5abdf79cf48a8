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
// loop, so that every memory barrier sits in uniform control flow. The traversal
// layout (bvh.glsl) is written on the way: each leaf's triangle, and each internal
// node with its children's boxes by the invocation that unites them.
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

// Leaf j's box and traversal triangle (bvh.glsl, FIT_LEAF); returns its parent.
uint fit_leaf(uint j) {
    FIT_LEAF(vertices, indices, nodes, tnodes, ttris, j, pc.n)
    return parents[pc.n - 1u + j];
}

// The second child's invocation at `parent`: its box and traversal node (UNITE);
// returns the next parent.
uint unite(uint parent) {
    UNITE(nodes, tnodes, parent, pc.n)
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
