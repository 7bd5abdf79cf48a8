#version 460
// ssr.compact, step 1 of 3: failed pixels per tile.
// CPU reference: cpu_ref::compact::compact, the whole list (tests/compact.rs).
layout(local_size_x = COMPACT_WG) in;

layout(binding = 0, r32ui) uniform readonly uimage2D mask; // nonzero: the pixel needs a ray
#define COMPACT_MASK
#include "compact.glsl"
layout(binding = 1, std430) writeonly buffer TileCounts { uint tile_counts[]; };

shared uint s_count;

void main() {
    uint l = gl_LocalInvocationID.x;
    if (l == 0u) {
        s_count = 0u;
    }
    barrier();
    uint base = gl_WorkGroupID.x * COMPACT_TILE + l * COMPACT_ITEMS;
    uint mine = 0u;
    for (uint k = 0u; k < COMPACT_ITEMS; ++k) {
        if (slot_listed(base + k)) {
            mine += 1u;
        }
    }
    atomicAdd(s_count, mine);
    barrier();
    if (l == 0u) {
        tile_counts[gl_WorkGroupID.x] = s_count;
    }
}
