#version 460
// reflect.denoise, step 2: temporal accumulation of glossy reflections after the
// spatial filter. Each glossy pixel's surface point is reprojected into the previous
// frame (where the G-buffer's motion says it was, seen by that frame's camera); the
// history there is kept only where the previous frame saw a glossy surface at the
// distance from its camera that this point had (within TEMPORAL_DISOCCLUSION of it:
// else disoccluded, history dropped), is clamped to the mean +- TEMPORAL_GAMMA standard deviations of the
// spatially filtered 3x3 neighbourhood (so a reflection that changed does not ghost),
// and is blended with this frame's value as a running mean of at most pc.max_frames
// frames. The result goes into the merged reflection, which compose reads. It runs
// over ssr.classify's list of glossy pixels; the history of a pixel is stamped with
// the frame that wrote it, so one that was not glossy last frame has none.
// Mirrored by cpu_ref::denoise::temporal (tests/suite/glossy.rs).
#include "glossy.glsl"
#include "pixel_list.glsl"
layout(local_size_x = SSR_LIST_WG) in;
layout(binding = 1, rgba32f) uniform readonly image2D current; // spatially filtered; a: source
layout(binding = 2) uniform sampler2D gb_depth;
layout(binding = 3) uniform sampler2D gb_normal;
layout(binding = 4) uniform sampler2D gb_albedo;
layout(binding = 5, rgba32f) uniform readonly image2D history_in;  // rgb; a: source
// r: distance, g: frames, b: the frame that wrote it (its index mod 2^24)
layout(binding = 6, rgba32f) uniform readonly image2D meta_in;
layout(binding = 7, rgba32f) uniform writeonly image2D history_out;
layout(binding = 8, rgba32f) uniform writeonly image2D meta_out;
layout(binding = 9, rgba32f) uniform writeonly image2D merged; // the glossy pixels' final reflection
layout(binding = 10, std430) readonly buffer GlossyList { uint glossy_list[]; };
layout(binding = 11, std430) readonly buffer GlossyArgs { uvec4 glossy_args; }; // w: length
layout(binding = 12) uniform sampler2D gb_motion; // xyz: the point last frame minus now
layout(push_constant) uniform Push {
    mat4 prev_view_proj;
    vec4 prev_camera;     // xyz: the previous frame's camera; w: 1 when the history is valid
    float reflective_min;
    uint max_frames;      // the running mean's longest window
} pc;

const float TEMPORAL_DISOCCLUSION = 0.01;
const float TEMPORAL_GAMMA = 2.0;

// As reflect_denoise.comp's: by the traced reflectivity (0 on the sky) and roughness.
bool glossy_at(ivec2 q) {
    return texelFetch(gb_normal, q, 0).w > pc.reflective_min && is_glossy(texelFetch(gb_albedo, q, 0).a);
}

// A frame's stamp: its index mod 2^24, exact in f32.
float stamp(uint index) {
    return float(index & 0xffffffu);
}

void main() {
    uint entry = list_entry(glossy_args.w, SSR_LIST_WG);
    if (entry >= glossy_args.w) {
        return;
    }
    ivec2 p = unpack_pixel(glossy_list[entry]);
    ivec2 res = ivec2(frame.resolution);
    vec4 c = imageLoad(current, p);
    vec3 x = world_from_depth(p, texelFetch(gb_depth, p, 0).r);
    float dist = length(x - frame.camera_pos.xyz);
    vec3 out_c = c.rgb;
    float frames = 1.0;
    if (pc.prev_camera.w > 0.0) {
        // The glossy neighbours' mean and deviation (the pixel is one of them).
        vec3 m1 = vec3(0.0), m2 = vec3(0.0);
        float count = 0.0;
        for (int j = -1; j <= 1; ++j) {
            for (int i = -1; i <= 1; ++i) {
                ivec2 q = p + ivec2(i, j);
                if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res)) && glossy_at(q)) {
                    vec3 v = imageLoad(current, q).rgb;
                    m1 += v;
                    m2 += v * v;
                    count += 1.0;
                }
            }
        }
        m1 /= count;
        vec3 sigma = sqrt(max(m2 / count - m1 * m1, vec3(0.0)));
        vec3 was = x + texelFetch(gb_motion, p, 0).xyz;
        vec4 h = pc.prev_view_proj * vec4(was, 1.0);
        vec2 uv = h.xy / h.w * 0.5 + 0.5;
        ivec2 q = ivec2(floor(uv * vec2(res)));
        if (h.w > 0.0 && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, res))) {
            vec4 meta = imageLoad(meta_in, q);
            float expected = length(was - pc.prev_camera.xyz);
            bool fresh = meta.b == stamp(frame.frame_index - 1u);
            if (fresh && abs(meta.r - expected) < TEMPORAL_DISOCCLUSION * expected) {
                vec3 hist = clamp(imageLoad(history_in, q).rgb, m1 - TEMPORAL_GAMMA * sigma, m1 + TEMPORAL_GAMMA * sigma);
                frames = min(meta.g + 1.0, float(pc.max_frames));
                out_c = mix(hist, c.rgb, 1.0 / frames);
            }
        }
    }
    imageStore(history_out, p, vec4(out_c, c.a));
    imageStore(meta_out, p, vec4(dist, frames, stamp(frame.frame_index), 0.0));
    imageStore(merged, p, vec4(out_c, c.a));
}
