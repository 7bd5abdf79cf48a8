// rt.trace's list of rays and their hits (bindings 0 and 1) and its push constants,
// for each of its kernels (rt_trace.comp, rt_trace_refill.comp, rt_trace.rgen): Ray and
// TracePush in gpu_types.rs and passes/rt_trace.rs. The includer includes hit.glsl
// (Hit) first.
#ifndef RAY_LIST_GLSL
#define RAY_LIST_GLSL

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
    uint static_tris;  // 0: no static BVH (or geometry)
    uint dynamic_tris; // 0: no dynamic BVH (or geometry)
    uint any_hit;      // 1: stop at the first hit (shadow rays)
} pc;
#endif
