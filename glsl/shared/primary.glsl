// gbuffer.trace's primary rays, shared by its two kernels: gbuffer_trace.comp (Speculum's
// BVHs, traverse.glsl) and gbuffer_trace.rgen (the vendor tracer, trace_khr.glsl). The
// includer includes frame.glsl and its tracer first; both define trace_ray and hit_vertex
// alike, so the two write the same G-buffer.
//
// One ray a pixel, through the pixel's centre from the near plane to the far plane (the
// raster's clip volume), writes what gbuffer.frag writes for the surface it hits: depth
// (the hit's projected z; this pass's buffer, copied into the depth image), the normal
// facing the viewer with its mirror direction kept above the facet and the traced
// reflectivity, the sRGB-encoded base colour and roughness, the material, and the motion
// (where the point was the frame before: the dynamic vertices' previous positions,
// weighted as the hit is) with the metallic. A miss writes the raster's clear values.
// Where raster takes the texture's level of detail from screen derivatives, a compute
// kernel has none: the level is the ray cone's (surface.glsl), the cone as wide as the
// pixel's footprint at the hit. Triangles are double-sided (the raster culls nothing).
// CPU reference: cpu_ref::primary::gbuffer_texel (tests/suite/gbuffer.rs).
#ifndef PRIMARY_GLSL
#define PRIMARY_GLSL
#include "surface.glsl"
#include "glossy.glsl"
#include "hit_uv.glsl"

layout(binding = 1, std430) readonly buffer Materials { Material materials[]; };
layout(binding = 2) uniform sampler2DArray scene_textures;
// The same texels as UNORM: data textures (roughness, metallic) with no sRGB decode.
layout(binding = 3) uniform sampler2DArray data_textures;
// The dynamic vertices as the frame before saw them (sim's previous-vertex copy).
layout(binding = 4, std430) readonly buffer DynamicPrevious { Vertex d_previous[]; };
// The hits' depth, row by row (copied into the G-buffer's depth image after the pass).
layout(binding = 5, std430) writeonly buffer DepthOut { float depth_out[]; };
layout(binding = 6, rgba16f) uniform writeonly image2D normal_out;
layout(binding = 7, rgba8) uniform writeonly image2D albedo_out;
// Bindings 8-15: the tracer's; 16-17: hit_uv.glsl's texture coordinates.
layout(binding = 18, r32ui) uniform writeonly uimage2D material_out;
layout(binding = 19, rgba16f) uniform writeonly image2D motion_out;

layout(push_constant) uniform Push {
    uint static_tris;
    uint dynamic_tris;
} pc;

// Writes pixel `p`'s G-buffer texels (`p` inside the frame).
void primary_pixel(ivec2 p) {
    uint at = uint(p.y) * frame.resolution.x + uint(p.x);
    vec3 near = world_from_depth(p, 0.0);
    vec3 dir = world_from_depth(p, 1.0) - near;
    Hit h = trace_ray(near, dir, 0.0, 1.0, pc.static_tris, pc.dynamic_tris, false);
    if (h.prim == BVH_INVALID) { // a miss, or a failed walk (t = -1): the sky
        depth_out[at] = 1.0;
        imageStore(normal_out, p, vec4(0.0));
        imageStore(albedo_out, p, vec4(0.0));
        imageStore(material_out, p, uvec4(MATERIAL_NONE));
        imageStore(motion_out, p, vec4(0.0));
        return;
    }
    Vertex a = hit_vertex(h.prim, 0u);
    Vertex b = hit_vertex(h.prim, 1u);
    Vertex c = hit_vertex(h.prim, 2u);
    float w = 1.0 - h.u - h.v;
    vec3 hp = near + dir * h.t;
    vec4 clip = frame.view_proj * vec4(hp, 1.0);
    depth_out[at] = clamp(clip.z / clip.w, 0.0, 1.0);

    Material m = materials[a.material];
    vec3 v = normalize(frame.camera_pos.xyz - hp);
    // The triangle's own plane, facing the viewer.
    vec3 g = cross(b.position - a.position, c.position - a.position);
    g = dot(g, v) < 0.0 ? -normalize(g) : normalize(g);
    vec3 n = normalize(w * a.normal + h.u * b.normal + h.v * c.normal);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    if (!any(isnan(g)) && !any(isinf(g))) { // a sliver too thin for its plane: as raster
        n = clamp_bent_normal(n, g, v);
    }
    float roughness = m.roughness, metallic = m.metallic;
    vec3 base = m.albedo;
    if (m.texture_layer != TEXTURE_NONE || m.roughness_layer != TEXTURE_NONE) {
        vec2 ta = hit_uv(h.prim, 0u), tb = hit_uv(h.prim, 1u), tc = hit_uv(h.prim, 2u);
        vec2 uv = w * ta + h.u * tb + h.v * tc;
        float cone = pixel_spread() * length(hp - frame.camera_pos.xyz);
        float texels = float(textureSize(scene_textures, 0).x);
        float lod = ray_cone_lod(cone, abs(dot(g, normalize(dir))), a.position, b.position, c.position, ta, tb, tc, texels);
        base = base_color_lod(m, scene_textures, uv, lod);
        if (m.roughness_layer != TEXTURE_NONE) { // glTF's layout: green roughness, blue metallic
            vec4 t = textureLod(data_textures, vec3(uv, float(m.roughness_layer)), lod);
            roughness *= t.g;
            metallic *= t.b;
        }
    }
    vec3 motion = vec3(0.0);
    if ((h.prim & HIT_DYNAMIC) != 0u) {
        uint t = h.prim & ~HIT_DYNAMIC;
        vec3 was = w * d_previous[d_indices[3u * t]].position + h.u * d_previous[d_indices[3u * t + 1u]].position
            + h.v * d_previous[d_indices[3u * t + 2u]].position;
        motion = was - (w * a.position + h.u * b.position + h.v * c.position);
    }
    imageStore(normal_out, p, vec4(n, traced_reflectivity(m.reflectivity, roughness)));
    imageStore(albedo_out, p, vec4(srgb_encode(base), roughness));
    imageStore(material_out, p, uvec4(a.material));
    imageStore(motion_out, p, vec4(motion, metallic));
}
#endif
