#version 460
// ssr.trace: screen-space reflections, one invocation per pixel of ssr.classify's march
// list (indirect dispatch). The reflected ray is marched in screen space, by default
// through ssr.hiz's min-depth pyramid (HIZ: the hierarchical march of FidelityFX SSSR,
// coarser while the ray crosses cells above their nearest surface, finer where it
// meets one), or by the perspective-correct linear DDA of McGuire & Mara 2014
// ("Efficient GPU Screen-Space Ray Tracing", JCGT 3(4)) with a stride. Either finds the
// first pixel where the ray reaches the depth surface; within the thickness it is a
// hit, which takes the lit colour there with a confidence that fades near the screen
// edges and for rays heading back to the camera. Writes SSR colour + confidence and the fail mask (reason bits,
// shader_defines.rs) of the listed pixels; nonzero sends the pixel to rt.trace
// (FAIL_BLEND: a faded hit, kept and blended with the ray-traced colour by merge).
// Counts each tile's marched pixels and those SSR answered (fail 0) into the adaptive
// hybrid's tile buffer (ssr_classify.comp), for the next frame's classification.
// CPU reference: cpu_ref::ssr::march (tests/ssr.rs).
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
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
layout(binding = 9) uniform sampler2D gb_motion; // w: metallic (0 on the sky)
// ssr.hiz's pyramid: level after level, row-major, level k ceil(resolution / 2^k).
layout(binding = 10, std430) readonly buffer Pyramid { float pyramid[]; };
// The mean distance (view space) from the pixel's surface to its rays' hits; HIT_FAR
// where SSR did not answer (rt.reflect writes the traced pixels').
layout(binding = 11, r32f) uniform writeonly image2D hit_distance;
// This frame's tile state and counts (TILE_WORDS a tile; ssr.classify zeroed the counts).
layout(binding = 12, std430) buffer Tiles { uint tiles[]; };
// Word 1: on a frame that only measures, the marched pixels outside rays-only tiles
// that SSR answered (ssr.classify zeroed it; word 0 is its count of SSR-first marches).
layout(binding = 13, std430) buffer SsrFirst { uint ssr_first_marches; uint ssr_first_answered; };

// true: the hierarchical march through the pyramid; false: the linear DDA.
layout(constant_id = 0) const bool HIZ = true;

