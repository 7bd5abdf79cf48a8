#version 460
// ssr.trace: screen-space reflections by perspective-correct DDA over the depth buffer
// (McGuire & Mara 2014, "Efficient GPU Screen-Space Ray Tracing", JCGT 3(4)), one
// invocation per pixel of ssr.classify's march list (indirect dispatch). The reflected
// ray is marched in screen space with a thickness test; a hit takes the lit colour
// there with a confidence that fades near the screen edges and for rays heading back
// to the camera. Writes SSR colour + confidence and the fail mask (reason bits,
// shader_defines.rs) of the listed pixels; nonzero sends the pixel to rt.trace
// (FAIL_BLEND: a faded hit, kept and blended with the ray-traced colour by merge).
// CPU reference: cpu_ref::ssr::march (tests/ssr.rs).
#include "ssr.glsl"
#include "shading.glsl"
#include "pixel_list.glsl"

layout(local_size_x = SSR_LIST_WG) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3, rgba32f) uniform readonly image2D lit;
layout(binding = 4, rgba32f) uniform writeonly image2D ssr_out; // rgb colour, a confidence
layout(binding = 5, r32ui) uniform writeonly uimage2D fail_mask;
layout(binding = 6, std430) readonly buffer MarchList { uint march_list[]; };
layout(binding = 7, std430) readonly buffer MarchArgs { uvec4 march_args; }; // w: length
layout(binding = 8) uniform sampler2D gb_albedo; // rgb: base colour, sRGB-encoded
layout(binding = 9) uniform usampler2D gb_material;
layout(binding = 10, std430) readonly buffer Materials { Material materials[]; };

layout(push_constant) uniform Push {
    uint max_steps;
    float stride;         // pixels per step
    float thickness;      // depth a surface is assumed to have, as a fraction of its view depth
    float max_distance;   // length of the ray, in multiples of the reflecting point's view depth
    float edge_fade;      // fraction of the screen's smaller side over which confidence fades
    float min_confidence; // below: the pixel fails
    float recursion_min;  // hits whose own reflection, seen along the ray, weighs more fail
} pc;

// View-space z (negative in front of the camera) of G-buffer depth d.
float view_z(float d) {
    return -frame.proj[3][2] / (d + frame.proj[2][2]);
}

// Pixel coordinates of a clip-space point.
vec2 to_pixel(vec4 h) {
    return (h.xy / h.w * 0.5 + 0.5) * vec2(frame.resolution);
}

