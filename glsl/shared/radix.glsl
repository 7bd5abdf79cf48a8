// Shared pieces of the radix sort: push constants and the digit of a key.
// Keys are `key_words` 32-bit words each (1 or 2, low word first).
#ifndef RADIX_GLSL
#define RADIX_GLSL
#extension GL_EXT_samplerless_texture_functions : require

layout(push_constant) uniform Push {
    uint n;         // number of keys
    uint shift;     // bit position of this pass's digit (a multiple of SORT_RADIX_BITS)
    uint key_words; // 32-bit words per key
    uint num_tiles; // ceil(n / SORT_TILE)
} pc;

// Keys each invocation owns (sort.rs: SORT_ITEMS_GPU or SORT_ITEMS_CPU, at most
// SORT_ITEMS_MAX = 252: the packed histograms below count to 255, and keys are read in
// quads).
layout(constant_id = 0) const uint SORT_ITEMS = 16u;
// Threads per workgroup (sort.rs: SORT_WG_GPU or SORT_WG_CPU), each kernel's local size
// (local_size_x_id = 1).
layout(constant_id = 1) const uint SORT_WG = 256u;
#define SORT_TILE (SORT_WG * SORT_ITEMS)

// The keys and values are read as texel buffers of uvec4 (4 words a fetch: lavapipe
// loads a storage buffer one lane and one word at a time, each behind a branch), in
// quads: keys i..i+3, i a multiple of 4 (SORT_ITEMS is one), their low words and high
// words (0 for one-word keys). The buffers hold whole quads (sort.rs).
void load_quad(utextureBuffer keys, uint i, out uvec4 lo, out uvec4 hi) {
    if (pc.key_words == 1u) {
        lo = texelFetch(keys, int(i >> 2u));
        hi = uvec4(0u);
    } else {
        uvec4 a = texelFetch(keys, int(i >> 1u));
        uvec4 b = texelFetch(keys, int((i >> 1u) + 1u));
        lo = uvec4(a.x, a.z, b.x, b.z);
        hi = uvec4(a.y, a.w, b.y, b.w);
    }
}

// This pass's digits of a quad of keys.
uvec4 quad_digits(uvec4 lo, uvec4 hi) {
    return ((pc.shift >= 32u ? hi : lo) >> (pc.shift & 31u)) & (SORT_BINS - 1u);
}

// A packed histogram of the SORT_BINS = 16 digits in registers: digit d's count in
// byte d % 4 of word d / 4, so counts up to 255 (a thread counts at most SORT_ITEMS
// keys). digit_one(d) is the histogram of one d.
uvec4 digit_one(uint d) {
    return uvec4(equal(uvec4(d >> 2u), uvec4(0u, 1u, 2u, 3u))) << ((d & 3u) * 8u);
}
uint digit_count(uvec4 h, uint d) {
    uint q = d >> 2u;
    uint w = q == 0u ? h.x : (q == 1u ? h.y : (q == 2u ? h.z : h.w));
    return (w >> ((d & 3u) * 8u)) & 0xffu;
}

// The packed histogram of the SORT_ITEMS keys from `base` (those below pc.n): what the
// count adds to its tile's and the scatter ranks by.
uvec4 count_digits(utextureBuffer keys, uint base) {
    uvec4 h = uvec4(0u);
    for (uint k = 0u; k < SORT_ITEMS; k += 4u) {
        uint i = base + k;
        if (i < pc.n) {
            uvec4 lo, hi;
            load_quad(keys, i, lo, hi);
            uvec4 d = quad_digits(lo, hi);
            for (uint c = 0u; c < 4u; ++c) {
                if (i + c < pc.n) {
                    h += digit_one(d[c]);
                }
            }
        }
    }
    return h;
}
#endif
