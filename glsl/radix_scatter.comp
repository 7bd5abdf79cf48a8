#version 460
// lbvh.sort, step 3 of 3 per pass: stable scatter. Each invocation owns SORT_ITEMS
// consecutive keys of the tile and counts their digits in registers: a packed
// histogram of 4 bins per word, 8 bits per bin (SORT_ITEMS < 256). Its column of
// counts goes to shared memory digit-major (s_counts[digit * SORT_WG + invocation]);
// an exclusive scan of that array gives, for every (digit, invocation), how many keys
// of that digit come earlier in the tile. Adding the scanned global offset of
// (digit, tile) gives each invocation's first slot per digit; its keys then take
// consecutive slots in input order, counted again in registers: the sort is stable
// (LSD radix sort needs it). No shared-memory read-modify-write per key (a per-lane
// scatter is the slow step on a CPU driver, which runs lanes as SIMD vectors).
//
// LOCAL_ORDER (a candidate for GPUs, whose tiles are SORT_BINS keys a thread): the
// tile's pairs are first put in their output order in shared memory, then written by
// consecutive invocations to consecutive slots. The direct scatter's stores land a
// key or two in each of the 16 digits' runs per 32 lanes, so a memory sector is
// written a few words at a time over the tile's 16 store rounds: merged in a GPU's
// L2 while the output fits in it (1M keys), maybe read and written back per store
// beyond it (the H200's sort of 10M keys took 36x its 1M sort). Same slots, same
// result; tests/suite/lbvh.rs sorts with both.
//
// FUSED_TILES (sort.rs: SortTile::fused): a sort of 2..FUSED_TILES tiles finds each
// tile's global offsets here, from the count's histograms as they were written, and
// the scan does not run: a dispatch and a barrier fewer a pass, for each workgroup
// reading the SORT_BINS x num_tiles counts (steps 1-3 in main).
// CPU reference: cpu_ref::lbvh::sort_pairs, the whole sort (tests/lbvh.rs).
#include "radix.glsl"
#define WG_SCAN_SIZE SORT_WG
#include "wg_scan.glsl"

layout(local_size_x_id = 1) in;
layout(constant_id = 2) const bool LOCAL_ORDER = false;
layout(constant_id = 3) const uint FUSED_TILES = 0u;

layout(binding = 0) uniform utextureBuffer keys_in;
layout(binding = 1) uniform utextureBuffer values_in;
layout(binding = 2, std430) writeonly buffer KeysOut { uint keys_out[]; };
layout(binding = 3, std430) writeonly buffer ValuesOut { uint values_out[]; };
layout(binding = 4, std430) readonly buffer Offsets { uint offsets[]; };

shared uint s_counts[SORT_BINS * SORT_WG];
shared uint s_base[SORT_BINS];
// LOCAL_ORDER: where each digit's keys start in the tile's output order.
shared uint s_first[SORT_BINS];
// FUSED_TILES: each invocation's sums of its digit's counts, over all its tiles and
// over those before this tile; then each digit's total.
shared uint s_fused[2u * SORT_WG];
shared uint s_digit_total[SORT_BINS];

// LOCAL_ORDER: word `w` of every pair of the tile (the key's words, then the value)
// into its place in the tile's output order, s_counts reused for it (SORT_ITEMS ==
// SORT_BINS: as many words as the tile has keys); `start`: this invocation's first
// place of each digit.
void stage_word(uint w, uint base, uint start[SORT_BINS]) {
    uvec4 h = uvec4(0u);
    for (uint k = 0u; k < SORT_ITEMS; k += 4u) {
        uint i = base + k;
        if (i < pc.n) {
            uvec4 lo, hi;
            load_quad(keys_in, i, lo, hi);
            uvec4 d = quad_digits(lo, hi);
            uvec4 word = w == pc.key_words ? texelFetch(values_in, int(i >> 2u)) : (w == 0u ? lo : hi);
            for (uint c = 0u; c < 4u; ++c) {
                if (i + c < pc.n) {
                    s_counts[start[d[c]] + digit_count(h, d[c])] = word[c];
                    h += digit_one(d[c]);
                }
            }
        }
    }
}

// LOCAL_ORDER: the tile's pairs written out in order, a word of each at a time, each
// invocation taking every SORT_WG-th place: neighbours store to neighbouring slots.
void scatter_local(uint base, uint tile_keys) {
    uint l = gl_LocalInvocationID.x;
    uint start[SORT_BINS];
    for (uint d = 0u; d < SORT_BINS; ++d) {
        start[d] = s_counts[d * SORT_WG + l];
    }
    // The output slot of each place this invocation writes (SORT_ITEMS == SORT_BINS of
    // them), found once for every word of the pair: the place's digit is the last whose
    // first place it reaches.
    uint slots[SORT_BINS];
    for (uint j = 0u; j < SORT_ITEMS; ++j) {
        uint at = j * SORT_WG + l;
        uint d = 0u;
        for (uint e = 1u; e < SORT_BINS; ++e) {
            d = s_first[e] <= at ? e : d;
        }
        slots[j] = at + s_base[d];
    }
    barrier(); // every column read before s_counts holds the staged words
    for (uint w = 0u; w <= pc.key_words; ++w) {
        stage_word(w, base, start);
        barrier();
        for (uint j = 0u; j < SORT_ITEMS; ++j) {
            uint at = j * SORT_WG + l;
            if (at < tile_keys) {
                uint slot = slots[j];
                uint word = s_counts[at];
                if (w == pc.key_words) {
                    values_out[slot] = word;
                } else if (pc.key_words == 1u) {
                    keys_out[slot] = word;
                } else {
                    keys_out[2u * slot + w] = word;
                }
            }
        }
        barrier(); // every staged word written out before the next word is staged
    }
}