// The lit colour at sub-pixel position `x` (pixels; texel centres at +0.5), bilinear.
vec3 lit_bilinear(vec2 x, ivec2 res) {
    vec2 t = x - 0.5;
    ivec2 i0 = ivec2(floor(t));
    vec2 f = t - vec2(i0);
    ivec2 lo = clamp(i0, ivec2(0), res - 1), hi = clamp(i0 + 1, ivec2(0), res - 1);
    vec3 c00 = imageLoad(lit, lo).rgb, c10 = imageLoad(lit, ivec2(hi.x, lo.y)).rgb;
    vec3 c01 = imageLoad(lit, ivec2(lo.x, hi.y)).rgb, c11 = imageLoad(lit, hi).rgb;
    return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

// How much of the surface at pixel q is its own mirror reflection, seen from the ray
// arriving along -v: reflectivity x Fresnel (shading.glsl), the largest channel. SSR
// takes the lit colour there, which lacks that reflection.
float hit_reflection_weight(ivec2 q, float reflectivity, vec3 n, vec3 v) {
    uint id = texelFetch(gb_material, q, 0).r;
    float metallic = id == MATERIAL_NONE ? 0.0 : materials[id].metallic;
    vec3 base = srgb_decode(texelFetch(gb_albedo, q, 0).rgb);
    vec3 w = reflection_weight(base, metallic, reflectivity, n, v);
    return max(w.r, max(w.g, w.b));
}

void main() {
    uint i = list_entry(march_args.w, SSR_LIST_WG);
    if (i >= march_args.w) {
        return;
    }
    ivec2 p = unpack_pixel(march_list[i]);
    ivec2 res = ivec2(frame.resolution);
    SsrRay ray = ssr_ray(p, texelFetch(gb_depth, p, 0).r, texelFetch(gb_normal, p, 0).xyz);
    vec3 vpos = ray.vpos, vn = ray.vn, vdir = ray.vdir;
    // Start a little off the surface so the first steps do not hit the pixel itself.
    vec3 origin = vpos + vn * (1e-3 * abs(vpos.z));

    float near_z = -frame.proj[3][2] / frame.proj[2][2];
    // Lengths relative to the view depth keep SSR's answers the same at any scene scale.
    float max_len = pc.max_distance * abs(origin.z);
    float ray_len = (origin.z + vdir.z * max_len) > near_z ? (near_z - origin.z) / vdir.z : max_len;
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
    // Sample k covers the ray between the half steps on either side of it, so the
    // first interval starts half a stride out: starting at the origin would let a ray
    // leaving a surface that nears the camera overlap that surface itself.
    float prev_z = (q0.z + 0.5 * dq.z) / (k0 + 0.5 * dk);
    bool went_behind = false;
    bool hit = false;
    uint steps = 0u;
    ivec2 hit_pixel = ivec2(-1);
    vec2 hit_pos = vec2(-1.0); // sub-pixel hit position in pixels
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
            float scene_z_min = scene_z_max - pc.thickness * abs(scene_z_max);
            if (ray_z_max >= scene_z_min && ray_z_min <= scene_z_max) {
                hit = true;
                hit_pixel = ip;
                hit_pos = px;
                break;
            }
            if (ray_z_max < scene_z_min) {
                // Behind a surface thicker than the threshold: the ray may hit that
                // object's hidden side, which the screen does not hold. Any hit found
                // beyond would be a guess (a reflection seen through the object).
                went_behind = true;
                break;
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
        // The surface is crossed between a (in front) and b (behind): place the hit by
        // the secant of the ray-to-surface distance, to a fraction of a pixel, so that a
        // magnified reflection interpolates instead of repeating whole texels.
        vec2 pa = permute ? a_p.yx : a_p, pb = permute ? b_p.yx : b_p;
        float za = texelFetch(gb_depth, clamp(ivec2(floor(pa)), ivec2(0), res - 1), 0).r;
        float zb = texelFetch(gb_depth, clamp(ivec2(floor(pb)), ivec2(0), res - 1), 0).r;
        float gap_a = a_qz / a_k - view_z(za); // > 0: in front
        float gap_b = b_qz / b_k - view_z(zb); // <= 0: at or behind
        float f = za < 1.0 && gap_a > 0.0 ? clamp(gap_a / (gap_a - gap_b), 0.0, 1.0) : 1.0;
        hit_pos = mix(pa, pb, f);
        hit_pixel = clamp(ivec2(floor(hit_pos)), ivec2(0), res - 1);
    }

    uint fail = 0u;
    float confidence = 0.0;
    vec3 color = vec3(0.0);
    if (!hit) {
        bool left = steps < pc.max_steps;
        fail = went_behind ? FAIL_BEHIND : (left ? FAIL_LEFT_SCREEN : FAIL_OUT_OF_STEPS);
    } else {
        vec4 hit_nr = texelFetch(gb_normal, hit_pixel, 0); // xyz normal, w reflectivity
        vec3 hit_n = normalize(hit_nr.xyz);
        vec3 world_dir = transpose(mat3(frame.view)) * vdir; // view is rigid
        if (dot(hit_n, world_dir) > 0.0) {
            fail = FAIL_BACK_FACE;
        } else if (hit_reflection_weight(hit_pixel, hit_nr.w, hit_n, -world_dir) > pc.recursion_min) {
            fail = FAIL_HIT_REFLECTIVE;
        } else {
            vec2 hp = vec2(hit_pixel) + 0.5;
            float edge = min(min(hp.x, float(res.x) - hp.x), min(hp.y, float(res.y) - hp.y));
            float fade_px = max(pc.edge_fade * float(min(res.x, res.y)), 1.0);
            confidence = clamp(edge / fade_px, 0.0, 1.0) * heading_confidence(vdir);
            if (confidence < pc.min_confidence) {
                fail = FAIL_LOW_CONFIDENCE;
            } else {
                color = lit_bilinear(hit_pos, res);
                // A faded hit is kept, but traced too: merge blends the two by confidence.
                fail = confidence < 1.0 ? FAIL_BLEND : 0u;
            }
        }
    }
    bool kept = fail == 0u || fail == FAIL_BLEND;
    imageStore(ssr_out, p, vec4(color, kept ? confidence : 0.0));
    imageStore(fail_mask, p, uvec4(fail));
}
