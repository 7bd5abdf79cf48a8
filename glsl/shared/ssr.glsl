// What ssr.classify and ssr.trace share: the reflected view ray of a pixel, and the
// confidence its heading allows. Mirrored by cpu_ref::ssr.
#ifndef SSR_GLSL
#define SSR_GLSL
#include "glossy.glsl"

// The reflected ray of pixel p (G-buffer depth and world normal) in view space.
struct SsrRay {
    vec3 vpos; // the surface point
    vec3 vn;   // its unit normal
    vec3 vdir; // the unit reflected direction
};

// Where the march starts: a little off the surface, so the first steps do not hit the
// pixel itself.
vec3 ray_origin(SsrRay r) {
    return r.vpos + r.vn * (1e-3 * abs(r.vpos.z));
}

// Ray `s` of the pixel (glossy.glsl): the mirror direction, or the sampled one of a
// glossy surface of perceptual `roughness`.
SsrRay ssr_ray(ivec2 p, float depth, vec3 n_world, float roughness, uint s) {
    SsrRay r;
    r.vpos = (frame.view * vec4(world_from_depth(p, depth), 1.0)).xyz;
    r.vn = normalize(mat3(frame.view) * normalize(n_world));
    if (is_glossy(roughness)) {
        vec3 v = transpose(mat3(frame.view)) * -normalize(r.vpos); // view is rigid
        vec3 l = glossy_direction(p, normalize(n_world), normalize(v), roughness, s);
        r.vdir = normalize(mat3(frame.view) * l);
    } else {
        r.vdir = normalize(reflect(normalize(r.vpos), r.vn));
    }
    return r;
}

// The confidence factor of a ray's heading (view space, unit): 1 for rays away from
// the camera, falling to 0 for rays straight back at it, which the screen rarely holds.
// A hit's confidence is at most this (edge fade aside).
float heading_confidence(vec3 vdir) {
    return clamp(1.0 - vdir.z, 0.0, 1.0);
}

// The weight of the pixel's own mirror reflection as the camera sees it (reflectivity x
// Fresnel, per channel).
vec3 view_reflection(SsrRay r, vec3 n_world, vec3 base, float metallic, float reflectivity) {
    vec3 v = transpose(mat3(frame.view)) * -normalize(r.vpos); // view is rigid
    return reflection_weight(base, metallic, reflectivity, normalize(n_world), v);
}

// Its largest channel: below trace_min_weight the pixel is traced one in four.
float view_reflection_weight(SsrRay r, vec3 n_world, vec3 base, float metallic, float reflectivity) {
    vec3 w = view_reflection(r, n_world, base, metallic, reflectivity);
    return max(w.r, max(w.g, w.b));
}

// Of the failed pixels whose reflection weighs less than trace_min_weight, the one at
// the even corner of each 2x2 block is traced for its block; the others are not
// (FAIL_UNTRACED) and take that ray's colour in reflect.merge, else the sky.
bool traced_for_block(ivec2 p) {
    return ((p.x | p.y) & 1) == 0;
}

// What an untraced pixel keeps where SSR found no hit: the sky in the reflected
// direction, which is what a miss of the ray tracer returns.
vec3 untraced_sky(SsrRay r) {
    return sky_radiance(transpose(mat3(frame.view)) * r.vdir);
}

// Whether a pixel sent to the ray tracer unmarched (its heading too low, or a rays-only
// tile's) is left untraced: its first ray's reflection weighs less than `min_weight`
// (0: every one traced) and another pixel of its 2x2 block is traced for it.
// ssr.classify decides by it for its pixels and for a rays-only tile's probes alike, so
// a probe ends as the tile's other pixels (cpu_ref::ssr::classify_in_tile).
bool untraced_for_block(ivec2 p, SsrRay r, vec3 n_world, vec3 base, float metallic, float reflectivity, float min_weight) {
    return min_weight > 0.0 && !traced_for_block(p) && view_reflection_weight(r, n_world, base, metallic, reflectivity) < min_weight;
}
#endif

// The adaptive hybrid's tile state after a frame in which `marched` of its pixels were
// marched and `answered` of those answered by SSR (mirrored by
// cpu_ref::ssr::tile_update): the success share (1/256, rounded) joins the smoothed
// one, 3:1 (taken whole the first time it is known); then the class: SSR-first while
// unknown or with `rate` 0 (the SSR-first policy), else it turns rays-only when the
// success falls tile_hysteresis(rate) below `rate` (the march's cost in rays, 1/256: a tile
// pays rate + (1 - success) rays a pixel SSR-first against 1 rays-only) and back when
// it rises that much above; a change of class adds one to the tile's flips. Integers:
// the CPU matches it exactly.
// How far a tile's success must pass `rate` to change class: a quarter of the rate,
// within 1..TILE_HYSTERESIS (mirrored by cpu_ref::ssr::tile_hysteresis).
uint tile_hysteresis(uint rate) {
    return clamp(rate / 4u, 1u, TILE_HYSTERESIS);
}

uint tile_update(uint state, uint marched, uint answered, uint rate) {
    uint s = state & TILE_SUCCESS;
    bool known = (state & TILE_KNOWN) != 0u;
    bool was_rays_only = (state & TILE_RAYS_ONLY) != 0u;
    bool rays_only = was_rays_only;
    uint flips = state >> TILE_FLIPS_SHIFT;
    if (marched > 0u) {
        uint share = (answered * TILE_ONE + marched / 2u) / marched;
        s = known ? (3u * s + share + 2u) / 4u : share;
        known = true;
    }
    if (rate == 0u || !known) {
        rays_only = false;
    } else if (rays_only && s > rate + tile_hysteresis(rate)) {
        rays_only = false;
    } else if (!rays_only && s + tile_hysteresis(rate) < rate) {
        rays_only = true;
    }
    if (rays_only != was_rays_only) {
        flips = min(flips + 1u, TILE_FLIPS_MAX);
    }
    return s | (known ? TILE_KNOWN : 0u) | (rays_only ? TILE_RAYS_ONLY : 0u) | (flips << TILE_FLIPS_SHIFT);
}

// Whether pixel p of a rays-only tile is marched anyway in frame `frame` (a probe): one
// pixel in each 4x4 block, the block's (frame mod 4, frame / 4 mod 4), so 4 of a tile's
// 64 pixels a frame and each pixel every 16 frames. Mirrored by cpu_ref::ssr::tile_probe.
bool tile_probe(uvec2 p, uint frame) {
    return (p.x & 3u) == (frame & 3u) && (p.y & 3u) == ((frame >> 2u) & 3u);
}
