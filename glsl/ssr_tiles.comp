#version 460
// ssr.classify, step 1 (the adaptive hybrid's tiles): one invocation per tile
// (ssr.classify's WG_2D x WG_2D workgroups, TILE_* in shader_defines.rs) updates its
// state from the last frame's (`tiles_in`: the state and what ssr.trace counted) by
// the exchange rate (tile_update, ssr.glsl) into `tiles_out`, its counts zeroed for
// this frame's march. Its own dispatch, so the classification reads the state
// without a workgroup barrier.
// CPU reference: cpu_ref::ssr::tile_update (tests/suite/ssr.rs).
#include "ssr.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer TilesIn { uint tiles_in[]; };
layout(binding = 1, std430) writeonly buffer TilesOut { uint tiles_out[]; };

layout(push_constant) uniform Push {
    uint tiles;
    uint rate; // the exchange rate in 1/256 (0: every tile SSR-first)
    uint history; // 0: no last frame (tiles_in is not read)
} pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.tiles) {
        return;
    }
    uint state = 0u, marched = 0u, answered = 0u;
    if (pc.history != 0u) {
        state = tiles_in[t * TILE_WORDS];
        marched = tiles_in[t * TILE_WORDS + 1u];
        answered = tiles_in[t * TILE_WORDS + 2u];
    }
    tiles_out[t * TILE_WORDS] = tile_update(state, marched, answered, pc.rate);
    tiles_out[t * TILE_WORDS + 1u] = 0u;
    tiles_out[t * TILE_WORDS + 2u] = 0u;
}
