#version 460
// ssr.compact, step 2 of 3: exclusive scan of the tile counts (one workgroup), the
// total, and the indirect dispatch arguments of the pass that consumes the list.
// CPU reference: cpu_ref::compact::compact, the whole list (tests/compact.rs).
#include "compact.glsl"
#define WG_SCAN_SIZE COMPACT_WG
#include "wg_scan.glsl"

layout(local_size_x = COMPACT_WG) in;

layout(binding = 0, std430) buffer TileCounts { uint tile_counts[]; };
// indirect: x, y, z a VkDispatchIndirectCommand for RT_LIST_WG-wide workgroups, w the
// count; trace_rays: x, y, z a VkTraceRaysIndirectCommandKHR of one ray per entry (the
// vendor tracer's launch), w unused.
layout(binding = 1, std430) writeonly buffer Indirect {
    uvec4 indirect;
    uvec4 trace_rays;
};

void main() {
    uint l = gl_LocalInvocationID.x;
    uint m = pc.num_tiles;
    uint per = (m + COMPACT_WG - 1u) / COMPACT_WG;
    uint begin = min(l * per, m);
    uint end = min(begin + per, m);
    uint sum = 0u;
    for (uint i = begin; i < end; ++i) {
        sum += tile_counts[i];
    }
    uint total;
    uint running = wg_exclusive_scan(sum, total);
    for (uint i = begin; i < end; ++i) {
        uint c = tile_counts[i];
        tile_counts[i] = running;
        running += c;
    }
    if (l == 0u) {
        indirect = uvec4(list_groups((total + RT_LIST_WG - 1u) / RT_LIST_WG), 1u, total);
        trace_rays = uvec4(total, 1u, 1u, 0u);
    }
}
