#version 460
// rt.trace with its lanes refilled (a candidate walk for wide SIMD groups; issue 52):
// closest-hit or any-hit traversal of the static BVH's compact nodes for a list of
// rays, each ray's walk rt.trace's (walk_bvh_step, walk_wide_step, walk_wide8_step), so
// its hit is rt.trace's bit for bit, closest or any (docs/precision.md). Where
// rt.trace gives each invocation one ray, and a SIMD group then takes as many passes as
// its longest walk while its finished lanes idle, here an invocation walks one step a
// pass, and when 1/SHARE of its subgroup's lanes (or all) hold no ray, those lanes
// take the next rays of a queue: one atomic a subgroup, each lane its place by ballot
// (after Aila & Laine 2009, persistent threads with dynamic fetch). Each invocation
// walks Refill::rays_per_lane rays on average (the dispatch's size, passes/rt_trace.rs).
// The static layout it walks and SHARE are specializations (one pipeline a layout:
// lavapipe runs every branch, uniform or not, so the others are compiled out).
// Mirrored by cpu_ref::trace (tests/suite/trace.rs: hits equal rt.trace's).
#extension GL_KHR_shader_subgroup_ballot : require
#define TRAVERSE_BINDING 3
#include "traverse.glsl"

// The static layout walked: its children a node (2: binary, WIDE, WIDE8).
layout(constant_id = 0) const uint SLOTS = 2u;
// Idle lanes take rays once they are at least 1/SHARE of the subgroup's (1: all; at
// least 1, Refill::new).
layout(constant_id = 1) const uint SHARE = 4u;

layout(local_size_x = LBVH_WG) in;

#include "ray_list.glsl"

// The queue's head: the next ray no lane has taken (0 before the dispatch). A dynamic
// BVH (pc.dynamic_tris) is not walked here: every ray fails.
layout(binding = 2, std430) coherent buffer Queue { uint next_ray; };

// One step of the ray's walk in the layout SLOTS names (traverse.glsl).
bool step(inout uint node, inout uint sp, inout uint top, vec3 g, vec3 st, vec3 origin, TriRay r, vec3 inv_dir,
          float tmin, bool any_hit, inout Hit best, inout bool failed) {
    if (SLOTS == WIDE8) {
        return walk_wide8_step(node, sp, top, origin, r, inv_dir, tmin, any_hit, best, failed);
    }
    if (SLOTS == WIDE) {
        return walk_wide_step(node, sp, top, g, st, origin, r, inv_dir, tmin, any_hit, best, failed);
    }
    return walk_bvh_step(0u, node, sp, top, g, st, origin, r, inv_dir, tmin, any_hit, best, failed);
}

void main() {
    bool any_hit = pc.any_hit != 0u;
    // What this walk reads: the static BVH alone, in the layout SLOTS names.
    bool walkable = pc.static_tris != 0u && pc.dynamic_tris == 0u && texelFetch(s_nodes, 0).w == SLOTS;
    vec3 g, st;
    static_grid(g, st);
    // The lane's ray and its walk.
    bool walking = false;
    uint ray = 0u, node = 0u, sp = 0u, top = BVH_INVALID, steps = 0u;
    vec3 origin = vec3(0.0), inv_dir = vec3(0.0);
    float tmin = 0.0;
    TriRay r = TriRay(vec3(0.0), vec3(0.0), 0u);
    Hit best = Hit(0.0, BVH_INVALID, 0.0, 0.0);
    bool failed = false;
    // Subgroup-uniform: whether the queue may hold rays; the subgroup's lanes (every
    // one stays in the loop to its end).
    bool queued = true;
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    while (true) {
        uvec4 idle = subgroupBallot(!walking);
        uint idle_lanes = subgroupBallotBitCount(idle);
        if (queued && SHARE * idle_lanes >= lanes) {
            uint first = 0u;
            if (subgroupElect()) {
                first = atomicAdd(next_ray, idle_lanes);
            }
            first = subgroupBroadcastFirst(first);
            queued = first + idle_lanes < pc.ray_count;
            uint k = first + subgroupBallotExclusiveBitCount(idle);
            if (!walking && k < pc.ray_count) {
                Ray q = rays[k];
                ray = k;
                origin = q.origin;
                tmin = q.tmin;
                inv_dir = ray_inv_dir(q.dir);
                r = tri_ray(q.origin, q.dir);
                best = Hit(q.tmax, BVH_INVALID, 0.0, 0.0);
                node = 0u;
                sp = 0u;
                top = BVH_INVALID;
                steps = 0u;
                failed = false;
                walking = true;
            }
        }
        if (subgroupBallotBitCount(subgroupBallot(walking)) == 0u) {
            if (!queued) {
                break;
            }
            continue;
        }
        if (walking) {
            bool ended = ++steps > pc.static_tris || !walkable;
            failed = failed || ended;
            ended = ended || step(node, sp, top, g, st, origin, r, inv_dir, tmin, any_hit, best, failed);
            if (ended) {
                // A failed walk is reported, never silently wrong (trace_ray).
                hits[ray] = failed ? Hit(-1.0, BVH_INVALID, 0.0, 0.0) : best;
                walking = false;
            }
        }
    }
}
