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
// - the variance of the taps (the guide): a tap whose luminance lies d standard
//   deviations of the geometry-weighted taps from their mean weighs 1 / (1 + d^2 /
//   (2 DENOISE_SIGMA^2)) as much (a Cauchy kernel: cheaper than a Gaussian and as
//   good at this), so a firefly is not spread over the disc.
// The disc's radius is the lobe's footprint on screen: alpha (r^2, the lobe's angular
// half-width) times the distance to what the rays hit (ssr.trace's and rt.reflect's
// hit_distance), over the pixel's distance from the camera times the angle a pixel
// subtends, at least DENOISE_MIN_RADIUS and at most the `denoise_radius` setting.
// It runs over ssr.classify's list of glossy pixels (lavapipe would run the whole
// filter for every pixel of a full-screen dispatch); the others are left alone.
#include "glossy.glsl"
#include "pixel_list.glsl"
layout(local_size_x = SSR_LIST_WG) in;
layout(binding = 1, rgba32f) uniform readonly image2D merged; // rgb, a: SOURCE_*
layout(binding = 2) uniform sampler2D gb_depth;
layout(binding = 3) uniform sampler2D gb_normal; // w: traced reflectivity
layout(binding = 4) uniform sampler2D gb_albedo; // a: perceptual roughness
layout(binding = 5, rgba32f) uniform writeonly image2D denoised;
layout(binding = 6, std430) readonly buffer GlossyList { uint glossy_list[]; };
layout(binding = 7, std430) readonly buffer GlossyArgs { uvec4 glossy_args; }; // w: length
layout(binding = 8, r32f) uniform readonly image2D hit_distance; // of the reflected rays
layout(push_constant) uniform Push {
    uint radius;          // the largest disc radius, pixels
    float reflective_min; // reflectivity above which a pixel reflects
} pc;

// The taps' offsets in a unit disc: tap i at radius sqrt((i + 0.5) / DENOISE_TAPS) and
// angle i x the golden angle (2.39996323), uniform over the disc; cpu_ref::denoise
// holds the same numbers.
const vec2 SPIRAL[DENOISE_TAPS] = vec2[](
    vec2(0.17677669, 0.0),
    vec2(-0.22577219, 0.20682582),
    vec2(0.034558054, -0.39377117),
    vec2(0.28457123, 0.37117276),
    vec2(-0.5222232, -0.09237393),
    vec2(0.4946954, -0.31468472),
    vec2(-0.16546592, 0.615525),
    vec2(-0.31556147, -0.60759443),
    vec2(0.68464214, 0.25003022),
    vec2(-0.7122561, 0.29400897),
    vec2(0.3433545, -0.73372865),
    vec2(0.25373024, 0.808932),
    vec2(-0.7647459, -0.44318587),
    vec2(0.897134, -0.19723238),
    vec2(-0.5475069, 0.77877223),
    vec2(-0.12648676, -0.9760897));
// A neighbour DENOISE_PLANE x the pixel's distance off its tangent plane weighs 1/e.
const float DENOISE_PLANE = 0.01;
// A neighbour this much rougher or smoother weighs 1/e.
const float DENOISE_ROUGHNESS = 0.1;
const float DENOISE_SIGMA = 2.0;
// The least disc radius, pixels: a glossy pixel's samples are noisy whatever its lobe's
// footprint (a narrow lobe's one sample is as noisy as a wide one's: it only varies less
// across the screen), and 2 px keeps the blur under the G-buffer's detail.
const float DENOISE_MIN_RADIUS = 2.0;

// Whether the surface at q is glossy: by its traced reflectivity and roughness alone
// (the sky's normal target is cleared to 0, so its reflectivity is never above
// reflective_min).
bool glossy_at(ivec2 q, out vec3 n, out float roughness) {
    vec4 nr = texelFetch(gb_normal, q, 0);
    n = normalize(nr.xyz);
    roughness = texelFetch(gb_albedo, q, 0).a;
    return nr.w > pc.reflective_min && is_glossy(roughness);
}

// cos^32 (DENOISE_NORMAL_POWER) by five squarings.
float pow32(float c) {
    c *= c;
    c *= c;
    c *= c;
    c *= c;
    return c * c;
}

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

void main() {
    uint entry = list_entry(glossy_args.w, SSR_LIST_WG);
    if (entry >= glossy_args.w) {
        return;
    }
    ivec2 p = unpack_pixel(glossy_list[entry]);
    ivec2 res = ivec2(frame.resolution);
    vec4 c = imageLoad(merged, p);
    vec3 n;
    float roughness;
    glossy_at(p, n, roughness); // listed: glossy
    vec3 x = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    float dist = length(x - frame.camera_pos.xyz);
    // The lobe's footprint: alpha (its angular half-width) times the distance to what it
    // reflects, seen from the camera, in pixels.
    float hit = imageLoad(hit_distance, p).r;
    float radius = min(float(pc.radius), max(roughness * roughness * hit / (dist * pixel_spread()), DENOISE_MIN_RADIUS));
    uint taps = radius >= 1.0 ? DENOISE_TAPS : 0u;
    float turn = float(pixel_hash(p, frame.frame_index) >> 8u) * (1.0 / 16777216.0);
    // The spiral turned by the pixel's angle and scaled to the disc.
    float angle = 2.0 * PI * turn;
    mat2 turn_by = radius * mat2(cos(angle), sin(angle), -sin(angle), cos(angle));
    vec3 col[DENOISE_TAPS + 1u];
    float w[DENOISE_TAPS + 1u];
    float lum[DENOISE_TAPS + 1u];
    col[0] = c.rgb;
    w[0] = 1.0;
    lum[0] = luminance(c.rgb);
    float wsum = 1.0, mean = lum[0], sq = lum[0] * lum[0];
    for (uint i = 0u; i < DENOISE_TAPS; ++i) {
        float t = (float(i) + 0.5) / float(DENOISE_TAPS);
        ivec2 q = p + ivec2(round(turn_by * SPIRAL[i]));
        vec3 nq;
        float rq;
        float wi = 0.0;
        col[i + 1u] = vec3(0.0);
        if (taps > 0u && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res)) && glossy_at(q, nq, rq)) {
            vec3 xq = world_from_depth(q, texelFetch(gb_depth, q, 0).r);
            float plane = abs(dot(n, xq - x)) / (DENOISE_PLANE * dist);
            wi = exp(-2.0 * t - plane * plane - abs(rq - roughness) / DENOISE_ROUGHNESS)
               * pow32(max(dot(n, nq), 0.0));
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
            float wi = w[i] / (1.0 + d * d * k);
            sum += wi * col[i];
            total += wi;
        }
        if (total > 1e-20) {
            out_c = sum / total;
        }
    }
    imageStore(denoised, p, vec4(out_c, c.a));
}
