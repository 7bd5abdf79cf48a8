#version 460
// rt.trace: closest-hit (or any-hit) traversal of the static and dynamic BVHs for a
// list of rays (glsl/shared/traverse.glsl). Mirrored by cpu_ref::trace.
#define TRAVERSE_BINDING 2
#include "traverse.glsl"

layout(local_size_x = LBVH_WG) in;

#include "ray_list.glsl"

void main() {
    uint r = gl_GlobalInvocationID.x;
    if (r >= pc.ray_count) {
        return;
    }
    Ray ray = rays[r];
    hits[r] = trace_ray(ray.origin, ray.dir, ray.tmin, ray.tmax, pc.static_tris, pc.dynamic_tris, pc.any_hit != 0u);
}
