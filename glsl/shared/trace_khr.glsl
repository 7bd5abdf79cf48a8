// The vendor tracer (tracer = khr): trace_ray and hit_vertex with the signature and
// meaning traverse.glsl gives them, through a top-level acceleration structure and
// VK_KHR_ray_tracing_pipeline, so a ray-generation shader written against them shades
// exactly what the LBVH's compute kernel shades. khr_hit.rchit and khr_miss.rmiss
// fill the payload.
//
// The includer defines TRAVERSE_BINDING (the first of traverse.glsl's eight bindings)
// first; here +0 is the scene's top level, +1/+2 the static vertices and indices, +3
// the static permutation (the bottom level's primitive i is scene triangle s_perm[i]:
// tracers/khr.rs hands the driver the triangles in Morton order), +4/+5 the dynamic
// vertices and indices (+6, +7 unused). Instances carry mask 1 (static) or 2
// (dynamic), so a trace skips the geometry whose triangle count it is given as 0.
// Epsilon policy: the driver's watertight test; a hit counts when tmin <= t <= tmax
// (traverse.glsl: tmin < t < tmax); ties between triangles go to whichever the
// driver finds first.
#ifndef TRACE_KHR_GLSL
#define TRACE_KHR_GLSL
#extension GL_EXT_ray_tracing : require
#include "types.glsl"
#include "hit.glsl"

layout(binding = TRAVERSE_BINDING + 0) uniform accelerationStructureEXT scene_tlas;
layout(binding = TRAVERSE_BINDING + 1, std430) readonly buffer StaticVertices { Vertex s_vertices[]; };
layout(binding = TRAVERSE_BINDING + 2, std430) readonly buffer StaticIndices { uint s_indices[]; };
layout(binding = TRAVERSE_BINDING + 3, std430) readonly buffer StaticPerm { uint s_perm[]; };
layout(binding = TRAVERSE_BINDING + 4, std430) readonly buffer DynamicVertices { Vertex d_vertices[]; };
layout(binding = TRAVERSE_BINDING + 5, std430) readonly buffer DynamicIndices { uint d_indices[]; };

layout(location = 0) rayPayloadEXT Hit khr_payload;

// Vertex `k` (0..2) of hit triangle `prim` (HIT_DYNAMIC: dynamic geometry).
Vertex hit_vertex(uint prim, uint k) {
    uint t = prim & ~HIT_DYNAMIC;
    if ((prim & HIT_DYNAMIC) == 0u) {
        return s_vertices[s_indices[3u * t + k]];
    }
    return d_vertices[d_indices[3u * t + k]];
}

// Traces one ray through the static and dynamic geometry (a count of 0 skips it).
// Returns the closest hit, or with any_hit the first found.
Hit trace_ray(vec3 origin, vec3 dir, float tmin, float tmax, uint static_tris, uint dynamic_tris, bool any_hit) {
    uint mask = (static_tris != 0u ? 1u : 0u) | (dynamic_tris != 0u ? 2u : 0u);
    khr_payload = Hit(tmax, BVH_INVALID, 0.0, 0.0);
    if (mask != 0u) {
        uint flags = gl_RayFlagsOpaqueEXT | (any_hit ? gl_RayFlagsTerminateOnFirstHitEXT : 0u);
        traceRayEXT(scene_tlas, flags, mask, 0, 0, 0, origin, tmin, dir, tmax, 0);
    }
    Hit h = khr_payload;
    if ((h.prim & HIT_DYNAMIC) == 0u) { // a static hit (BVH_INVALID has the bit set)
        h.prim = s_perm[h.prim];
    }
    return h;
}
#endif
