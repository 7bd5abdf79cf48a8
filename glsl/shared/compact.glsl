// Stream compaction of a per-pixel mask into a list of pixels, in tile order:
// count per tile → scan (one workgroup) → scatter. Tiles are COMPACT_TILE consecutive
// slots of that order (COMPACT_WG invocations x COMPACT_ITEMS slots each). Mirrored by
// cpu_ref::compact.
#ifndef COMPACT_GLSL
#define COMPACT_GLSL
#include "pixel_list.glsl"

#define COMPACT_TILE (COMPACT_WG * COMPACT_ITEMS)

layout(push_constant) uniform Push {
    uvec2 size;     // mask size in pixels
    uint num_tiles; // ceil(slots / COMPACT_TILE)
    uint slots;     // slots of the order: whole WG_2D x WG_2D tiles covering the mask
} pc;

// The list's order: WG_2D x WG_2D pixel blocks in row-major order, pixels row-major
// inside each block. Consecutive rays then come from neighbouring pixels wherever the
// failed pixels lie, so a SIMD group of rays stays coherent (a row-major list puts
// the ends of distant rows side by side). Slot i holds pixel_at(i); slots past the
// mask's edge (in partial blocks) hold no pixel.
uvec2 pixel_at(uint i) {
    uint blocks_x = (pc.size.x + WG_2D - 1u) / WG_2D;
    uint block = i / (WG_2D * WG_2D);
    uint j = i % (WG_2D * WG_2D);
    return uvec2((block % blocks_x) * WG_2D + j % WG_2D, (block / blocks_x) * WG_2D + j / WG_2D);
}

#ifdef COMPACT_MASK
// Slot i holds a pixel whose mask is set and not FAIL_UNTRACED (the includer binds the
// mask image first and defines COMPACT_MASK).
bool slot_listed(uint i) {
    uvec2 p = pixel_at(i);
    if (i >= pc.slots || any(greaterThanEqual(p, pc.size))) {
        return false;
    }
    uint m = imageLoad(mask, ivec2(p)).r;
    return m != 0u && (m & FAIL_UNTRACED) == 0u;
}
#endif
#endif
