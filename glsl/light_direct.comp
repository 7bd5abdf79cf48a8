#version 460
// light.direct: deferred shading of the G-buffer with the sun, shadowed by its shadow
// map or (shadows `rays`, `hybrid`) by the visibility shadow.trace left.
// CPU reference: cpu_ref::shading::shade_direct with shadow_visibility (tests/kernels.rs).
#include "shading.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3) uniform sampler2D gb_albedo; // rgb: base colour, sRGB-encoded
layout(binding = 4) uniform usampler2D gb_material;
layout(binding = 5) uniform sampler2D shadow_map;
layout(binding = 6, rgba32f) uniform writeonly image2D lit;
layout(binding = 7) uniform sampler2D gb_motion; // w: metallic
layout(binding = 8, r32f) uniform image2D visibility; // written under the map: what it gave

layout(push_constant) uniform Push {
    uint traced; // 1: the sun's visibility is `visibility`'s, else the shadow map's (then written there)
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(frame.resolution)))) {
        return;
    }
    float depth = texelFetch(gb_depth, p, 0).r;
    uint material = texelFetch(gb_material, p, 0).r;
    vec3 w = world_from_depth(p, depth);
    vec3 to_camera = frame.camera_pos.xyz - w;
    vec3 color;
    float vis = 1.0;
    if (material == MATERIAL_NONE) {
        color = sky_radiance(-normalize(to_camera));
    } else {
        vec4 nr = texelFetch(gb_normal, p, 0);
        vec4 ar = texelFetch(gb_albedo, p, 0);
        vis = pc.traced != 0u ? imageLoad(visibility, p).r : shadow_visibility(shadow_map, w);
        float metallic = texelFetch(gb_motion, p, 0).w;
        color = shade_direct(srgb_decode(ar.rgb), ar.a, nr.w, metallic, normalize(nr.xyz), normalize(to_camera), vis);
    }
    imageStore(lit, p, vec4(color, 1.0));
    if (pc.traced == 0u) {
        imageStore(visibility, p, vec4(vis)); // for readbacks (reports, tests)
    }
}
