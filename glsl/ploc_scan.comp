#version 460
// lbvh.ploc, round step 3 (one workgroup): each tile's first kept position and first
// merge, the next round's count and dispatch (none once at most PLOC_TAIL_CAP clusters
// are left: ploc_tail.comp's), and the slots this round's merges take. Each invocation sums a run of consecutive tiles.
// CPU reference: cpu_ref::lbvh::ploc (tests/lbvh.rs).
#include "ploc.glsl"
#define WG_SCAN_SIZE PLOC_SCAN_WG
#include "wg_scan.glsl"

layout(local_size_x = PLOC_SCAN_WG) in;

layout(binding = 0, std430) readonly buffer TileCounts { uint tile_counts[]; };
layout(binding = 1, std430) writeonly buffer TileOffsets { uvec2 tile_offsets[]; };
layout(binding = 2, std430) buffer State { PlocState state; };
layout(binding = 3, std430) writeonly buffer NextArgs { uvec3 next_args; };

void main() {
    uint c = state.count[pc.parity];
    uint tiles = c > PLOC_TAIL_CAP ? (c + LBVH_WG - 1u) / LBVH_WG : 0u;
    uint l = gl_LocalInvocationID.x;
    uint per = (tiles + PLOC_SCAN_WG - 1u) / PLOC_SCAN_WG;
    uint first = l * per, last = min(tiles, first + per);
    uint keep = 0u, merge = 0u;
    for (uint t = first; t < last; ++t) {
        keep += tile_counts[t] & 0xffffu;
        merge += tile_counts[t] >> 16;
    }
    uint keep_total, merge_total;
    uint keep_run = wg_exclusive_scan(keep, keep_total);
    uint merge_run = wg_exclusive_scan(merge, merge_total);
    for (uint t = first; t < last; ++t) {
        tile_offsets[t] = uvec2(keep_run, merge_run);
        keep_run += tile_counts[t] & 0xffffu;
        merge_run += tile_counts[t] >> 16;
    }
    if (l == 0u) {
        uint next = tiles == 0u ? c : keep_total;
        state.count[1u - pc.parity] = next;
        state.base_slot = state.next_slot;
        state.next_slot += merge_total;
        if (tiles != 0u) {
            state.live = 1u - pc.parity;
        }
        next_args = uvec3(next > PLOC_TAIL_CAP ? (next + LBVH_WG - 1u) / LBVH_WG : 0u, 1u, 1u);
    }
}
