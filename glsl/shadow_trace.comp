#version 460
// shadow.trace: one any-hit shadow ray toward the sun per pixel of the shadow list
// (indirect dispatch), through the static and dynamic BVHs: visibility 1 when nothing
// is in the way, else 0. The ray starts at the G-buffer position pushed off the
// surface along its normal (offset_scale), like the reflected rays.
// CPU reference: cpu_ref::shadows::ray_visibility (tests/shadows.rs).
#include "frame.glsl"
#define TRAVERSE_BINDING 6
#include "traverse.glsl"
#include "pixel_list.glsl"

layout(local_size_x = RT_LIST_WG) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3, std430) readonly buffer Pixels { uint pixels[]; };
layout(binding = 4, std430) readonly buffer Indirect { uvec4 indirect; }; // w: count
layout(binding = 5, r32f) uniform writeonly image2D visibility;

layout(push_constant) uniform Push {
    uint static_tris;
    uint dynamic_tris;
} pc;

void main() {
    uint i = list_entry(indirect.w, RT_LIST_WG);
    if (i >= indirect.w) {
        return;
    }
    ivec2 p = unpack_pixel(pixels[i]);
    vec3 pos = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    vec3 n = normalize(texelFetch(gb_normal, p, 0).xyz);
    vec3 origin = pos + n * offset_scale(pos);
    Hit h = trace_ray(origin, frame.light_dir.xyz, 0.0, 3.0e38, pc.static_tris, pc.dynamic_tris, true);
    imageStore(visibility, p, vec4(h.prim == BVH_INVALID ? 1.0 : 0.0));
}
