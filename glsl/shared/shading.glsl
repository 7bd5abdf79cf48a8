// Direct lighting: shadow-map PCF and the surface model. Mirrored exactly by
// src/cpu_ref/shading.rs; change both together.
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "frame.glsl"

const float PI = 3.14159265358979;

// 1 where the shadow-map texel `q` (clamped to the map) is at or beyond `ref_depth`.
float shadow_texel(sampler2D shadow_map, ivec2 q, float ref_depth) {
    int last = int(frame.shadow_map_size) - 1;
    q = clamp(q, ivec2(0), ivec2(last));
    return texelFetch(shadow_map, q, 0).r >= ref_depth ? 1.0 : 0.0;
}

// Fraction of light reaching world point `w`: the mean of (2r+1)^2 bilinearly
// filtered depth compares centred on w's shadow-map position. Equivalent to that
// mean but computed over the (2r+2)^2 texels it touches, each fetched once: interior
// texels weigh 1, the border rows and columns (1-f) and f.
float shadow_visibility(sampler2D shadow_map, vec3 w) {
    vec4 c = frame.light_view_proj * vec4(w, 1.0);
    vec3 ndc = c.xyz / c.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z > 1.0) {
        return 1.0; // outside the light's frustum: unshadowed
    }
    float ref_depth = ndc.z - frame.shadow_bias;
    vec2 t = uv * float(frame.shadow_map_size) - 0.5;
    vec2 cell = floor(t);
    vec2 f = t - cell;
    int r = int(min(frame.pcf_radius, MAX_PCF_RADIUS));
    ivec2 base = ivec2(cell) - r;
    int n = 2 * r + 2;
    float sum = 0.0;
    for (int j = 0; j < n; ++j) {
        float wy = j == 0 ? 1.0 - f.y : (j == n - 1 ? f.y : 1.0);
        for (int i = 0; i < n; ++i) {
            float wx = i == 0 ? 1.0 - f.x : (i == n - 1 ? f.x : 1.0);
            sum += wx * wy * shadow_texel(shadow_map, base + ivec2(i, j), ref_depth);
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
