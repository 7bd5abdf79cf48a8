#version 460
// lbvh.ploc, the last rounds (one workgroup): once at most PLOC_TAIL_CAP clusters are
// left, every remaining round runs here, in the rounds' order and with their slots, so
// the tree is the one the round kernels would build; the many small last rounds cost
// one dispatch in all instead of four each (ploc.glsl). The rounds hand over to it by
// dispatching nothing once the count is at most PLOC_TAIL_CAP; it does nothing while
// more are left (the caller records more rounds and this again) or one is. Clusters
// ping-pong between the two arrays, from the one the last round wrote
// (PlocState::live); a round is ploc_tail_round.glsl, its steps separated by workgroup
// barriers over `coherent` buffers. Ends with both counts at 1.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"
#define WG_SCAN_SIZE PLOC_TAIL_WG
#include "wg_scan.glsl"

layout(local_size_x = PLOC_TAIL_WG) in;

layout(binding = 0, std430) coherent buffer Clusters0 { Cluster clusters0[]; };
layout(binding = 1, std430) coherent buffer Clusters1 { Cluster clusters1[]; };
layout(binding = 2, std430) coherent buffer Nearest { uint nearest[]; };
layout(binding = 3, std430) buffer State { PlocState state; };
layout(binding = 4, std430) buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 5, std430) buffer TTris { TraversalTri ttris[]; };
// The order counts (ploc.glsl: PLOC_WRITE_COUNTS): a round reads those of earlier ones.
layout(binding = 6, std430) coherent buffer Counts { uvec4 counts[]; };

// The round's boxes (lo, hi), which its nearest-neighbour search reads 2 * PLOC_RADIUS
// times each: shared memory rather than the `coherent` cluster arrays.
shared float s_box[6u * PLOC_TAIL_CAP];
void tail_box(uint j, out vec3 lo, out vec3 hi) {
    lo = vec3(s_box[6u * j], s_box[6u * j + 1u], s_box[6u * j + 2u]);
    hi = vec3(s_box[6u * j + 3u], s_box[6u * j + 4u], s_box[6u * j + 5u]);
}

#define SRC clusters0
#define DST clusters1
#define ROUND round_forth
#include "ploc_tail_round.glsl"
#undef SRC
#undef DST
#undef ROUND
#define SRC clusters1
#define DST clusters0
#define ROUND round_back
#include "ploc_tail_round.glsl"

void main() {
    uint c = state.count[pc.parity];
    if (c <= 1u || c > PLOC_TAIL_CAP) {
        return;
    }
    uint merges = state.next_slot;
    // c, merges and forth are the same in every invocation: the loop's control flow is
    // uniform, as its barriers need.
    for (bool forth = state.live == 0u; c > 1u; forth = !forth) {
        if (forth) {
            c = round_forth(c, merges);
        } else {
            c = round_back(c, merges);
        }
    }
    if (gl_LocalInvocationID.x == 0u) {
        state.count[0] = 1u;
        state.count[1] = 1u;
        state.next_slot = merges;
    }
}
