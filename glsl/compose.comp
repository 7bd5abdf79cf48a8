#version 460
// compose: the lit colour plus the merged reflection weighted by the surface's
// reflectivity and Fresnel term (shading.glsl), then exposure, ACES tonemap (Narkowicz
// 2015 fit) and sRGB encoding to LDR. Mirrored by cpu_ref::compose.
#include "glossy.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, rgba32f) uniform readonly image2D hdr;
layout(binding = 2, rgba8) uniform writeonly image2D ldr;
// rgb: reflected radiance; a: source (SOURCE_*).
layout(binding = 3, rgba32f) uniform readonly image2D reflection;
layout(binding = 4) uniform sampler2D gb_normal; // w: reflectivity
layout(binding = 5) uniform sampler2D gb_albedo; // rgb: base colour, sRGB-encoded
layout(binding = 6) uniform sampler2D gb_depth;
layout(binding = 7) uniform usampler2D gb_material;
layout(binding = 8) uniform sampler2D gb_motion; // w: metallic
layout(binding = 9, r32ui) uniform readonly uimage2D fail_mask; // read by COMPOSE_FAIL_MASK

layout(push_constant) uniform ComposePush {
    uvec2 size;
    float exposure;
    uint mode; // COMPOSE_PLAIN, COMPOSE_REFLECT, COMPOSE_PROVENANCE or COMPOSE_FAIL_MASK
    float reflective_min; // COMPOSE_FAIL_MASK: which pixels reflect
} pc;

const uint FAIL_COLOURS[10] = uint[](MASK_COLOUR_0, MASK_COLOUR_1, MASK_COLOUR_2, MASK_COLOUR_3,
                                     MASK_COLOUR_4, MASK_COLOUR_5, MASK_COLOUR_6, MASK_COLOUR_7, MASK_COLOUR_8,
                                     MASK_COLOUR_9);

// Beyond 7.24 the ACES fit is flat at 1, and clamping its input here keeps x * x far
// from f32 overflow (near 1.8e19, where inf / inf would give NaN): e.g. exposure 1e20.
const float ACES_MAX = 1.0e4;

vec3 aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}


void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(pc.size)))) {
        return;
    }
    if (pc.mode == COMPOSE_FAIL_MASK) {
        // Mirrored by ReflectionMaps::fail_mask_rgba: black where nothing reflects,
        // dark blue where SSR answered, grey where untraced, else the colour of the
        // lowest reason bit.
        uint rgb = 0u;
        if (texelFetch(gb_material, p, 0).r != MATERIAL_NONE && texelFetch(gb_normal, p, 0).w > pc.reflective_min) {
            uint m = imageLoad(fail_mask, p).r;
            uint reason = (m & FAIL_UNTRACED) != 0u ? FAIL_UNTRACED : m;
            rgb = m == 0u ? MASK_COLOUR_SSR_OK : FAIL_COLOURS[uint(findLSB(reason)) % 10u];
        }
        imageStore(ldr, p, vec4(unpackUnorm4x8(rgb).rgb, 1.0));
        return;
    }
    vec3 c = imageLoad(hdr, p).rgb;
    if (pc.mode != COMPOSE_PLAIN) {
        vec4 r = imageLoad(reflection, p);
        uint source = uint(r.a);
        if (pc.mode == COMPOSE_PROVENANCE) {
            // The method's figures: pink = ray traced, blue = SSR, grey = no reflector;
            // a glossy surface's (glossy.glsl) in lighter pink and blue; a rays-only
            // tile's traced pixels (FAIL_SKIPPED, the adaptive hybrid) orange.
            vec3 tint = source == SOURCE_RT ? vec3(1.0, 0.25, 0.6) : (source == SOURCE_SSR ? vec3(0.15, 0.35, 1.0) : vec3(0.35));
            if (source != SOURCE_NONE && is_glossy(texelFetch(gb_albedo, p, 0).a)) {
                tint = source == SOURCE_RT ? vec3(1.0, 0.45, 0.75) : vec3(0.45, 0.6, 1.0);
            }
            if (source == SOURCE_RT && imageLoad(fail_mask, p).r == FAIL_SKIPPED) {
                tint = vec3(1.0, 0.55, 0.1);
            }
            float luma = dot(max(c, vec3(0.0)), vec3(0.2126, 0.7152, 0.0722));
            imageStore(ldr, p, vec4(tint * (0.55 + 0.45 * clamp(luma, 0.0, 1.0)), 1.0));
            return;
        }
        uint material = texelFetch(gb_material, p, 0).r;
        if (material != MATERIAL_NONE) {
            vec4 nr = texelFetch(gb_normal, p, 0);
            vec3 base = srgb_decode(texelFetch(gb_albedo, p, 0).rgb);
            vec3 w = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
            vec3 v = normalize(frame.camera_pos.xyz - w);
            c += reflection_weight(base, texelFetch(gb_motion, p, 0).w, nr.w, normalize(nr.xyz), v) * r.rgb;
        }
    }
    c = max(c, vec3(0.0)) * pc.exposure;
    // NaN-safe: a NaN (e.g. 0 x inf) is black, anything larger than ACES_MAX is ACES_MAX.
    c = clamp(mix(c, vec3(0.0), isnan(c)), 0.0, ACES_MAX);
    imageStore(ldr, p, vec4(srgb_encode(aces(c)), 1.0));
}
