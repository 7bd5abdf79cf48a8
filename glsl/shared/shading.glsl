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
float shadow_visibility(sampler2D shadow_map, vec3 w) {
    vec4 c = frame.light_view_proj * vec4(w, 1.0);
    vec3 ndc = c.xyz / c.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z > 1.0) {
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
            vec4 lit = step(vec4(ref_depth), textureGather(shadow_map, g, 0));
            sum += lit.w * wx0 * wy0 + lit.z * wx1 * wy0 + lit.x * wx0 * wy1 + lit.y * wx1 * wy1;
        }
    }
    float taps = float((2 * r + 1) * (2 * r + 1));
    return sum / taps;
}

// Radiance leaving a surface towards `v` under the sun and the sky, without the
// specular reflection of the scene (the reflection passes add that).
// n, v: unit vectors; visibility: shadow_visibility in [0, 1].
vec3 shade_direct(vec3 albedo, float roughness, float reflectivity, vec3 n, vec3 v, float visibility) {
    vec3 l = frame.light_dir.xyz;
    float ndl = max(dot(n, l), 0.0);
    // Energy split: what is reflected specularly is not diffused.
    vec3 diffuse = albedo * (1.0 - reflectivity) * (1.0 / PI);
    // Normalized Blinn-Phong highlight of the sun; roughness floored so that mirrors
    // keep a finite, visible highlight.
    float r = max(roughness, 0.05);
    float e = max(2.0 / (r * r) - 2.0, 1.0); // >= 1: pow(x, 0) is undefined at x = 0
    vec3 h = normalize(l + v);
    float spec = (e + 8.0) / (8.0 * PI) * pow(max(dot(n, h), 0.0), e);
    float ks = 0.04 + 0.96 * reflectivity;
    vec3 direct = (diffuse + vec3(ks * spec)) * frame.light_color.rgb * ndl * visibility;
    vec3 sky = mix(frame.sky_horizon.rgb, frame.sky_zenith.rgb, n.y * 0.5 + 0.5);
    vec3 ambient = albedo * (1.0 - reflectivity) * sky * frame.ambient;
    return direct + ambient;
}
#endif
