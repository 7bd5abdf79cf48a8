// Pixel lists (the ray list, the SSR march list): one uint per pixel, x in the low
// 16 bits, y in the high 16.
#ifndef PIXEL_LIST_GLSL
#define PIXEL_LIST_GLSL
uint pack_pixel(uvec2 p) {
    return p.x | (p.y << 16);
}

ivec2 unpack_pixel(uint packed) {
    return ivec2(packed & 0xffffu, packed >> 16);
}

#endif
