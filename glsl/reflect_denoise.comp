#version 460
// reflect.denoise: the spatial filter of glossy reflections, after reflect.merge (so it
// filters SSR's and the tracer's samples together, with no holes where either source
// is missing). Mirrored by cpu_ref::denoise::denoise (tests/suite/glossy.rs).
//
// Per glossy pixel (glossy.glsl) the mean of DENOISE_TAPS neighbours and itself, the
// taps on a golden-angle spiral over a disc (rotated per pixel and frame), weighted by
// - a Gaussian of the distance (sigma half the radius);
// - edge stops: the neighbour's distance from the pixel's tangent plane (relative to
//   the pixel's distance from the camera), its normal's agreement and its roughness's;
//   a neighbour that is not a glossy pixel takes no part;
// - the variance of the taps (the guide): a tap whose luminance lies more than
//   DENOISE_SIGMA standard deviations of the geometry-weighted taps from their mean
//   weighs less, so a firefly is not spread over the disc.
// The disc's radius is the lobe's footprint on screen: alpha (r^2, the lobe's angular
// half-width) over the angle a pixel subtends, as if the reflected surface were as far
// as the reflecting one, at most the `denoise_radius` setting; under a pixel nothing is
// filtered. Mirror and other pixels are copied as they are.
#include "glossy.glsl"
layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(binding = 1, rgba32f) uniform readonly image2D merged; // rgb, a: SOURCE_*
layout(binding = 2) uniform sampler2D gb_depth;
layout(binding = 3) uniform sampler2D gb_normal; // w: traced reflectivity
layout(binding = 4) uniform sampler2D gb_albedo; // a: perceptual roughness
layout(binding = 5) uniform usampler2D gb_material;
layout(binding = 6, rgba32f) uniform writeonly image2D denoised;
layout(push_constant) uniform Push {
    uint radius;          // the largest disc radius, pixels
    float reflective_min; // reflectivity above which a pixel reflects
} pc;

const float GOLDEN_ANGLE = 2.39996323;
// A neighbour DENOISE_PLANE x the pixel's distance off its tangent plane weighs 1/e.
const float DENOISE_PLANE = 0.01;
const float DENOISE_NORMAL_POWER = 32.0;
// A neighbour this much rougher or smoother weighs 1/e.
const float DENOISE_ROUGHNESS = 0.1;
const float DENOISE_SIGMA = 2.0;

bool glossy_at(ivec2 q, out vec3 n, out float roughness) {
    uint m = texelFetch(gb_material, q, 0).r;
    vec4 nr = texelFetch(gb_normal, q, 0);
    n = normalize(nr.xyz);
    roughness = texelFetch(gb_albedo, q, 0).a;
    return m != MATERIAL_NONE && nr.w > pc.reflective_min && is_glossy(roughness);
}

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (any(greaterThanEqual(p, res))) {
        return;
    }
    vec4 c = imageLoad(merged, p);
    vec3 n;
    float roughness;
    float radius = 0.0;
    if (glossy_at(p, n, roughness)) {
        float spread = 2.0 / (abs(frame.proj[1][1]) * float(frame.resolution.y));
        radius = min(float(pc.radius), roughness * roughness / spread);
    }
    uint taps = radius >= 1.0 ? DENOISE_TAPS : 0u;
    vec3 x = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    float dist = length(x - frame.camera_pos.xyz);
    float turn = float(pcg_hash(uint(p.x) + pcg_hash(uint(p.y) + pcg_hash(frame.frame_index))) >> 8u) * (1.0 / 16777216.0);
    vec3 col[DENOISE_TAPS + 1u];
    float w[DENOISE_TAPS + 1u];
    float lum[DENOISE_TAPS + 1u];
    col[0] = c.rgb;
    w[0] = 1.0;
    lum[0] = luminance(c.rgb);
    float wsum = 1.0, mean = lum[0], sq = lum[0] * lum[0];
    for (uint i = 0u; i < DENOISE_TAPS; ++i) {
        float t = (float(i) + 0.5) / float(DENOISE_TAPS);
        float angle = float(i) * GOLDEN_ANGLE + 2.0 * PI * turn;
        ivec2 q = p + ivec2(round(radius * sqrt(t) * vec2(cos(angle), sin(angle))));
        vec3 nq;
        float rq;
        float wi = 0.0;
        col[i + 1u] = vec3(0.0);
        if (taps > 0u && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res)) && glossy_at(q, nq, rq)) {
            vec3 xq = world_from_depth(q, texelFetch(gb_depth, q, 0).r);
            float plane = abs(dot(n, xq - x)) / (DENOISE_PLANE * dist);
            wi = exp(-2.0 * t - plane * plane - abs(rq - roughness) / DENOISE_ROUGHNESS)
               * pow(max(dot(n, nq), 0.0), DENOISE_NORMAL_POWER);
            col[i + 1u] = imageLoad(merged, q).rgb;
        }
        w[i + 1u] = wi;
        lum[i + 1u] = luminance(col[i + 1u]);
        wsum += wi;
        mean += wi * lum[i + 1u];
        sq += wi * lum[i + 1u] * lum[i + 1u];
    }
    vec3 out_c = c.rgb;
    if (taps > 0u) {
        mean /= wsum;
        float variance = max(sq / wsum - mean * mean, 0.0);
        float k = 1.0 / (2.0 * DENOISE_SIGMA * DENOISE_SIGMA * variance + 1e-8);
        vec3 sum = vec3(0.0);
        float total = 0.0;
        for (uint i = 0u; i <= DENOISE_TAPS; ++i) {
            float d = lum[i] - mean;
            float wi = w[i] * exp(-d * d * k);
            sum += wi * col[i];
            total += wi;
        }
        if (total > 1e-20) {
            out_c = sum / total;
        }
    }
    imageStore(denoised, p, vec4(out_c, c.a));
}
