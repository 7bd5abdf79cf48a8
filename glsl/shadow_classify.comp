#version 460
// shadow.classify: for every pixel, whether the shadow map answers its sun visibility
// or a shadow ray must: the mask (nonzero: the SHADOW_* reasons it gets a ray) and the
// visibility where the map answers (-1 where a ray will), by shadow_ray_reasons:
// `rays` lists every lit pixel (SHADOW_ALL); `hybrid` those where the map is not sure.
// The sky (visibility 1) and surfaces facing away from the sun (0) are never listed. shadow.compact lists the mask's pixels, shadow.trace answers them.
// CPU reference: cpu_ref::shadows::classify (tests/shadows.rs).
#include "shading.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3) uniform usampler2D gb_material;
layout(binding = 4) uniform sampler2D shadow_map;
layout(binding = 5, r32ui) uniform writeonly uimage2D mask;
layout(binding = 6, r32f) uniform writeonly image2D visibility;

layout(push_constant) uniform Push {
    uint shadows; // SHADOWS_RAYS or SHADOWS_HYBRID
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(frame.resolution)))) {
        return;
    }
    uint doubt = 0u;
    float vis = 1.0;
    if (texelFetch(gb_material, p, 0).r != MATERIAL_NONE) {
        float ndl = dot(normalize(texelFetch(gb_normal, p, 0).xyz), frame.light_dir.xyz);
        vec3 w = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
        doubt = shadow_ray_reasons(shadow_map, w, ndl, pc.shadows, vis);
    }
    if (doubt != 0u) {
        vis = -1.0; // shadow.trace's to write: a pixel it missed stays out of 0..1
    }
    imageStore(mask, p, uvec4(doubt));
    imageStore(visibility, p, vec4(vis));
}
