#version 460
// shadow.trace: one any-hit shadow ray toward the sun per pixel of the shadow list
// (indirect dispatch), through the static and dynamic BVHs: visibility 1 when nothing
// is in the way, else 0. The ray starts at the G-buffer position pushed off the
// surface along its normal (offset_scale), like the reflected rays.
// CPU reference: cpu_ref::shadows::ray_visibility (tests/shadows.rs).
#include "frame.glsl"
#define TRAVERSE_BINDING 6
#include "traverse.glsl"
#include "shadow_ray.glsl"

layout(local_size_x = RT_LIST_WG) in;

void main() {
    uint i = list_entry(indirect.w, RT_LIST_WG);
    if (i < indirect.w) {
        shadow_entry(i);
    }
}
