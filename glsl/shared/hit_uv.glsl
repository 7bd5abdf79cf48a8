// The texture coordinates of a hit's corners, for the kernels that shade hits
// (reflect_path.glsl, primary.glsl): the static and dynamic vertices' coordinates at
// bindings 16 and 17. The includer includes its tracer (traverse.glsl or
// trace_khr.glsl) first: both declare the indices read here.
#ifndef HIT_UV_GLSL
#define HIT_UV_GLSL
layout(binding = 16, std430) readonly buffer StaticUvs { vec2 s_uvs[]; };
layout(binding = 17, std430) readonly buffer DynamicUvs { vec2 d_uvs[]; };

// Corner `k` (0..2)'s texture coordinates of hit triangle `prim` (HIT_DYNAMIC: dynamic).
vec2 hit_uv(uint prim, uint k) {
    uint t = prim & ~HIT_DYNAMIC;
    if ((prim & HIT_DYNAMIC) == 0u) {
        return s_uvs[s_indices[3u * t + k]];
    }
    return d_uvs[d_indices[3u * t + k]];
}
#endif
