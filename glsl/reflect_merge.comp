#version 460
// reflect.merge, step 1: each reflective pixel takes its reflection from SSR (where
// SSR succeeded) or from the ray tracer (where it failed), labelled by source.
#include "frame.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1, r32ui) uniform readonly uimage2D fail_mask;
layout(binding = 2, rgba32f) uniform readonly image2D ssr_in;
layout(binding = 3, rgba32f) uniform readonly image2D rt_in;
layout(binding = 4) uniform sampler2D gb_normal;
layout(binding = 5) uniform usampler2D gb_material;
layout(binding = 6, rgba32f) uniform writeonly image2D merged; // rgb, a: SOURCE_*

layout(push_constant) uniform Push {
    float reflective_min;
    uint rt_enabled; // 0 (ssr mode): failed pixels get no reflection
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(frame.resolution)))) {
        return;
    }
    bool reflective = texelFetch(gb_material, p, 0).r != MATERIAL_NONE && texelFetch(gb_normal, p, 0).w > pc.reflective_min;
    vec4 out_value = vec4(0.0, 0.0, 0.0, float(SOURCE_NONE));
    if (reflective) {
        if (imageLoad(fail_mask, p).r == 0u) {
            out_value = vec4(imageLoad(ssr_in, p).rgb, float(SOURCE_SSR));
        } else if (pc.rt_enabled != 0u) {
            out_value = vec4(imageLoad(rt_in, p).rgb, float(SOURCE_RT));
        }
    }
    imageStore(merged, p, out_value);
}
