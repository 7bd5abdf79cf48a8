// Stream compaction of a per-pixel mask into a list of pixels, in row-major order:
// count per tile → scan (one workgroup) → scatter. Tiles are COMPACT_TILE consecutive
// pixels (SORT_WG invocations x SORT_ITEMS pixels each). Mirrored by
// cpu_ref::compact.
#ifndef COMPACT_GLSL
#define COMPACT_GLSL

#define COMPACT_TILE (SORT_WG * SORT_ITEMS)

layout(push_constant) uniform Push {
    uvec2 size;     // mask size in pixels
    uint num_tiles; // ceil(size.x * size.y / COMPACT_TILE)
    uint _pad0;
} pc;

// Packs a pixel into one ray-list entry: x in the low 16 bits, y in the high 16.
uint pack_pixel(uvec2 p) {
    return p.x | (p.y << 16);
}
#endif
