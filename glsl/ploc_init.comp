#version 460
// lbvh.ploc, before the rounds: each triangle in key order into the BVH's triangles,
// and as a one-triangle leaf into the first cluster array; the state's count (N) and
// the first round's dispatch (none for at most PLOC_TAIL_CAP: ploc_tail.comp's); the
// root's parent link. A single triangle is its own tree (bvh.glsl).
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"

layout(local_size_x = LBVH_WG) in;

// The triangles' vertices and indices as texels (bvh.glsl: TRIANGLE_CORNERS).
layout(binding = 0) uniform utextureBuffer vertices;
layout(binding = 1) uniform utextureBuffer indices;
layout(binding = 2, std430) readonly buffer Values { uint values[]; };
layout(binding = 3, std430) writeonly buffer Clusters { Cluster clusters[]; };
layout(binding = 4, std430) writeonly buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 5, std430) writeonly buffer TTris { TraversalTri ttris[]; };
layout(binding = 6, std430) writeonly buffer State { PlocState state; };
layout(binding = 7, std430) writeonly buffer Args { uvec3 args; };
// The order counts, written here only for a single triangle (ploc.glsl).
layout(binding = 8, std430) writeonly buffer Counts { uvec4 counts[]; };

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j == 0u) {
        state.count[0] = pc.n;
        state.next_slot = 0u;
        state.live = 0u;
        args = uvec3(pc.n > PLOC_TAIL_CAP ? (pc.n + LBVH_WG - 1u) / LBVH_WG : 0u, 1u, 1u);
    }
    if (j >= pc.n) {
        return;
    }
    uint prim = values[j];
    TRIANGLE_CORNERS(vertices, indices, prim, a, b, c)
    vec3 lo = min(a, min(b, c)), hi = max(a, max(b, c));
    uint leaf = bvh_leaf_ref(j, 1u);
    // The parent link is written by the merge (0 for a single triangle).
    ttris[j] = TraversalTri(a, prim, b, 0u, c, 0u);
    clusters[j] = Cluster(lo, leaf, hi, bvh_area(lo, hi), leaf, j, 1u, 0u);
    if (pc.n == 1u) {
        tnodes[0] = TraversalNode(lo, leaf, hi, leaf, lo, BVH_INVALID, hi, 0u);
        if (pc.order != 0u) {
            counts[0] = ORDER_ONE_LEAF;
        }
    } else if (j == 0u) {
        tnodes[0].parent = BVH_INVALID; // the root, the last merge, is never linked
    }
}
