// A material's base colour: its albedo times its texture (a layer of the scene's
// sRGB 2D array texture; trilinear, repeating), and the ray-cone level of detail of a
// texture lookup at a ray-traced hit. Mirrored by cpu_ref::texture.
#ifndef SURFACE_GLSL
#define SURFACE_GLSL
#include "types.glsl"

// The lowest a mirror direction may leave a surface: cos of its angle to the surface's
// geometric normal.
const float BENT_NORMAL_MIN_COS = 0.01;

// A shading normal `n` whose mirror direction for the view direction `v` (towards the
// viewer) stays above the surface's plane: when reflect(-v, n) points below (or within
// BENT_NORMAL_MIN_COS of) the plane of the geometric normal `g` (which faces v), the
// direction is lifted to that bound and the normal becomes the half vector between v
// and it, the normal that mirrors v there. Interpolated or file normals bent away from
// the facet (silhouettes of smooth meshes, normal-mapped scans) would otherwise send
// reflected rays into the surface. All unit vectors.
vec3 clamp_bent_normal(vec3 n, vec3 g, vec3 v) {
    vec3 r = reflect(-v, n);
    float d = dot(r, g);
    if (d >= BENT_NORMAL_MIN_COS) {
        return n;
    }
    vec3 lifted = normalize(r + g * (BENT_NORMAL_MIN_COS - d));
    return normalize(v + lifted);
}

// In a fragment shader: the mip level from the screen-space derivatives of `uv`.
vec3 base_color(Material m, sampler2DArray textures, vec2 uv) {
    if (m.texture_layer == TEXTURE_NONE) {
        return m.albedo;
    }
    return m.albedo * texture(textures, vec3(uv, float(m.texture_layer))).rgb;
}

// Anywhere: at mip level `lod`.
vec3 base_color_lod(Material m, sampler2DArray textures, vec2 uv, float lod) {
    if (m.texture_layer == TEXTURE_NONE) {
        return m.albedo;
    }
    return m.albedo * textureLod(textures, vec3(uv, float(m.texture_layer)), lod).rgb;
}

// Mip level of a lookup at a ray hit by ray cones (Akenine-Moller et al. 2019, "Texture
// Level of Detail Strategies for Real-Time Ray Tracing", Ray Tracing Gems ch. 20): the cone is
// `width` wide at the hit; the triangle has corners p0..p2, texture coordinates
// uv0..uv2 and a texture `texels` wide; `cos_incidence` is |geometric normal . dir|.
float ray_cone_lod(float width, float cos_incidence, vec3 p0, vec3 p1, vec3 p2, vec2 uv0, vec2 uv1, vec2 uv2, float texels) {
    vec2 e1 = uv1 - uv0, e2 = uv2 - uv0;
    float t_area = texels * texels * abs(e1.x * e2.y - e1.y * e2.x);
    float p_area = length(cross(p1 - p0, p2 - p0));
    // A texture-less (all-equal UVs) or degenerate triangle: the finest level.
    if (!(t_area > 0.0) || !(p_area > 0.0)) {
        return 0.0;
    }
    return 0.5 * log2(t_area / p_area) + log2(width / max(cos_incidence, 1e-4));
}
#endif
