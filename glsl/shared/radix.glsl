// Shared pieces of the radix sort: push constants and the digit of a key.
// Keys are `key_words` 32-bit words each (1 or 2, low word first).
#ifndef RADIX_GLSL
#define RADIX_GLSL

layout(push_constant) uniform Push {
    uint n;         // number of keys
    uint shift;     // bit position of this pass's digit (a multiple of SORT_RADIX_BITS)
    uint key_words; // 32-bit words per key
    uint num_tiles; // ceil(n / (SORT_WG * SORT_ITEMS))
} pc;

#define SORT_TILE (SORT_WG * SORT_ITEMS)

#define DIGIT_OF(keys, i) ((keys[(i) * pc.key_words + (pc.shift >> 5)] >> (pc.shift & 31u)) & (SORT_BINS - 1u))
#endif
