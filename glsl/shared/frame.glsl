// The per-frame uniform block at binding 0 and helpers that only need it.
#ifndef FRAME_GLSL
#define FRAME_GLSL
#include "types.glsl"

layout(binding = 0) uniform FrameUniforms { FRAME_UNIFORMS_BLOCK } frame;

// Sky radiance seen along unit direction `d`: zenith-to-horizon gradient above the
// horizon, a darker ground colour below. Mirrored by cpu_ref::shading::sky.
vec3 sky_radiance(vec3 d) {
    float up = clamp(d.y, -1.0, 1.0);
    if (up >= 0.0) {
        return mix(frame.sky_horizon.rgb, frame.sky_zenith.rgb, sqrt(up));
    }
    return frame.sky_horizon.rgb * mix(0.6, 0.25, min(-up * 4.0, 1.0));
}

// World position of pixel `p` (integer coordinates) at G-buffer depth `depth`.
vec3 world_from_depth(ivec2 p, float depth) {
    vec2 ndc = (vec2(p) + 0.5) / vec2(frame.resolution) * 2.0 - 1.0;
    vec4 w = frame.inv_view_proj * vec4(ndc, depth, 1.0);
    return w.xyz / w.w;
}

// How far a ray's origin is pushed off its surface (along a normal) at `pos`: it grows
// with the distance from the camera, as depth-buffer and float error do. Mirrored by
// cpu_ref::reflect::offset_scale.
float offset_scale(vec3 pos) {
    return 2e-4 * max(1.0, length(pos - frame.camera_pos.xyz));
}

// The angle one pixel subtends at the camera (vertical; square pixels). Mirrored by
// cpu_ref::shading::pixel_spread.
float pixel_spread() {
    return 2.0 / (abs(frame.proj[1][1]) * float(frame.resolution.y));
}

// The sRGB transfer function and its inverse (IEC 61966-2-1), for the G-buffer's base
// colour (gbuffer::ALBEDO_FORMAT). Mirrored by scene::texture::{srgb_to_linear, linear_to_srgb}.
vec3 srgb_encode(vec3 c) {
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

vec3 srgb_decode(vec3 e) {
    return mix(e / 12.92, pow((e + 0.055) / 1.055, vec3(2.4)), greaterThan(e, vec3(0.04045)));
}

// Tiles of WG_2D x WG_2D pixels covering the frame (the grid of every 2D kernel's
// workgroups); tile (x, y) has index y * tile_grid().x + x.
ivec2 tile_grid() {
    return (ivec2(frame.resolution) + int(WG_2D) - 1) / int(WG_2D);
}
#endif
