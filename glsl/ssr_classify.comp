#version 460
// CPU reference: cpu_ref::ssr::classify (tests/ssr.rs).
#extension GL_KHR_shader_subgroup_ballot : require
// ssr.classify: which pixels ssr.trace marches (after FidelityFX SSSR's classification).
// A pixel with no reflective surface gets no reflection (fail mask 0); a reflective
// pixel whose heading alone keeps its confidence below the threshold fails
// (FAIL_LOW_CONFIDENCE) without a march, as every outcome of the march would (and is
// not traced either, keeping the sky, where its own reflection weighs less than
// trace_min_weight: FAIL_UNTRACED); the rest
// are appended to the march list, whose length sets ssr.trace's indirect dispatch. So
// the march and everything around it run only where they can give a reflection:
// lavapipe pays a full-screen kernel's whole straight-line code on every pixel, taken
// branch or not. Pixels listed here get their SSR colour and fail mask from ssr.trace,
// but for those marched only to measure (below); the rest get them here. Mirrored by
// cpu_ref::ssr::classify.
// The adaptive hybrid: each workgroup is a tile (TILE_* in shader_defines.rs), whose
// state for this frame ssr_tiles.comp has just written; in a rays-only tile a pixel that would
// be marched is not (FAIL_SKIPPED: straight to the ray tracer) unless it is a probe
// (tile_probe), which keeps measuring the tile's success (ssr.trace counts it; its
// outputs are written here, as the tile's skipped pixels'). Mirrored by
// cpu_ref::ssr::tile_update and tile_probe. With skip_all (the adaptive hybrid's idle
// path) every tile is treated as rays-only with no probe: nothing is listed.
#include "ssr.glsl"
#include "pixel_list.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 1) uniform sampler2D gb_depth;
layout(binding = 2) uniform sampler2D gb_normal;
layout(binding = 3) uniform usampler2D gb_material;
layout(binding = 4, rgba32f) uniform writeonly image2D ssr_out; // rgb colour, a confidence
layout(binding = 5, r32ui) uniform writeonly uimage2D fail_mask;
layout(binding = 6, std430) writeonly buffer MarchList { uint march_list[]; };
// VkDispatchIndirectCommand of ssr.trace (x) and the list's length (w); x and w are
// zeroed before, y and z are 1.
layout(binding = 7, std430) buffer MarchArgs { uvec4 march_args; };
layout(binding = 8) uniform sampler2D gb_albedo; // rgb: base colour, sRGB-encoded
layout(binding = 9) uniform sampler2D gb_motion; // w: metallic

// The glossy pixels (glossy.glsl), for reflect.denoise: packed pixels, and its
// VkDispatchIndirectCommand (x, y) and length (w), zeroed before as march_args.
layout(binding = 10, std430) writeonly buffer GlossyList { uint glossy_list[]; };
layout(binding = 11, std430) buffer GlossyArgs { uvec4 glossy_args; };
// The reflected rays' distance to what they hit (glossy.glsl's HIT_FAR here, for pixels
// not marched; ssr.trace and rt.reflect write the rest), for reflect.denoise's footprint.
layout(binding = 12, r32f) uniform writeonly image2D hit_distance;
// This frame's tile states (TILE_WORDS a tile, ssr_tiles.comp's).
layout(binding = 13, std430) readonly buffer Tiles { uint tiles[]; };
// The pixels marched in known SSR-first tiles; zeroed before. None: the renderer
// may skip the march until the next probe frame.
layout(binding = 14, std430) buffer SsrFirst { uint ssr_first_marches; };
// The rt mode's variant: no SSR, every reflective pixel fails (FAIL_FORCED).
layout(constant_id = 0) const bool MASK_ONLY = false;

