#version 460
// gbuffer: writes normal + reflectivity, base colour + roughness, material id, motion +
// metallic.
#include "frame.glsl"
#include "surface.glsl"
#include "glossy.glsl"

layout(binding = 2, std430) readonly buffer Materials { Material materials[]; };
layout(binding = 4) uniform sampler2DArray scene_textures;
// The same texels as UNORM: data textures (roughness, metallic) with no sRGB decode.
layout(binding = 6) uniform sampler2DArray data_textures;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) flat in uint in_material;
layout(location = 3) in vec2 in_uv;
layout(location = 4) in vec3 in_motion;

// xyz: unit world normal facing the camera, its mirror direction above the facet; w: the
// reflectivity the reflection passes trace (glossy.glsl: 0 past the rough cut-off)
layout(location = 0) out vec4 out_normal;
layout(location = 1) out vec4 out_albedo;   // rgb: base colour (textured), sRGB-encoded; a: roughness
layout(location = 2) out uint out_material; // material index (MATERIAL_NONE where empty)
// xyz: the surface point's world position the frame before minus this frame's;
// w: metallic (per texel)
layout(location = 3) out vec4 out_motion;

void main() {
    // The triangle's own plane (from the position's screen derivatives), facing the viewer.
    vec3 g = cross(dFdx(in_world), dFdy(in_world));
    vec3 v = normalize(frame.camera_pos.xyz - in_world);
    g = dot(g, v) < 0.0 ? -normalize(g) : normalize(g);
    Material m = materials[in_material];
    vec3 n = normalize(in_normal);
    // Culling is off (scenes mix windings): make the normal face the viewer.
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    // A mirror direction below the facet would leave through the surface.
    if (!any(isnan(g)) && !any(isinf(g))) { // a triangle seen edge-on has no plane here
        n = clamp_bent_normal(n, g, v);
    }
    float roughness = m.roughness, metallic = m.metallic;
    if (m.roughness_layer != TEXTURE_NONE) { // glTF's layout: green roughness, blue metallic
        vec4 t = texture(data_textures, vec3(in_uv, float(m.roughness_layer)));
        roughness *= t.g;
        metallic *= t.b;
    }
    out_normal = vec4(n, traced_reflectivity(m.reflectivity, roughness));
    out_albedo = vec4(srgb_encode(base_color(m, scene_textures, in_uv)), roughness);
    out_material = in_material;
    out_motion = vec4(in_motion, metallic);
}
