#version 460
// reflect.merge, step 3 (run twice: horizontal, then vertical): a Gaussian blur of the
// merged reflection restricted to the band around SSR/RT seams. A pixel is blurred only
// when a pixel of the other source lies within `band` pixels along this direction;
// only reflective neighbours contribute, so the blur never bleeds across the edge of a
// reflector; and a neighbour weighs less the more its colour differs from the pixel's
// (range_weight), so an edge *in* a mirror reflection (a thin slab's front face against
// the sky) stays sharp while a seam's few percent are blurred. A glossy pixel's
// reflection has softer edges and its sampled colours differ by more than a seam's: it
// takes a three times wider range. Mirrored by cpu_ref::merge::seam_blur.
//
// One workgroup per active tile (reflect_tiles.comp lists them and sizes this indirect
// dispatch); the other tiles have no seam within reach and are never touched. The
// horizontal pass writes its active tiles to `scratch`; the vertical pass writes them
// back into `reflection` in place, taking a neighbour's horizontally blurred value from
// `scratch` when its tile is active and from `reflection` when not (an inactive tile's
// scratch is never written, and its reflection never changes). No texel is both read
// and written by different workgroups of one pass.
#include "frame.glsl"
#include "glossy.glsl"
#include "pixel_list.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, rgba32f) uniform image2D reflection;
layout(binding = 2, rgba32f) uniform image2D scratch;
layout(binding = 3, std430) readonly buffer TileActive { uint tile_active[]; };
layout(binding = 4, std430) readonly buffer TileList { uint tile_list[]; };
layout(binding = 5, std430) readonly buffer BlurArgs { uvec4 blur_args; }; // w: tiles listed
layout(binding = 6) uniform sampler2D gb_albedo; // a: perceptual roughness

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

// How a neighbour of colour b counts beside a pixel of colour a: exp(-(r / edge)^2)
// with r their largest channel difference relative to the brighter of the two (+0.05,
// so near-black pixels do not count as edges), `edge` SEAM_EDGE around a mirror pixel
// (an SSR/RT seam's few percent weigh ~0.97, a slab's face against the sky, r 0.56,
// 0.03), SEAM_EDGE_GLOSSY around a glossy one. Measured (lavapipe, 960x540, SSR-first
// hybrid vs rt, one frame): 0.15 for both sharpened mirrors and thin slabs but lost
// 0.02 SSIM on `glossy`; 0.3 for mirrors and 0.9 for glossy pixels is at or above the
// plain Gaussian on every built-in scene (docs/experiments.md).
const float SEAM_EDGE = 0.3;
const float SEAM_EDGE_GLOSSY = 0.9;

float range_weight(vec3 a, vec3 b, float edge) {
    vec3 d = abs(a - b);
    vec3 m = max(a, b);
    float r = max(d.r, max(d.g, d.b)) / (max(m.r, max(m.g, m.b)) + 0.05);
    return exp(-(r * r) / (edge * edge));
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
    float edge = is_glossy(texelFetch(gb_albedo, p, 0).a) ? SEAM_EDGE_GLOSSY : SEAM_EDGE;
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
            float wk = exp(-float(k * k) / (2.0 * sigma * sigma)) * range_weight(c.rgb, s.rgb, edge);
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
