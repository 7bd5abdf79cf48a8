#version 460
// CPU reference: cpu_ref::merge::active_tiles (tests/merge.rs).
#extension GL_KHR_shader_subgroup_ballot : require
// reflect.merge, step 2: which WG_2D x WG_2D tiles the seam blur works on. A tile is
// *active* when the tiles within ceil(band / WG_2D) of it (the merge's per-tile source
// bits) hold both SSR and RT pixels: a pixel of an inactive tile has no other-source
// pixel within `band` on either axis, so both blur directions leave it as it is. Each
// tile's activity goes to `tile_active`, and the active tiles are appended to a list
// whose length is the indirect dispatch of the blur (one workgroup per tile), so the
// blur costs nothing where there is no seam. Mirrored by cpu_ref::merge::active_tiles.
#include "frame.glsl"
#include "pixel_list.glsl"

layout(local_size_x = 64) in;

layout(binding = 1, std430) readonly buffer TileSources { uint tile_sources[]; };
layout(binding = 2, std430) writeonly buffer TileActive { uint tile_active[]; };
layout(binding = 3, std430) writeonly buffer TileList { uint tile_list[]; };
// VkDispatchIndirectCommand of the blur; x (the list's length) is zeroed before.
// x, y, z: the blur's indirect dispatch (list_groups of the tile count); w: the count.
layout(binding = 4, std430) buffer BlurArgs { uvec4 blur_args; };

layout(push_constant) uniform Push {
    int band; // half-width of the seam band in pixels
} pc;

const uint BOTH = (1u << SOURCE_SSR) | (1u << SOURCE_RT);

void main() {
    ivec2 tiles = tile_grid();
    uint t = gl_GlobalInvocationID.x;
    bool is_active = false;
    if (t < uint(tiles.x * tiles.y)) {
        ivec2 tile = ivec2(int(t) % tiles.x, int(t) / tiles.x);
        int k = (pc.band + int(WG_2D) - 1) / int(WG_2D);
        uint bits = 0u;
        for (int y = max(tile.y - k, 0); y <= min(tile.y + k, tiles.y - 1); ++y) {
            for (int x = max(tile.x - k, 0); x <= min(tile.x + k, tiles.x - 1); ++x) {
                bits |= tile_sources[y * tiles.x + x];
            }
        }
        is_active = (bits & BOTH) == BOTH;
        tile_active[t] = is_active ? 1u : 0u;
    }
    // One atomic per subgroup for its active tiles.
    uvec4 ballot = subgroupBallot(is_active);
    uint n = subgroupBallotBitCount(ballot);
    uint base = 0u;
    if (subgroupElect() && n > 0u) {
        base = atomicAdd(blur_args.w, n);
        uvec2 groups = list_groups(base + n);
        atomicMax(blur_args.x, groups.x);
        atomicMax(blur_args.y, groups.y);
    }
    base = subgroupBroadcastFirst(base);
    if (is_active) {
        tile_list[base + subgroupBallotExclusiveBitCount(ballot)] = t;
    }
}
