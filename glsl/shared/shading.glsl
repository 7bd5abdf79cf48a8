// Direct lighting: shadow-map PCF and the surface model. Mirrored exactly by
// src/cpu_ref/shading.rs; change both together.
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "frame.glsl"

const float PI = 3.14159265358979;

// Weight of texel column/row k of the (2r+2)-wide PCF footprint with sub-texel offset f.
float pcf_weight(int k, int n, float f) {
    return k == 0 ? 1.0 - f : (k == n - 1 ? f : 1.0);
}

// Fraction of light reaching world point `w`: the mean of (2r+1)^2 bilinearly
// filtered depth compares centred on w's shadow-map position. Equivalent to that
// mean but computed over the (2r+2)^2 texels it touches, each read once, four at a
// time with textureGather (clamp-to-edge sampler): interior texels weigh 1, the
// border rows and columns (1-f) and f.
// `doubt` receives the SHADOW_* bits of why the map may be wrong at w (0: it is
// sure): w is outside the map (SHADOW_OUTSIDE); the texels of the footprint, whatever
// their weights, do not all agree (SHADOW_EDGE); a texel's depth is within
// frame.shadow_band of the biased compare (SHADOW_NEAR: acne, contact shadows).
float shadow_pcf(sampler2D shadow_map, vec3 w, out uint doubt) {
    doubt = 0u;
    vec4 c = frame.light_view_proj * vec4(w, 1.0);
    vec3 ndc = c.xyz / c.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z > 1.0) {
        doubt = SHADOW_OUTSIDE;
        return 1.0; // outside the light's frustum: unshadowed
    }
    float ref_depth = ndc.z - frame.shadow_bias;
    float size = float(frame.shadow_map_size);
    vec2 t = uv * size - 0.5;
    vec2 cell = floor(t);
    vec2 f = t - cell;
    int r = int(min(frame.pcf_radius, MAX_PCF_RADIUS));
    ivec2 base = ivec2(cell) - r;
    int n = 2 * r + 2; // even: the footprint is whole 2x2 gathers
    float sum = 0.0;
    bool any_lit = false, any_dark = false;
    for (int j = 0; j < n; j += 2) {
        float wy0 = pcf_weight(j, n, f.y);
        float wy1 = pcf_weight(j + 1, n, f.y);
        for (int i = 0; i < n; i += 2) {
            float wx0 = pcf_weight(i, n, f.x);
            float wx1 = pcf_weight(i + 1, n, f.x);
            // The centre of the 2x2 block whose lower corner texel is base + (i, j):
            // exactly half a texel from every texel centre, so the footprint is exact.
            vec2 g = (vec2(base + ivec2(i, j)) + 1.0) / size;
            // Gather order: x = (i, j+1), y = (i+1, j+1), z = (i+1, j), w = (i, j).
            vec4 d = textureGather(shadow_map, g, 0);
            bvec4 texel_lit = greaterThanEqual(d, vec4(ref_depth));
            any_lit = any_lit || any(texel_lit);
            any_dark = any_dark || !all(texel_lit);
            if (any(lessThan(abs(d - vec4(ref_depth)), vec4(frame.shadow_band)))) {
                doubt |= SHADOW_NEAR;
            }
            vec4 lit = vec4(texel_lit);
            sum += lit.w * wx0 * wy0 + lit.z * wx1 * wy0 + lit.x * wx0 * wy1 + lit.y * wx1 * wy1;
        }
    }
    if (any_lit && any_dark) {
        doubt |= SHADOW_EDGE;
    }
    float taps = float((2 * r + 1) * (2 * r + 1));
    return sum / taps;
}

float shadow_visibility(sampler2D shadow_map, vec3 w) {
    uint doubt;
    return shadow_pcf(shadow_map, w, doubt);
}

// Cosine of the sun's angle to the normal under which the hybrid shadows do not trust
// the shadow map: its depth slope outruns any bias there.
const float SHADOW_GRAZING_NDL = 0.1;

