#version 460
// lbvh.sort, step 2 of 3 per pass: exclusive prefix sum of the digit-major tile
// histograms, in place, by a single workgroup (the array holds SORT_BINS entries per
// tile: for 1M keys, 4096 entries in a GPU's tiles of 4K keys, 2048 in a CPU device's
// tiles of 8K). Each invocation sums a contiguous segment, the workgroup scans the
// segment sums, each segment is rewritten with its offset. No workgroup waits on
// another. Not run for a sort of few tiles, whose scatter finds its offsets itself
// (radix_scatter.comp: FUSED_TILES).
// CPU reference: cpu_ref::lbvh::sort_pairs, the whole sort (tests/lbvh.rs).
#include "radix.glsl"
#define WG_SCAN_SIZE SORT_WG
#include "wg_scan.glsl"

layout(local_size_x_id = 1) in;

layout(binding = 0, std430) buffer Counts { uint counts[]; };

void main() {
    uint l = gl_LocalInvocationID.x;
    uint m = SORT_BINS * pc.num_tiles;
    uint per = (m + SORT_WG - 1u) / SORT_WG;
    uint begin = min(l * per, m);
    uint end = min(begin + per, m);
    uint sum = 0u;
    for (uint i = begin; i < end; ++i) {
        sum += counts[i];
    }
    uint total;
    uint running = wg_exclusive_scan(sum, total);
    for (uint i = begin; i < end; ++i) {
        uint c = counts[i];
        counts[i] = running;
        running += c;
    }
}
