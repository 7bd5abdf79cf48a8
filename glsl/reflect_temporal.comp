#version 460
// reflect.denoise, step 2: temporal accumulation of glossy reflections after the
// spatial filter. Each glossy pixel's surface point is reprojected into the previous
// frame (its camera; the scene is assumed still there); the history there is kept
// only where the previous frame saw a glossy surface at the distance from its camera
// that this point has (within TEMPORAL_DISOCCLUSION of it: else disoccluded, history
// dropped), is clamped to the mean +- TEMPORAL_GAMMA standard deviations of the
// spatially filtered 3x3 neighbourhood (so a reflection that changed does not ghost),
// and is blended with this frame's value as a running mean of at most pc.max_frames
// frames. Mirror and other pixels pass through and reset their history.
// Mirrored by cpu_ref::denoise::temporal (tests/suite/glossy.rs).
#include "glossy.glsl"
layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(binding = 1, rgba32f) uniform readonly image2D current; // spatially filtered; a: source
layout(binding = 2) uniform sampler2D gb_depth;
layout(binding = 3) uniform sampler2D gb_normal;
layout(binding = 4) uniform sampler2D gb_albedo;
layout(binding = 5) uniform usampler2D gb_material;
layout(binding = 6, rgba32f) uniform readonly image2D history_in;  // rgb; a: source
layout(binding = 7, rgba32f) uniform readonly image2D meta_in;     // r: distance (-1: none), g: frames
layout(binding = 8, rgba32f) uniform writeonly image2D history_out;
layout(binding = 9, rgba32f) uniform writeonly image2D meta_out;
layout(push_constant) uniform Push {
    mat4 prev_view_proj;
    vec4 prev_camera;     // xyz: the previous frame's camera; w: 1 when the history is valid
    float reflective_min;
    uint max_frames;      // the running mean's longest window
} pc;

const float TEMPORAL_DISOCCLUSION = 0.01;
const float TEMPORAL_GAMMA = 2.0;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (any(greaterThanEqual(p, res))) {
        return;
    }
    vec4 c = imageLoad(current, p);
    uint m = texelFetch(gb_material, p, 0).r;
    vec4 nr = texelFetch(gb_normal, p, 0);
    bool glossy = m != MATERIAL_NONE && nr.w > pc.reflective_min && is_glossy(texelFetch(gb_albedo, p, 0).a);
    vec3 x = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    float dist = length(x - frame.camera_pos.xyz);
    vec3 out_c = c.rgb;
    float frames = 1.0;
    if (glossy && pc.prev_camera.w > 0.0) {
        vec3 m1 = vec3(0.0), m2 = vec3(0.0);
        for (int j = -1; j <= 1; ++j) {
            for (int i = -1; i <= 1; ++i) {
                vec3 v = imageLoad(current, clamp(p + ivec2(i, j), ivec2(0), res - 1)).rgb;
                m1 += v;
                m2 += v * v;
            }
        }
        m1 /= 9.0;
        vec3 sigma = sqrt(max(m2 / 9.0 - m1 * m1, vec3(0.0)));
        vec4 h = pc.prev_view_proj * vec4(x, 1.0);
        vec2 uv = h.xy / h.w * 0.5 + 0.5;
        ivec2 q = ivec2(floor(uv * vec2(res)));
        if (h.w > 0.0 && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res))) {
            vec4 meta = imageLoad(meta_in, q);
            float expected = length(x - pc.prev_camera.xyz);
            if (meta.g >= 1.0 && abs(meta.r - expected) < TEMPORAL_DISOCCLUSION * expected) {
                vec3 hist = clamp(imageLoad(history_in, q).rgb, m1 - TEMPORAL_GAMMA * sigma, m1 + TEMPORAL_GAMMA * sigma);
                frames = min(meta.g + 1.0, float(pc.max_frames));
                out_c = mix(hist, c.rgb, 1.0 / frames);
            }
        }
    }
    imageStore(history_out, p, vec4(out_c, c.a));
    imageStore(meta_out, p, glossy ? vec4(dist, frames, 0.0, 0.0) : vec4(-1.0, 0.0, 0.0, 0.0));
}
