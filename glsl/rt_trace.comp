#version 460
// rt.trace: closest-hit (or any-hit) traversal of the static and dynamic BVHs for a
// list of rays (glsl/shared/traverse.glsl). Mirrored by cpu_ref::trace.
#define TRAVERSE_BINDING 2
#include "traverse.glsl"

layout(local_size_x = LBVH_WG) in;

struct Ray {
    vec3 origin;
    float tmin;
    vec3 dir;
    float tmax;
};

layout(binding = 0, std430) readonly buffer Rays { Ray rays[]; };
layout(binding = 1, std430) writeonly buffer Hits { Hit hits[]; };

layout(push_constant) uniform Push {
    uint ray_count;
    uint static_tris;  // 0: no static BVH
    uint dynamic_tris; // 0: no dynamic BVH
    uint any_hit;      // 1: stop at the first hit (shadow rays)
} pc;

void main() {
    uint r = gl_GlobalInvocationID.x;
    if (r >= pc.ray_count) {
        return;
    }
    Ray ray = rays[r];
    hits[r] = trace_ray(ray.origin, ray.dir, ray.tmin, ray.tmax, pc.static_tris, pc.dynamic_tris, pc.any_hit != 0u);
}
