#version 460
// reflect.merge, step 3 (run twice: horizontal, then vertical): a Gaussian blur of the
// merged reflection restricted to the band around SSR/RT seams. A pixel is blurred only
// when a pixel of the other source lies within `band` pixels along this direction;
// only reflective neighbours contribute, so the blur never bleeds across the edge of a
// reflector. Mirrored by cpu_ref::merge::seam_blur.
//
// One workgroup per active tile (reflect_tiles.comp lists them and sizes this indirect
// dispatch); the other tiles have no seam within reach and are never touched. The
// horizontal pass writes its active tiles to `scratch`; the vertical pass writes them
// back into `reflection` in place, taking a neighbour's horizontally blurred value from
// `scratch` when its tile is active and from `reflection` when not (an inactive tile's
// scratch is never written, and its reflection never changes). No texel is both read
// and written by different workgroups of one pass.
#include "frame.glsl"
#include "pixel_list.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, rgba32f) uniform image2D reflection;
layout(binding = 2, rgba32f) uniform image2D scratch;
layout(binding = 3, std430) readonly buffer TileActive { uint tile_active[]; };
layout(binding = 4, std430) readonly buffer TileList { uint tile_list[]; };
layout(binding = 5, std430) readonly buffer BlurArgs { uvec4 blur_args; }; // w: tiles listed

layout(push_constant) uniform Push {
    ivec2 axis;  // (1, 0): horizontal pass; (0, 1): vertical pass
    int radius;  // blur radius in pixels (Gaussian sigma = radius / 2)
    int band;    // half-width of the seam band in pixels
} pc;

// The horizontally blurred value of pixel q (inside the image), for the vertical pass.
vec4 horizontal_result(ivec2 q) {
    ivec2 tile = q / int(WG_2D);
    return tile_active[tile.y * tile_grid().x + tile.x] != 0u ? imageLoad(scratch, q) : imageLoad(reflection, q);
}

vec4 source_at(ivec2 q) {
    return pc.axis.x == 1 ? imageLoad(reflection, q) : horizontal_result(q);
}

void main() {
    uint w = list_workgroup(); // one workgroup per listed tile
    if (w >= blur_args.w) {
        return; // the last row of a 2D dispatch (the whole workgroup alike)
    }
    int t = int(tile_list[w]);
    int tiles_x = tile_grid().x;
    ivec2 p = ivec2(t % tiles_x, t / tiles_x) * int(WG_2D) + ivec2(gl_LocalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (any(greaterThanEqual(p, res))) {
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
