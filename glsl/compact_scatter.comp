#version 460
// ssr.compact, step 3 of 3: every failed pixel to its slot, in tile order (compact.glsl).
// CPU reference: cpu_ref::compact::compact, the whole list (tests/compact.rs).
#define WG_SCAN_SIZE COMPACT_WG
#include "wg_scan.glsl"

layout(local_size_x = COMPACT_WG) in;

layout(binding = 0, r32ui) uniform readonly uimage2D mask;
#define COMPACT_MASK
#include "compact.glsl"
layout(binding = 1, std430) readonly buffer TileOffsets { uint tile_offsets[]; };
layout(binding = 2, std430) writeonly buffer Pixels { uint pixels_out[]; };

void main() {
    uint l = gl_LocalInvocationID.x;
    uint base = gl_WorkGroupID.x * COMPACT_TILE + l * COMPACT_ITEMS;
    uint mine = 0u;
    for (uint k = 0u; k < COMPACT_ITEMS; ++k) {
        if (slot_listed(base + k)) {
            mine += 1u;
        }
    }
    uint total;
    uint slot = tile_offsets[gl_WorkGroupID.x] + wg_exclusive_scan(mine, total);
    for (uint k = 0u; k < COMPACT_ITEMS; ++k) {
        if (slot_listed(base + k)) {
            pixels_out[slot++] = pack_pixel(pixel_at(base + k));
        }
    }
}