layout(push_constant) uniform Push {
    float min_confidence; // below: the pixel fails
    float reflective_min; // reflectivity above which a pixel reflects
    float trace_min_weight; // failed pixels whose own reflection weighs less are not traced
    uint tile_history; // 0: no last frame (the first after a reset or resize)
    uint skip_all; // 1: as if every tile were rays-only without probes (tiles not read)
    uint measure_only; // 1: every marched pixel ends as a rays-only tile's probe
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 res = ivec2(frame.resolution);
    bool inside = all(lessThan(p, res));
    uint fail = 0u;
    bool march = false;
    bool ends_skipped = false;
    bool glossy = false;
    vec3 sky = vec3(0.0);
    bool skip_all = pc.skip_all != 0u;
    uint tile = MASK_ONLY || skip_all ? 0u : tiles[(gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * TILE_WORDS];
    bool rays_only = skip_all || (tile & TILE_RAYS_ONLY) != 0u;
    if (inside) {
        uint material = texelFetch(gb_material, p, 0).r;
        vec4 nr = texelFetch(gb_normal, p, 0);
        bool reflective = material != MATERIAL_NONE && nr.w > pc.reflective_min;
        float roughness = texelFetch(gb_albedo, p, 0).a;
        glossy = reflective && is_glossy(roughness);
        if (MASK_ONLY) {
            fail = reflective ? FAIL_FORCED : 0u;
        } else if (reflective) {
            SsrRay r = ssr_ray(p, texelFetch(gb_depth, p, 0).r, nr.xyz, roughness, 0u);
            march = heading_confidence(r.vdir) >= pc.min_confidence;
            fail = march ? 0u : FAIL_LOW_CONFIDENCE;
            if (march && rays_only && (skip_all || !tile_probe(uvec2(p), frame.frame_index))) {
                march = false;
                fail = FAIL_SKIPPED;
            }
            // A rays-only tile's probe, and every marched pixel of a frame that only
            // measures, is marched to measure SSR and then ends as the tile's skipped
            // pixels: decided and written here, by the same instructions as theirs, so
            // no device's rounding can tell a probe from its neighbours (ssr.trace
            // writes nothing for it).
            ends_skipped = march && (rays_only || pc.measure_only != 0u);
            if (ends_skipped) {
                fail = FAIL_SKIPPED;
            }
            if ((!march || ends_skipped) && pc.trace_min_weight > 0.0) {
                vec3 base = srgb_decode(texelFetch(gb_albedo, p, 0).rgb);
                if (untraced_for_block(p, r, nr.xyz, base, texelFetch(gb_motion, p, 0).w, nr.w, pc.trace_min_weight)) {
                    fail |= FAIL_UNTRACED;
                    sky = untraced_sky(r);
                }
            }
        }
        if (!march || ends_skipped) {
            imageStore(ssr_out, p, vec4(sky, 0.0));
            imageStore(fail_mask, p, uvec4(fail));
            imageStore(hit_distance, p, vec4(HIT_FAR));
        }
    }
    // One atomic per subgroup for its listed pixels; the dispatch covers the list.
    uvec4 ballot = subgroupBallot(march);
    uint n = subgroupBallotBitCount(ballot);
    uint base = 0u;
    if (subgroupElect() && n > 0u) {
        base = atomicAdd(march_args.w, n);
        uvec2 groups = list_groups((base + n + SSR_LIST_WG - 1u) / SSR_LIST_WG);
        atomicMax(march_args.x, groups.x);
        atomicMax(march_args.y, groups.y);
    }
    base = subgroupBroadcastFirst(base);
    if (march) {
        march_list[base + subgroupBallotExclusiveBitCount(ballot)] = pack_pixel(uvec2(p));
    }
    // The SSR-first tiles' marches: not the rays-only tiles' probes, nor after the
    // first frame the marches of tiles not known yet (a glossy pixel's sampled ray
    // turning marchable, a surface coming into view), which probe frames learn.
    bool known_first = !MASK_ONLY && !rays_only && ((tile & TILE_KNOWN) != 0u || pc.tile_history == 0u);
    uint first_tile = subgroupBallotBitCount(subgroupBallot(march && known_first));
    if (subgroupElect() && first_tile > 0u) {
        atomicAdd(ssr_first_marches, first_tile);
    }
    // The glossy list, likewise.
    ballot = subgroupBallot(glossy);
    n = subgroupBallotBitCount(ballot);
    base = 0u;
    if (subgroupElect() && n > 0u) {
        base = atomicAdd(glossy_args.w, n);
        uvec2 groups = list_groups((base + n + SSR_LIST_WG - 1u) / SSR_LIST_WG);
        atomicMax(glossy_args.x, groups.x);
        atomicMax(glossy_args.y, groups.y);
    }
    base = subgroupBroadcastFirst(base);
    if (glossy) {
        glossy_list[base + subgroupBallotExclusiveBitCount(ballot)] = pack_pixel(uvec2(p));
    }
}
