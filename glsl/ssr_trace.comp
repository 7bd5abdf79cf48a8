#version 460
// ssr.trace: screen-space reflections by perspective-correct DDA over the depth buffer
// (McGuire & Mara 2014, "Efficient GPU Screen-Space Ray Tracing", JCGT 3(4)). For each
// reflective pixel: the reflected ray is marched in screen space with a thickness
// test; a hit takes the lit colour there with a confidence that fades near the screen
// edges and for rays heading back to the camera. Writes SSR colour + confidence and
// the fail mask (reason bits, shader_defines.rs); nonzero sends the pixel to rt.trace.
#include "frame.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3) uniform usampler2D gb_material;
layout(binding = 4, rgba32f) uniform readonly image2D lit;
layout(binding = 5, rgba32f) uniform writeonly image2D ssr_out; // rgb colour, a confidence
layout(binding = 6, r32ui) uniform writeonly uimage2D fail_mask;

layout(push_constant) uniform Push {
    uint max_steps;
    float stride;         // pixels per step
    float thickness;      // view-space depth a surface is assumed to have
    float max_distance;   // view-space length of the ray
    float edge_fade;      // fraction of the screen's smaller side over which confidence fades
    float min_confidence; // below: the pixel fails
    float reflective_min; // reflectivity above which a pixel reflects
    uint force_fail;      // 1: SSR off, every reflective pixel fails (rt mode)
    float recursion_min;  // hits on surfaces more reflective than this fail
} pc;

// View-space z (negative in front of the camera) of G-buffer depth d.
float view_z(float d) {
    return -frame.proj[3][2] / (d + frame.proj[2][2]);
}

