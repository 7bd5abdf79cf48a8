#version 460
// lbvh.sort, step 1 of 3 per pass: the digit histogram of each tile, written
// digit-major (counts[digit * num_tiles + tile]) so that one exclusive scan of the
// whole array gives every (digit, tile) its first output position.
// CPU reference: cpu_ref::lbvh::sort_pairs, the whole sort (tests/lbvh.rs).
#include "radix.glsl"

layout(local_size_x_id = 1) in;

layout(binding = 0) uniform utextureBuffer keys;
layout(binding = 1, std430) writeonly buffer Counts { uint counts[]; };

shared uint s_hist[SORT_BINS];

void main() {
    uint l = gl_LocalInvocationID.x;
    uint tile = gl_WorkGroupID.x;
    if (l < SORT_BINS) {
        s_hist[l] = 0u;
    }
    barrier();
    uint base = tile * SORT_TILE + l * SORT_ITEMS;
    // This invocation's keys counted in registers (radix.glsl: count_digits), then
    // added to the tile's histogram once per digit.
    uvec4 h = count_digits(keys, base);
    for (uint d = 0u; d < SORT_BINS; ++d) {
        uint c = digit_count(h, d);
        if (c != 0u) {
            atomicAdd(s_hist[d], c);
        }
    }
    barrier();
    if (l < SORT_BINS) {
        counts[l * pc.num_tiles + tile] = s_hist[l];
    }
}
