#version 460
// compose: exposure, ACES tonemap (Narkowicz 2015 fit) and sRGB encoding to LDR.
// Mirrored by cpu_ref::compose.

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 0, rgba32f) uniform readonly image2D hdr;
layout(binding = 1, rgba8) uniform writeonly image2D ldr;

layout(push_constant) uniform ComposePush {
    uvec2 size;
    float exposure;
    float _pad0;
} pc;

vec3 aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb_encode(vec3 c) {
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, ivec2(pc.size)))) {
        return;
    }
    vec3 c = max(imageLoad(hdr, p).rgb, vec3(0.0)) * pc.exposure;
    imageStore(ldr, p, vec4(srgb_encode(aces(c)), 1.0));
}
