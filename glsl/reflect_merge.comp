#version 460
// CPU reference: cpu_ref::merge::merge (tests/merge.rs).
#extension GL_KHR_shader_subgroup_arithmetic : require
// reflect.merge, step 1: each reflective pixel takes its reflection from SSR (where
// SSR succeeded) or from the ray tracer (where it failed), labelled by source; a faded
// SSR hit (FAIL_BLEND) is blended with the ray-traced colour by its confidence and
// labelled ray traced (it was traced). Each WG_2D x WG_2D tile also records which
// sources it holds (bit 1 << SOURCE_*), so that the seam blur can skip the tiles no
// seam comes near. Mirrored by cpu_ref::merge::merge.
#include "frame.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, r32ui) uniform readonly uimage2D fail_mask;
layout(binding = 2, rgba32f) uniform readonly image2D ssr_in;
layout(binding = 3, rgba32f) uniform readonly image2D rt_in;
layout(binding = 4) uniform sampler2D gb_normal;
layout(binding = 5) uniform usampler2D gb_material;
layout(binding = 6, rgba32f) uniform writeonly image2D merged; // rgb, a: SOURCE_*
layout(binding = 7, std430) buffer TileSources { uint tile_sources[]; }; // zeroed before

layout(push_constant) uniform Push {
    float reflective_min;
    uint rt_enabled; // 0 (ssr mode): failed pixels get no reflection
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    uint bits = 0u;
    if (all(lessThan(p, ivec2(frame.resolution)))) {
        bool reflective = texelFetch(gb_material, p, 0).r != MATERIAL_NONE && texelFetch(gb_normal, p, 0).w > pc.reflective_min;
        vec4 out_value = vec4(0.0, 0.0, 0.0, float(SOURCE_NONE));
        if (reflective) {
            uint fail = imageLoad(fail_mask, p).r;
            vec4 ssr = imageLoad(ssr_in, p); // a: confidence
            if (fail == 0u) {
                out_value = vec4(ssr.rgb, float(SOURCE_SSR));
            } else if ((fail & FAIL_UNTRACED) != 0u) {
                // A weak reflector not traced: the ray its 2x2 block's even corner
                // traced (ssr.glsl, traced_for_block), else SSR's answer, the sky.
                ivec2 q = p & ~1;
                uint qf = imageLoad(fail_mask, q).r;
                bool q_traced = pc.rt_enabled != 0u && qf != 0u && (qf & FAIL_UNTRACED) == 0u;
                out_value = q_traced ? vec4(imageLoad(rt_in, q).rgb, float(SOURCE_RT)) : vec4(ssr.rgb, float(SOURCE_SSR));
            } else if (pc.rt_enabled != 0u) {
                // A faded SSR hit weighs by its confidence against the ray-traced colour.
                float c = fail == FAIL_BLEND ? ssr.a : 0.0;
                out_value = vec4(mix(imageLoad(rt_in, p).rgb, ssr.rgb, c), float(SOURCE_RT));
            } else if (fail == FAIL_BLEND) {
                // SSR alone: a faded hit fades out to no reflection.
                out_value = vec4(ssr.rgb * ssr.a, float(SOURCE_SSR));
            }
        }
        imageStore(merged, p, out_value);
        bits = 1u << uint(out_value.a);
    }
    // One atomic per subgroup (no workgroup barrier: lavapipe runs barrier-free
    // workgroups without switching between its SIMD chunks).
    bits = subgroupOr(bits);
    if (subgroupElect()) {
        atomicOr(tile_sources[gl_WorkGroupID.y * uint(tile_grid().x) + gl_WorkGroupID.x], bits);
    }
}