// The hybrid shadows' question at w (normal n, a unit vector facing the sun: n.l > 0):
// returns 0 when the shadow map is sure, with `vis` its answer (0 or 1: every texel
// agrees), else the SHADOW_* bits of why not (shadow_pcf's, and SHADOW_GRAZING).
uint shadow_map_doubt(sampler2D shadow_map, vec3 w, float ndl, out float vis) {
    uint doubt;
    vis = shadow_pcf(shadow_map, w, doubt) > 0.5 ? 1.0 : 0.0;
    if (ndl < SHADOW_GRAZING_NDL) {
        doubt |= SHADOW_GRAZING;
    }
    return doubt;
}

// Under traced shadows (`shadows`: SHADOWS_RAYS or SHADOWS_HYBRID), whether the point
// w, whose normal has n.l = ndl, gets a shadow ray: the SHADOW_* reasons, or 0 when
// `vis` is the answer already (0 for a surface facing away from the sun, unlit
// whatever is in the way; else the sure shadow map's). Shared by shadow.classify and
// the reflection hits of rt.reflect.
uint shadow_ray_reasons(sampler2D shadow_map, vec3 w, float ndl, uint shadows, out float vis) {
    vis = 0.0;
    if (ndl <= 0.0) {
        return 0u;
    }
    if (shadows == SHADOWS_RAYS) {
        return SHADOW_ALL;
    }
    return shadow_map_doubt(shadow_map, w, ndl, vis);
}

// The material model (README, "Materials"): a base colour, a metallic blend between a
// dielectric (specular reflectance DIELECTRIC_F0 at normal incidence) and a metal
// (reflectance = the base colour), Schlick's Fresnel for the angle, and `reflectivity`,
// the share of the specular reflection that is a mirror image of the scene (traced by
// the reflection passes; the rest is approximated by the sky).
const float DIELECTRIC_F0 = 0.04;

// Specular reflectance at normal incidence.
vec3 specular_f0(vec3 base, float metallic) {
    return mix(vec3(DIELECTRIC_F0), base, metallic);
}

// Schlick's approximation of the Fresnel reflectance at cos_theta = n . v.
vec3 fresnel_schlick(vec3 f0, float cos_theta) {
    float m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

// Weight of the mirror reflection of the scene seen from `v` (n, v unit vectors).
vec3 reflection_weight(vec3 base, float metallic, float reflectivity, vec3 n, vec3 v) {
    return reflectivity * fresnel_schlick(specular_f0(base, metallic), dot(n, v));
}

// Radiance leaving a surface towards `v` under the sun and the sky, without the
// mirror reflection of the scene (the reflection passes add that).
// n, v: unit vectors; visibility: shadow_visibility in [0, 1].
vec3 shade_direct(vec3 base, float roughness, float reflectivity, float metallic, vec3 n, vec3 v, float visibility) {
    vec3 l = frame.light_dir.xyz;
    float ndl = max(dot(n, l), 0.0);
    vec3 f0 = specular_f0(base, metallic);
    vec3 f = fresnel_schlick(f0, dot(n, v));
    // Energy split: what the surface reflects specularly (f) is not diffused; metals
    // diffuse nothing.
    vec3 diffuse_albedo = base * (1.0 - metallic) * (1.0 - f);
    // Normalized Blinn-Phong highlight of the sun with Schlick's Fresnel at the half
    // vector; roughness floored so that mirrors keep a finite, visible highlight.
    float r = max(roughness, 0.05);
    float e = max(2.0 / (r * r) - 2.0, 1.0); // >= 1: pow(x, 0) is undefined at x = 0
    vec3 h = normalize(l + v);
    float spec = (e + 8.0) / (8.0 * PI) * pow(max(dot(n, h), 0.0), e);
    vec3 ks = fresnel_schlick(f0, dot(h, v));
    vec3 direct = (diffuse_albedo * (1.0 / PI) + ks * spec) * frame.light_color.rgb * ndl * visibility;
    // Sky ambient: diffuse, plus the specular share that is not a traced mirror image.
    vec3 sky = mix(frame.sky_horizon.rgb, frame.sky_zenith.rgb, n.y * 0.5 + 0.5);
    vec3 ambient = (diffuse_albedo + (1.0 - reflectivity) * f) * sky * frame.ambient;
    return direct + ambient;
}
#endif