void main() {
    uint l = gl_LocalInvocationID.x;
    uint tile = gl_WorkGroupID.x;
    uint base = tile * SORT_TILE + l * SORT_ITEMS;
    // FUSED_TILES, step 1: invocation l sums digit l % SORT_BINS over every (SORT_WG /
    // SORT_BINS)-th tile from the count's histograms (`offsets` unscanned). The
    // exchanges below ride on the barriers the tile's own ranking has.
    bool fused = pc.num_tiles > 1u && pc.num_tiles <= FUSED_TILES;
    if (fused) {
        uint d = l % SORT_BINS;
        uint all_tiles = 0u;
        uint before = 0u;
        for (uint t = l / SORT_BINS; t < pc.num_tiles; t += SORT_WG / SORT_BINS) {
            uint c = offsets[d * pc.num_tiles + t];
            all_tiles += c;
            before += t < tile ? c : 0u;
        }
        s_fused[l] = all_tiles;
        s_fused[SORT_WG + l] = before;
    }

    uvec4 h = count_digits(keys_in, base);
    for (uint d = 0u; d < SORT_BINS; ++d) {
        s_counts[d * SORT_WG + l] = digit_count(h, d);
    }
    barrier();
    // FUSED_TILES, step 2: digit l's total over all tiles, and its keys in the tiles
    // before this one (kept here), from the invocations that summed it.
    uint fused_before = 0u;
    if (fused && l < SORT_BINS) {
        uint all_tiles = 0u;
        for (uint j = l; j < SORT_WG; j += SORT_BINS) {
            all_tiles += s_fused[j];
            fused_before += s_fused[SORT_WG + j];
        }
        s_digit_total[l] = all_tiles;
    }

    // Exclusive scan of the SORT_BINS * SORT_WG counts: invocation l scans the
    // SORT_BINS consecutive entries starting at l * SORT_BINS.
    uint seg = l * SORT_BINS;
    uint sum = 0u;
    for (uint k = 0u; k < SORT_BINS; ++k) {
        sum += s_counts[seg + k];
    }
    uint total;
    uint running = wg_exclusive_scan(sum, total);
    for (uint k = 0u; k < SORT_BINS; ++k) {
        uint c = s_counts[seg + k];
        s_counts[seg + k] = running;
        running += c;
    }
    barrier();

    // The tile's first slot of each digit (scanned, or found here where fused), less
    // the scanned count before its first invocation; added to this invocation's
    // column, its first slot of each digit. A single tile's scan already counts every
    // earlier key: no global offsets (the count and scan kernels do not run).
    if (l < SORT_BINS) {
        uint global_first = 0u;
        if (fused) {
            // FUSED_TILES, step 3 (the totals written before the scan's barriers): the
            // keys of every smaller digit, and of this one in the earlier tiles.
            global_first = fused_before;
            for (uint e = 0u; e < l; ++e) {
                global_first += s_digit_total[e];
            }
        } else if (pc.num_tiles > 1u) {
            global_first = offsets[l * pc.num_tiles + tile];
        }
        s_base[l] = pc.num_tiles == 1u ? 0u : global_first - s_counts[l * SORT_WG];
        s_first[l] = s_counts[l * SORT_WG];
    }
    barrier();
    if (LOCAL_ORDER && SORT_ITEMS == SORT_BINS) {
        scatter_local(base, min(SORT_TILE, pc.n - tile * SORT_TILE));
        return;
    }
    for (uint d = 0u; d < SORT_BINS; ++d) {
        s_counts[d * SORT_WG + l] += s_base[d]; // own column only
    }

    h = uvec4(0u);
    for (uint k = 0u; k < SORT_ITEMS; k += 4u) {
        uint i = base + k;
        if (i < pc.n) {
            uvec4 lo, hi;
            load_quad(keys_in, i, lo, hi);
            uvec4 d = quad_digits(lo, hi);
            uvec4 v = texelFetch(values_in, int(i >> 2u));
            for (uint c = 0u; c < 4u; ++c) {
                if (i + c < pc.n) {
                    uint slot = s_counts[d[c] * SORT_WG + l] + digit_count(h, d[c]);
                    h += digit_one(d[c]);
                    if (pc.key_words == 1u) {
                        keys_out[slot] = lo[c];
                    } else {
                        keys_out[2u * slot] = lo[c];
                        keys_out[2u * slot + 1u] = hi[c];
                    }
                    values_out[slot] = v[c];
                }
            }
        }
    }
}
