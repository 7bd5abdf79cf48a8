#version 460
// reflect.merge, step 2 (run twice: horizontal, then vertical): a Gaussian blur of the
// merged reflection restricted to the band around SSR/RT seams. A pixel is blurred only
// when a pixel of the other source lies within `band` pixels along this direction;
// only reflective neighbours contribute, so the blur never bleeds across the edge of a
// reflector. Mirrored by cpu_ref::merge::seam_blur.
//
// Only tiles near a seam do any work. A tile is *active* when the tiles within
// ceil(band / WG_2D) of it (merge's per-tile source bits) hold both SSR and RT pixels;
// a pixel of an inactive tile has no other-source pixel within `band` on either axis,
// so both blurs leave it as it is. The horizontal pass decides and records each
// tile's activity and writes its active tiles to `scratch`; the vertical pass writes
// the active tiles back into `reflection` in place, taking a neighbour's horizontally
// blurred value from `scratch` when its tile is active and from `reflection` when not
// (an inactive tile's scratch is never written). No texel is both read and written by
// different workgroups of one pass.
#include "frame.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, rgba32f) uniform image2D reflection;
layout(binding = 2, rgba32f) uniform image2D scratch;
layout(binding = 3, std430) readonly buffer TileSources { uint tile_sources[]; };
layout(binding = 4, std430) buffer TileActive { uint tile_active[]; };

layout(push_constant) uniform Push {
    ivec2 axis;  // (1, 0): horizontal pass; (0, 1): vertical pass
    int radius;  // blur radius in pixels (Gaussian sigma = radius / 2)
    int band;    // half-width of the seam band in pixels
} pc;

const uint BOTH = (1u << SOURCE_SSR) | (1u << SOURCE_RT);

uint tile_index(ivec2 tile) {
    return uint(tile.y) * gl_NumWorkGroups.x + uint(tile.x);
}

// The horizontally blurred value of pixel q (inside the image), for the vertical pass.
vec4 horizontal_result(ivec2 q) {
    return tile_active[tile_index(q / int(WG_2D))] != 0u ? imageLoad(scratch, q) : imageLoad(reflection, q);
}

vec4 source_at(ivec2 q) {
    return pc.axis.x == 1 ? imageLoad(reflection, q) : horizontal_result(q);
}

void main() {
    // Every invocation decides its tile's activity itself: no workgroup barrier.
    ivec2 tile = ivec2(gl_WorkGroupID.xy);
    bool tile_is_active;
    if (pc.axis.x == 1) {
        int k = (pc.band + int(WG_2D) - 1) / int(WG_2D);
        ivec2 tiles = ivec2(gl_NumWorkGroups.xy);
        uint bits = 0u;
        for (int y = max(tile.y - k, 0); y <= min(tile.y + k, tiles.y - 1); ++y) {
            for (int x = max(tile.x - k, 0); x <= min(tile.x + k, tiles.x - 1); ++x) {
                bits |= tile_sources[tile_index(ivec2(x, y))];
            }
        }
        tile_is_active = (bits & BOTH) == BOTH;
        if (gl_LocalInvocationIndex == 0u) {
            tile_active[tile_index(tile)] = tile_is_active ? 1u : 0u;
        }
    } else {
        tile_is_active = tile_active[tile_index(tile)] != 0u;
    }
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (!tile_is_active || any(greaterThanEqual(p, res))) {
        return;
    }
    vec4 c = source_at(p);
    uint source = uint(c.a);
    bool seam = false;
    if (source != SOURCE_NONE) {
        for (int k = -pc.band; k <= pc.band && !seam; ++k) {
            ivec2 q = p + pc.axis * k;
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res))) {
                uint s = uint(source_at(q).a);
                seam = s != SOURCE_NONE && s != source;
            }
        }
    }
    vec4 result = c;
    if (seam) {
        float sigma = max(float(pc.radius) * 0.5, 0.5);
        vec3 sum = vec3(0.0);
        float weight = 0.0;
        for (int k = -pc.radius; k <= pc.radius; ++k) {
            ivec2 q = p + pc.axis * k;
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, res))) {
                continue;
            }
            vec4 s = source_at(q);
            if (uint(s.a) == SOURCE_NONE) {
                continue;
            }
            float wk = exp(-float(k * k) / (2.0 * sigma * sigma));
            sum += s.rgb * wk;
            weight += wk;
        }
        result = vec4(sum / weight, c.a);
    }
    if (pc.axis.x == 1) {
        imageStore(scratch, p, result);
    } else {
        imageStore(reflection, p, result);
    }
}
