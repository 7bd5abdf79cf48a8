// What ssr.classify and ssr.trace share: the reflected view ray of a pixel, and the
// confidence its heading allows. Mirrored by cpu_ref::ssr.
#ifndef SSR_GLSL
#define SSR_GLSL
#include "frame.glsl"

// The reflected ray of pixel p (G-buffer depth and world normal) in view space.
struct SsrRay {
    vec3 vpos; // the surface point
    vec3 vn;   // its unit normal
    vec3 vdir; // the unit reflected direction
};

SsrRay ssr_ray(ivec2 p, float depth, vec3 n_world) {
    SsrRay r;
    r.vpos = (frame.view * vec4(world_from_depth(p, depth), 1.0)).xyz;
    r.vn = normalize(mat3(frame.view) * normalize(n_world));
    r.vdir = normalize(reflect(normalize(r.vpos), r.vn));
    return r;
}

// The confidence factor of a ray's heading (view space, unit): 1 for rays away from
// the camera, falling to 0 for rays straight back at it, which the screen rarely holds.
// A hit's confidence is at most this (edge fade aside).
float heading_confidence(vec3 vdir) {
    return clamp(1.0 - vdir.z, 0.0, 1.0);
}
#endif
