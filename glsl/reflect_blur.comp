#version 460
// reflect.merge, step 2 (run twice: horizontal, then vertical): a Gaussian blur of the
// merged reflection restricted to the band around SSR/RT seams. A pixel is blurred only
// when a pixel of the other source lies within `band` pixels along this direction;
// only reflective neighbours contribute, so the blur never bleeds across the edge of a
// reflector.
#include "frame.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, rgba32f) uniform readonly image2D src;
layout(binding = 2, rgba32f) uniform writeonly image2D dst;

layout(push_constant) uniform Push {
    ivec2 axis;  // (1, 0) or (0, 1)
    int radius;  // blur radius in pixels (Gaussian sigma = radius / 2)
    int band;    // half-width of the seam band in pixels
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (any(greaterThanEqual(p, res))) {
        return;
    }
    vec4 c = imageLoad(src, p);
    uint source = uint(c.a);
    bool seam = false;
    if (source != SOURCE_NONE && pc.radius > 0) {
        for (int k = -pc.band; k <= pc.band && !seam; ++k) {
            ivec2 q = clamp(p + pc.axis * k, ivec2(0), res - 1);
            uint s = uint(imageLoad(src, q).a);
            seam = s != SOURCE_NONE && s != source;
        }
    }
    if (!seam) {
        imageStore(dst, p, c);
        return;
    }
    float sigma = max(float(pc.radius) * 0.5, 0.5);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int k = -pc.radius; k <= pc.radius; ++k) {
        ivec2 q = p + pc.axis * k;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, res))) {
            continue;
        }
        vec4 s = imageLoad(src, q);
        if (uint(s.a) == SOURCE_NONE) {
            continue;
        }
        float wk = exp(-float(k * k) / (2.0 * sigma * sigma));
        sum += s.rgb * wk;
        weight += wk;
    }
    imageStore(dst, p, vec4(sum / weight, c.a));
}
