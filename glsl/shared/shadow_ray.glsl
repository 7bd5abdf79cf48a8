// shadow.trace's ray, shared by its two kernels: shadow_trace.comp (Speculum's BVHs,
// traverse.glsl) and shadow_trace.rgen (the vendor tracer, trace_khr.glsl); the
// includer includes its tracer first. See shadow_trace.comp for what the ray does.
// CPU reference: cpu_ref::shadows::ray_visibility (tests/shadows.rs).
#ifndef SHADOW_RAY_GLSL
#define SHADOW_RAY_GLSL
#include "frame.glsl"
#include "pixel_list.glsl"

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3, std430) readonly buffer Pixels { uint pixels[]; };
layout(binding = 4, std430) readonly buffer Indirect { uvec4 indirect; }; // w: count
layout(binding = 5, r32f) uniform writeonly image2D visibility;

layout(push_constant) uniform Push {
    uint static_tris;
    uint dynamic_tris;
} pc;

// The sun's visibility of list entry `i` (< the list's length), stored.
void shadow_entry(uint i) {
    ivec2 p = unpack_pixel(pixels[i]);
    vec3 pos = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    vec3 n = normalize(texelFetch(gb_normal, p, 0).xyz);
    vec3 origin = pos + n * offset_scale(pos);
    Hit h = trace_ray(origin, frame.light_dir.xyz, 0.0, 3.0e38, pc.static_tris, pc.dynamic_tris, true);
    imageStore(visibility, p, vec4(h.prim == BVH_INVALID ? 1.0 : 0.0));
}
#endif
