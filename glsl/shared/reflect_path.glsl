// rt.reflect's path, shared by its two kernels: rt_reflect.comp (Speculum's BVHs,
// traverse.glsl) and rt_reflect.rgen (the vendor tracer, trace_khr.glsl). The includer
// includes its tracer first; both define trace_ray and hit_vertex alike, so the two
// shade every hit identically. See rt_reflect.comp for what the path does.
// CPU reference: cpu_ref::reflect::reflected_radiance (tests/rt_reflect.rs).
#ifndef REFLECT_PATH_GLSL
#define REFLECT_PATH_GLSL
#include "glossy.glsl"
#include "surface.glsl"
#include "pixel_list.glsl"
#include "hit_uv.glsl"
layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3, std430) readonly buffer Materials { Material materials[]; };
layout(binding = 4) uniform sampler2D shadow_map;
layout(binding = 5, std430) readonly buffer Pixels { uint pixels[]; };
layout(binding = 6, std430) readonly buffer Indirect { uvec4 indirect; }; // w: count
layout(binding = 7, rgba32f) uniform writeonly image2D rt_out;
// Bindings 8-15: the tracer's; 16-17: hit_uv.glsl's texture coordinates.
layout(binding = 18) uniform sampler2DArray scene_textures;
layout(binding = 19) uniform sampler2D gb_albedo; // a: perceptual roughness
// The mean distance to the first hits of the pixel's rays (HIT_FAR for a miss), for
// reflect.denoise's footprint.
layout(binding = 20, r32f) uniform writeonly image2D hit_distance;

layout(push_constant) uniform Push {
    uint max_bounces;  // rays per path (1: a single reflection)
    uint static_tris;
    uint dynamic_tris;
    uint shadows;      // SHADOWS_*: how hits are shadowed
} pc;

// The radiance along one path from `origin` (just off the reflecting surface) in
// direction `dir`, its ray cone `cone` wide at the origin and spreading by `spread`;
// `first` receives the distance to its first hit (HIT_FAR for a miss).
vec3 trace_path(vec3 origin, vec3 dir, float cone, float spread, out float first) {
    first = HIT_FAR;
    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    for (uint bounce = 0u; bounce < pc.max_bounces; ++bounce) {
        Hit h = trace_ray(origin, dir, 0.0, 3.0e38, pc.static_tris, pc.dynamic_tris, false);
        if (h.prim == BVH_INVALID) {
            radiance += throughput * sky_radiance(dir);
            break;
        }
        if (bounce == 0u) {
            first = h.t;
        }
        Vertex a = hit_vertex(h.prim, 0u);
        Vertex b = hit_vertex(h.prim, 1u);
        Vertex c = hit_vertex(h.prim, 2u);
        Material m = materials[a.material];
        // The facet's plane facing the ray.
        vec3 g = normalize(cross(b.position - a.position, c.position - a.position));
        g = dot(g, dir) > 0.0 ? -g : g;
        vec3 albedo = m.albedo;
        cone += spread * h.t;
        if (m.texture_layer != TEXTURE_NONE) {
            vec2 ta = hit_uv(h.prim, 0u), tb = hit_uv(h.prim, 1u), tc = hit_uv(h.prim, 2u);
            vec2 uv = (1.0 - h.u - h.v) * ta + h.u * tb + h.v * tc;
            float texels = float(textureSize(scene_textures, 0).x);
            float lod = ray_cone_lod(cone, abs(dot(g, dir)), a.position, b.position, c.position, ta, tb, tc, texels);
            albedo = base_color_lod(m, scene_textures, uv, lod);
        }
        vec3 hn = normalize((1.0 - h.u - h.v) * a.normal + h.u * b.normal + h.v * c.normal);
        if (dot(hn, dir) > 0.0) {
            hn = -hn; // double-sided: face the incoming ray
        }
        // The next mirror direction stays above the facet.
        hn = clamp_bent_normal(hn, g, -dir);
        vec3 hp = origin + dir * h.t;
        // Shadows as on the visible surface: the map, or a ray where shadow_ray_reasons
        // asks for one (always under `rays`; where the map is unsure under `hybrid`).
        float vis;
        if (pc.shadows == SHADOWS_MAP) {
            vis = shadow_visibility(shadow_map, hp);
        } else if (shadow_ray_reasons(shadow_map, hp, dot(hn, frame.light_dir.xyz), pc.shadows, vis) != 0u) {
            vec3 so = hp + g * offset_scale(hp);
            Hit sh = trace_ray(so, frame.light_dir.xyz, 0.0, 3.0e38, pc.static_tris, pc.dynamic_tris, true);
            vis = sh.prim == BVH_INVALID ? 1.0 : 0.0;
        }
        // A hit past the rough cut-off reflects only the prefiltered sky (glossy.glsl);
        // a glossy one continues in its mirror direction (one ray per path: the
        // lobe's blur of a reflection within a reflection is left out).
        float reflectivity = traced_reflectivity(m.reflectivity, m.roughness);
        radiance += throughput * shade_direct(albedo, m.roughness, reflectivity, m.metallic, hn, -dir, vis);
        if (reflectivity <= 0.0) {
            break;
        }
        throughput *= reflection_weight(albedo, m.metallic, reflectivity, hn, -dir);
        dir = reflect(dir, hn);
        origin = hp + g * offset_scale(hp); // off the facet itself, whatever the normal
    }
    return radiance;
}

// The reflected radiance of list entry `i` (< the list's length), stored in rt_out: the
// mean of the pixel's rays (glossy.glsl: one for a mirror).
void reflect_entry(uint i) {
    ivec2 p = unpack_pixel(pixels[i]);
    float depth = texelFetch(gb_depth, p, 0).r;
    vec3 pos = world_from_depth(p, depth);
    vec3 n = normalize(texelFetch(gb_normal, p, 0).xyz);
    float roughness = texelFetch(gb_albedo, p, 0).a;
    vec3 view_dir = normalize(pos - frame.camera_pos.xyz);
    vec3 origin = pos + n * offset_scale(pos);
    float spread = pixel_spread();
    // The ray cone's width at `origin`, grown along the path.
    float cone = spread * length(pos - frame.camera_pos.xyz);
    vec3 radiance;
    float first;
    if (!is_glossy(roughness)) {
        radiance = trace_path(origin, reflect(view_dir, n), cone, spread, first);
    } else {
        uint rays = reflection_rays(roughness);
        radiance = vec3(0.0);
        float first_sum = 0.0;
        for (uint s = 0u; s < rays; ++s) {
            radiance += trace_path(origin, glossy_direction(p, n, -view_dir, roughness, s), cone, spread, first);
            first_sum += min(first, HIT_FAR);
        }
        radiance /= float(rays);
        first = first_sum / float(rays);
    }
    imageStore(rt_out, p, vec4(radiance, 1.0));
    imageStore(hit_distance, p, vec4(first));
}
#endif
