#version 460
// rt.reflect: one invocation per pixel of the compacted list (indirect
// dispatch). The reflected ray starts at the G-buffer position, walks the static and
// dynamic BVHs, and the hit is shaded with the sun (shadow map lookup, or a shadow ray
// when asked) and the sky ambient; while the hit is reflective the path continues,
// up to max_bounces rays. A miss returns the sky. Textures are looked up at the mip
// level of a ray cone that starts as wide as the pixel's footprint at the reflecting
// point and spreads by the pixel's angle (a flat mirror keeps the spread).
//
// Self-intersection: each origin is pushed off its surface along the normal by a
// distance that grows with its distance from the camera (depth-buffer and float
// error both grow with it), and the hit must be beyond tmin.
// CPU reference: cpu_ref::reflect::reflected_radiance (tests/rt_reflect.rs).
#include "shading.glsl"
#define TRAVERSE_BINDING 8
#include "traverse.glsl"
#include "reflect_path.glsl"

layout(local_size_x = RT_LIST_WG) in;

void main() {
    uint i = list_entry(indirect.w, RT_LIST_WG);
    if (i < indirect.w) {
        reflect_entry(i);
    }
}