layout(push_constant) uniform Push {
    uint max_steps;       // DDA steps, or Hi-Z cell visits
    float stride;         // pixels per DDA step
    float thickness;      // depth a surface is assumed to have, as a fraction of its view depth
    float max_distance;   // length of the ray, in multiples of the reflecting point's view depth
    float edge_fade;      // fraction of the screen's smaller side over which confidence fades
    float min_confidence; // below: the pixel fails
    float recursion_min;  // hits whose own reflection, as the pixel shows it, weighs more fail
    uint hiz_top;         // the pyramid's last (1x1) level
    float trace_min_weight; // failed pixels whose own reflection weighs less are not traced
    uint measure_only;      // 1: every marched pixel ends as a rays-only tile's probe
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

// The base colour (linear) and metallic of the surface at pixel q.
void surface_at(ivec2 q, out vec3 base, out float metallic) {
    metallic = texelFetch(gb_motion, q, 0).w;
    base = srgb_decode(texelFetch(gb_albedo, q, 0).rgb);
}

// How much of what the pixel shows is the hit surface's own mirror reflection (which
// the lit colour SSR takes lacks): the surface at pixel q's reflectivity x Fresnel
// (shading.glsl) seen from the ray arriving along -v, times the pixel's own reflection
// weight `own`, the largest channel. A second bounce the pixel barely shows (a glossy
// wall seen in a faint floor) costs nothing to leave out; one a mirror shows in full
// does.
float hit_reflection_weight(ivec2 q, float reflectivity, vec3 n, vec3 v, vec3 own) {
    vec3 base;
    float metallic;
    surface_at(q, base, metallic);
    vec3 w = own * reflection_weight(base, metallic, reflectivity, n, v);
    return max(w.r, max(w.g, w.b));
}

// Where a march ended: `reason` 0 with the pixel and sub-pixel position of a hit, or
// why it found none (FAIL_LEFT_SCREEN, FAIL_BEHIND, FAIL_OUT_OF_STEPS).
struct Found {
    uint reason;
    ivec2 hit_pixel;
    vec2 hit_pos;
};

// The perspective-correct DDA from clip-space h0 (the origin) to h1 (the ray's end),
// `stride` pixels a step, the hit refined inside its step by binary search.
Found march_linear(vec4 h0, vec4 h1, vec3 origin, vec3 end_point, ivec2 res) {
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
    Found found = Found(0u, ivec2(-1), vec2(-1.0));
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
                found.hit_pixel = ip;
                found.hit_pos = px;
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
    if (!hit) {
        bool left = steps < pc.max_steps;
        found.reason = went_behind ? FAIL_BEHIND : (left ? FAIL_LEFT_SCREEN : FAIL_OUT_OF_STEPS);
        return found;
    }
    // With strides of several pixels the hit is somewhere in the last step: binary
    // search it (McGuire & Mara, section 3) for the first sample at or behind the
    // surface. Everything interpolates linearly in screen space, so midpoints do too.
    if (pc.stride > 1.0) {
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
        found.hit_pos = mix(pa, pb, f);
        found.hit_pixel = clamp(ivec2(floor(found.hit_pos)), ivec2(0), res - 1);
    }
    return found;
}

// Past a cell's boundary a Hi-Z step lands this far (pixels) inside the next cell.
const float HIZ_NUDGE = 0.005;
// The ray parameter of a plane the ray runs parallel to: never the nearest.
const float NO_PLANE = 3.0e38;

// The pyramid's level k: ceil(resolution / 2^k) texels, as ssr.hiz halves rounding up.
uvec2 hiz_size(uint k, ivec2 res) {
    return (uvec2(res) + (1u << k) - 1u) >> k;
}

// The hierarchical march (FidelityFX SSSR's): the ray as a line in (pixel x, pixel y,
// depth), which a perspective projection keeps straight, walked cell by cell through
// the min-depth pyramid from level 0. In a cell whose nearest surface the ray stays in
// front of up to the cell's far side, the ray jumps to that side and the next step
// looks one level coarser; where it reaches that surface's depth inside the cell it
// stops there and looks one level finer; where it is already behind, finer too. At
// level 0 that is the first pixel the ray reaches the depth surface in (the surface
// taken as infinitely thick); the thickness then judges it hit or behind.
Found march_hiz(vec4 h0, vec4 h1, ivec2 res) {
    vec3 s0 = vec3(to_pixel(h0), h0.z / h0.w);
    vec3 s1 = vec3(to_pixel(h1), h1.z / h1.w);
    vec3 dir = s1 - s0;
    // Past the far plane (depth 1) the ray is behind every surface: it ends there.
    float t_end = s1.z > 1.0 ? (1.0 - s0.z) / dir.z : 1.0;
    vec3 inv = vec3(abs(dir.x) > 1e-20 ? 1.0 / dir.x : NO_PLANE, abs(dir.y) > 1e-20 ? 1.0 / dir.y : NO_PLANE,
                    abs(dir.z) > 1e-20 ? 1.0 / dir.z : NO_PLANE);
    // The side of a cell the ray leaves by, per axis (1: the high side), and the nudge
    // past it.
    vec2 side = vec2(dir.x >= 0.0 ? 1.0 : 0.0, dir.y >= 0.0 ? 1.0 : 0.0);
    vec2 nudge = vec2(dir.x >= 0.0 ? HIZ_NUDGE : -HIZ_NUDGE, dir.y >= 0.0 ? HIZ_NUDGE : -HIZ_NUDGE);
    // Out of the origin's own pixel first, which the ray would hit at once.
    vec2 t0 = (floor(s0.xy) + side + nudge - s0.xy) * inv.xy;
    float t = min(t0.x, t0.y);
    vec3 pos = s0 + dir * t;
    uint mip = 0u, offset = 0u;
    uvec2 size = uvec2(res);
    Found found = Found(FAIL_OUT_OF_STEPS, ivec2(-1), vec2(-1.0));
    // The loop body is kept short and free of divergent branches: a CPU driver
    // (lavapipe) runs every branch of a SIMD group whichever its lanes take, so the
    // level-0 judgement is made once, after the loop.
    bool reached = false; // the ray reached the surface of a level-0 cell
    bool entered_behind = false; // ... by entering it behind its surface (not crossing it)
    uvec2 cell = uvec2(0u);
    for (uint steps = 0u; steps < pc.max_steps; ++steps) {
        if (t > t_end || any(lessThan(pos.xy, vec2(0.0))) || any(greaterThanEqual(pos.xy, vec2(res)))) {
            found.reason = FAIL_LEFT_SCREEN; // off the screen, or the ray's end
            break;
        }
        cell = uvec2(pos.xy) >> mip; // pos >= 0: truncation is floor
        float surface = pyramid[offset + cell.y * size.x + cell.x];
        vec2 planes = (vec2(cell) + side) * float(1u << mip) + nudge;
        vec2 txy = (planes - s0.xy) * inv.xy;
        // Sky (depth 1) has no surface to reach; nor does a ray whose depth falls.
        float tz = surface < 1.0 && dir.z > 0.0 ? (surface - s0.z) * inv.z : NO_PLANE;
        float t_min = min(min(txy.x, txy.y), tz);
        bool above = pos.z < surface;
        t = above ? t_min : t;
        pos = s0 + dir * t;
        // Crossed the cell in front of its nearest surface: coarser (up to the top);
        // reached that surface, or behind it: finer, and at level 0 the march ends.
        bool coarser = above && t_min != tz;
        reached = !coarser && mip == 0u;
        entered_behind = !above;
        if (reached) {
            break;
        }
        uint next = coarser ? min(mip + 1u, pc.hiz_top) : mip - 1u;
        uvec2 next_size = hiz_size(next, res);
        offset = next > mip ? offset + size.x * size.y : (next < mip ? offset - next_size.x * next_size.y : offset);
        mip = next;
        size = next_size;
    }
    if (reached) { // level 0: this pixel's surface
        ivec2 p = ivec2(cell);
        float depth = pyramid[p.y * res.x + p.x];
        float scene_z = view_z(depth);
        float ray_z = view_z(pos.z);
        float thickness = pc.thickness * abs(scene_z);
        if (entered_behind) {
            // Entered from the side, behind the pixel's surface: a real hit only where
            // the ray would have reached it within about a pixel (a surface sloped
            // across the pixel). More is a silhouette the ray passes behind, or hits
            // on a side the screen does not show: taking the silhouette's colour there
            // streaks it along the ray (the curtains of thick SSR).
            float t_px = 1.0 / max(abs(dir.x), abs(dir.y));
            thickness = min(thickness, 2.0 * abs(view_z(s0.z + dir.z * (t + t_px)) - ray_z));
        }
        if (depth >= 1.0) {
            found.reason = FAIL_LEFT_SCREEN; // the far plane, over the sky
        } else if (ray_z < scene_z - thickness) {
            found.reason = FAIL_BEHIND; // see march_linear
        } else {
            found = Found(0u, p, pos.xy);
        }
    }
    return found;
}

// The hit's fail mask, colour and confidence: back faces, surfaces whose own
// reflection the screen lacks and faded hits fail; a faded hit above the threshold is
// kept and traced too (FAIL_BLEND: merge blends the two by confidence).
// How far (pixels) from the hit position the ray may cross the plane of the hit
// pixel's surface: a true hit crosses it in that pixel, give or take a sloped or
// curved surface's departure from its tangent plane across a pixel or two.
const float SSR_PLANE_PX = 1.0;

// Where (pixels) a ray from `origin` along `vdir` (view space) crosses the plane of the
// surface at hit pixel q (its depth, its normal n), or far off the screen when it runs
// along that plane.
vec2 plane_crossing(vec3 origin, vec3 vdir, ivec2 q, vec3 n) {
    vec3 hv = (frame.view * vec4(world_from_depth(q, texelFetch(gb_depth, q, 0).r), 1.0)).xyz;
    vec3 vn = mat3(frame.view) * n; // view is rigid
    float along = dot(vn, vdir);
    if (abs(along) < 1e-6) {
        return vec2(-1e9);
    }
    float s = dot(vn, hv - origin) / along;
    return to_pixel(frame.proj * vec4(origin + vdir * s, 1.0));
}

void judge(Found found, SsrRay ray, vec3 own, ivec2 res, out uint fail, out float confidence, out vec3 color) {
    vec3 vdir = ray.vdir;
    fail = found.reason;
    confidence = 0.0;
    color = vec3(0.0);
    if (fail != 0u) {
        return;
    }
    ivec2 hit_pixel = found.hit_pixel;
    vec4 hit_nr = texelFetch(gb_normal, hit_pixel, 0); // xyz normal, w reflectivity
    vec3 hit_n = normalize(hit_nr.xyz);
    vec3 world_dir = transpose(mat3(frame.view)) * vdir; // view is rigid
    if (dot(hit_n, world_dir) > 0.0) {
        fail = FAIL_BACK_FACE;
    } else if (hit_reflection_weight(hit_pixel, hit_nr.w, hit_n, -world_dir, own) > pc.recursion_min) {
        fail = FAIL_HIT_REFLECTIVE;
    } else if (distance(plane_crossing(ray_origin(ray), vdir, hit_pixel, hit_n), found.hit_pos) > SSR_PLANE_PX) {
        // The ray reached this pixel's depth without crossing its surface there: it
        // passed behind a surface thinner than the thickness (under a table top, behind
        // a thin wall) and crosses the surface's plane elsewhere on the screen, where
        // the surface is not. What it hits lies behind: the tracer's to find.
        fail = FAIL_BEHIND;
    } else {
        vec2 hp = vec2(hit_pixel) + 0.5;
        float edge = min(min(hp.x, float(res.x) - hp.x), min(hp.y, float(res.y) - hp.y));
        float fade_px = max(pc.edge_fade * float(min(res.x, res.y)), 1.0);
        confidence = clamp(edge / fade_px, 0.0, 1.0) * heading_confidence(vdir);
        if (confidence < pc.min_confidence) {
            fail = FAIL_LOW_CONFIDENCE;
        } else {
            color = lit_bilinear(found.hit_pos, res);
            fail = confidence < 1.0 ? FAIL_BLEND : 0u;
        }
    }
}

// Adds the marched pixel p, answered or not, to its tile's counts: one atomic pair a
// subgroup when all its lanes are in one tile (the list is appended a classify
// subgroup at a time, so runs of entries share a tile), else one a lane. Returns
// whether the tile is rays-only (the pixel is one of its probes).
bool count_in_tile(ivec2 p, bool answered) {
    uint groups_x = (frame.resolution.x + WG_2D - 1u) / WG_2D;
    uint t = (uint(p.y) / WG_2D) * groups_x + uint(p.x) / WG_2D;
    uint first = subgroupBroadcastFirst(t);
    bool one_tile = subgroupBallotBitCount(subgroupBallot(t == first)) == subgroupBallotBitCount(subgroupBallot(true));
    if (one_tile) {
        uint m = subgroupAdd(1u), a = subgroupAdd(answered ? 1u : 0u);
        if (subgroupElect()) {
            atomicAdd(tiles[t * TILE_WORDS + 1u], m);
            atomicAdd(tiles[t * TILE_WORDS + 2u], a);
        }
    } else {
        atomicAdd(tiles[t * TILE_WORDS + 1u], 1u);
        if (answered) {
            atomicAdd(tiles[t * TILE_WORDS + 2u], 1u);
        }
    }
    return (tiles[t * TILE_WORDS] & TILE_RAYS_ONLY) != 0u;
}

void main() {
    uint i = list_entry(march_args.w, SSR_LIST_WG);
    if (i >= march_args.w) {
        return;
    }
    ivec2 p = unpack_pixel(march_list[i]);
    ivec2 res = ivec2(frame.resolution);
    vec4 nr = texelFetch(gb_normal, p, 0); // xyz normal, w reflectivity
    float depth = texelFetch(gb_depth, p, 0).r;
    float roughness = texelFetch(gb_albedo, p, 0).a;
    uint rays = reflection_rays(roughness);
    vec3 base;
    float metallic;
    surface_at(p, base, metallic);
    // Every ray of the pixel (one, or a glossy pixel's reflection_rays): SSR answers
    // the pixel only if it answers each ray (the mean of their colours, the least
    // confidence); the first ray it cannot answer sends the whole pixel to the tracer.
    uint fail = 0u;
    float confidence = 1.0;
    vec3 color = vec3(0.0);
    SsrRay ray;
    vec3 own;
    float distance_sum = 0.0;
    for (uint s = 0u; s < rays; ++s) {
        ray = ssr_ray(p, depth, nr.xyz, roughness, s);
        vec3 vdir = ray.vdir;
        vec3 origin = ray_origin(ray);

        float near_z = -frame.proj[3][2] / frame.proj[2][2];
        // Lengths relative to the view depth keep SSR's answers the same at any scene scale.
        float max_len = pc.max_distance * abs(origin.z);
        float ray_len = (origin.z + vdir.z * max_len) > near_z ? (near_z - origin.z) / vdir.z : max_len;
        vec3 end_point = origin + vdir * ray_len;
        vec4 h0 = frame.proj * vec4(origin, 1.0);
        vec4 h1 = frame.proj * vec4(end_point, 1.0);
        Found found = HIZ ? march_hiz(h0, h1, res) : march_linear(h0, h1, origin, end_point, res);

        own = view_reflection(ray, nr.xyz, base, metallic, nr.w);
        uint f;
        float c;
        vec3 col;
        judge(found, ray, own, res, f, c, col);
        if (f != 0u && f != FAIL_BLEND) {
            fail = f;
            color = vec3(0.0);
            break;
        }
        fail |= f;
        confidence = min(confidence, c);
        color += col;
        ivec2 hp = found.hit_pixel;
        vec3 hit = (frame.view * vec4(world_from_depth(hp, texelFetch(gb_depth, hp, 0).r), 1.0)).xyz;
        distance_sum += length(hit - ray.vpos);
    }
    if (fail == 0u || fail == FAIL_BLEND) {
        color /= float(rays);
    }
    if (fail != 0u && pc.trace_min_weight > 0.0) {
        if (max(own.r, max(own.g, own.b)) < pc.trace_min_weight) {
            // Not traced: a faded hit is kept whole, a failure keeps the sky (but one
            // pixel in four is traced for its 2x2 block).
            if (fail == FAIL_BLEND) {
                fail = 0u;
            } else if (!traced_for_block(p)) {
                fail |= FAIL_UNTRACED;
                color = untraced_sky(ray);
            }
        }
    }
    // A probe of a rays-only tile measured SSR for the tile; its pixel then ends as the
    // tile's others (ssr.classify's skipped pixels): traced, or left untraced for its
    // block, so the tile has one source, no seam inside it, and which pixels a frame
    // probes does not show. A frame that only measures (the adaptive hybrid's probe
    // frame while idle) ends every marched pixel so: its image is the idle path's.
    // ssr.classify wrote those pixels' outputs, as it writes the skipped ones'.
    bool rays_only = count_in_tile(p, fail == 0u);
    if (pc.measure_only != 0u) {
        // What the marching path would not have traced (exchange::march_estimate).
        uint answered = subgroupAdd(!rays_only && fail == 0u ? 1u : 0u);
        if (subgroupElect() && answered > 0u) {
            atomicAdd(ssr_first_answered, answered);
        }
    }
    if (rays_only || pc.measure_only != 0u) {
        return;
    }
    bool kept = fail == 0u || fail == FAIL_BLEND;
    imageStore(ssr_out, p, vec4(color, kept ? confidence : 0.0));
    imageStore(fail_mask, p, uvec4(fail));
    imageStore(hit_distance, p, vec4(kept ? distance_sum / float(rays) : HIT_FAR));
}