// Pixel coordinates of a clip-space point.
vec2 to_pixel(vec4 h) {
    return (h.xy / h.w * 0.5 + 0.5) * vec2(frame.resolution);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    if (any(greaterThanEqual(p, res))) {
        return;
    }
    uint material = texelFetch(gb_material, p, 0).r;
    vec4 nr = texelFetch(gb_normal, p, 0);
    if (material == MATERIAL_NONE || nr.w <= pc.reflective_min) {
        imageStore(ssr_out, p, vec4(0.0));
        imageStore(fail_mask, p, uvec4(0u));
        return;
    }
    if (pc.force_fail != 0u) {
        imageStore(ssr_out, p, vec4(0.0));
        imageStore(fail_mask, p, uvec4(FAIL_FORCED));
        return;
    }
    float depth = texelFetch(gb_depth, p, 0).r;
    vec3 w = world_from_depth(p, depth);
    vec3 n_world = normalize(nr.xyz);
    vec3 vpos = (frame.view * vec4(w, 1.0)).xyz;
    vec3 vn = normalize(mat3(frame.view) * n_world);
    vec3 vdir = normalize(reflect(normalize(vpos), vn));
    // Start a little off the surface so the first steps do not hit the pixel itself.
    vec3 origin = vpos + vn * (1e-3 * abs(vpos.z));

    float near_z = -frame.proj[3][2] / frame.proj[2][2];
    float ray_len = (origin.z + vdir.z * pc.max_distance) > near_z ? (near_z - origin.z) / vdir.z : pc.max_distance;
    vec3 end_point = origin + vdir * ray_len;
    vec4 h0 = frame.proj * vec4(origin, 1.0);
    vec4 h1 = frame.proj * vec4(end_point, 1.0);
    float k0 = 1.0 / h0.w, k1 = 1.0 / h1.w;
    vec3 q0 = origin * k0, q1 = end_point * k1;
    vec2 p0 = to_pixel(h0), p1 = to_pixel(h1);
    // A degenerate (one-pixel) line still advances.
    p1 += vec2(dot(p1 - p0, p1 - p0) < 1e-4 ? 0.01 : 0.0);
    vec2 delta = p1 - p0;
    bool permute = abs(delta.x) < abs(delta.y);
    if (permute) {
        delta = delta.yx;
        p0 = p0.yx;
        p1 = p1.yx;
    }
    float step_dir = sign(delta.x);
    float invdx = step_dir / delta.x;
    vec3 dq = (q1 - q0) * invdx * pc.stride;
    float dk = (k1 - k0) * invdx * pc.stride;
    vec2 dp = vec2(step_dir, delta.y * invdx) * pc.stride;
    // Start one step out: the first step samples a neighbour, not this pixel.
    vec2 pp = p0 + dp;
    vec3 q = q0 + dq;
    float k = k0 + dk;
    float end = p1.x * step_dir;
    float prev_z = origin.z;
    bool went_behind = false;
    bool hit = false;
    uint steps = 0u;
    ivec2 hit_pixel = ivec2(-1);
    for (; pp.x * step_dir <= end && steps < pc.max_steps; ++steps) {
        vec2 px = permute ? pp.yx : pp;
        ivec2 ip = ivec2(floor(px));
        if (any(lessThan(ip, ivec2(0))) || any(greaterThanEqual(ip, res))) {
            break; // left the screen
        }
        float ray_z_min = prev_z;
        float ray_z_max = (dq.z * 0.5 + q.z) / (dk * 0.5 + k);
        prev_z = ray_z_max;
        if (ray_z_min > ray_z_max) {
            float t = ray_z_min;
            ray_z_min = ray_z_max;
            ray_z_max = t;
        }
        float scene_depth = texelFetch(gb_depth, ip, 0).r;
        if (scene_depth < 1.0) { // depth 1 is the cleared value: sky, nothing to hit
            float scene_z_max = view_z(scene_depth);
            float scene_z_min = scene_z_max - pc.thickness;
            if (ray_z_max >= scene_z_min && ray_z_min <= scene_z_max) {
                hit = true;
                hit_pixel = ip;
                break;
            }
            if (ray_z_max < scene_z_min) {
                went_behind = true;
            }
        }
        pp += dp;
        q.z += dq.z;
        k += dk;
    }
    // With strides of several pixels the hit is somewhere in the last step: binary
    // search it (McGuire & Mara, section 3) for the first sample at or behind the
    // surface. Everything interpolates linearly in screen space, so midpoints do too.
    if (hit && pc.stride > 1.0) {
        vec2 a_p = pp - dp, b_p = pp;
        float a_qz = q.z - dq.z, b_qz = q.z;
        float a_k = k - dk, b_k = k;
        for (int r = 0; r < SSR_REFINE_STEPS; ++r) {
            vec2 m_p = 0.5 * (a_p + b_p);
            float m_qz = 0.5 * (a_qz + b_qz);
            float m_k = 0.5 * (a_k + b_k);
            ivec2 m_ip = clamp(ivec2(floor(permute ? m_p.yx : m_p)), ivec2(0), res - 1);
            float d = texelFetch(gb_depth, m_ip, 0).r;
            if (d < 1.0 && m_qz / m_k <= view_z(d)) {
                b_p = m_p;
                b_qz = m_qz;
                b_k = m_k;
            } else {
                a_p = m_p;
                a_qz = m_qz;
                a_k = m_k;
            }
        }
        hit_pixel = clamp(ivec2(floor(permute ? b_p.yx : b_p)), ivec2(0), res - 1);
    }

    uint fail = 0u;
    float confidence = 0.0;
    vec3 color = vec3(0.0);
    if (!hit) {
        bool left = steps < pc.max_steps;
        fail = went_behind ? FAIL_BEHIND : (left ? FAIL_LEFT_SCREEN : FAIL_OUT_OF_STEPS);
    } else {
        vec3 hit_n = normalize(texelFetch(gb_normal, hit_pixel, 0).xyz);
        vec3 world_dir = normalize((inverse(frame.view) * vec4(vdir, 0.0)).xyz);
        if (dot(hit_n, world_dir) > 0.0) {
            fail = FAIL_BACK_FACE;
        } else if (texelFetch(gb_normal, hit_pixel, 0).w > pc.recursion_min) {
            fail = FAIL_HIT_REFLECTIVE;
        } else {
            vec2 hp = vec2(hit_pixel) + 0.5;
            float edge = min(min(hp.x, float(res.x) - hp.x), min(hp.y, float(res.y) - hp.y));
            float fade_px = max(pc.edge_fade * float(min(res.x, res.y)), 1.0);
            confidence = clamp(edge / fade_px, 0.0, 1.0) * clamp(1.0 - vdir.z, 0.0, 1.0);
            if (confidence < pc.min_confidence) {
                fail = FAIL_LOW_CONFIDENCE;
            } else {
                color = imageLoad(lit, hit_pixel).rgb;
            }
        }
    }
    imageStore(ssr_out, p, vec4(color, fail == 0u ? confidence : 0.0));
    imageStore(fail_mask, p, uvec4(fail));
}
