// BVH traversal shared by rt.trace and the reflection tracer: closest hit or any hit
// over two BVHs (static, dynamic), stack-based, nearest child first, a leaf's
// triangles tested in the step that hits its box (the stack holds internal nodes
// only). The watertight test (tri_hit below), double-sided. Epsilon policy: none; a
// triangle whose determinant is exactly 0 (parallel to the ray or zero area) is never
// hit, a ray exactly on an edge or corner hits it; a hit counts when tmin < t < tmax and it is
// closer than the best so far, equal t going to the smaller (bvh, triangle) id. No
// offset is applied to the origin: callers set tmin or offset origins. Mirrored by
// cpu_ref::trace.
//
// The includer defines TRAVERSE_BINDING (first of eight consecutive bindings) first.
// The walk reads the BVH's layout (bvh.glsl): one node per step, whose children's
// boxes are tested together, and a leaf's 1..BVH_LEAF_MAX 48-byte triangles in leaf
// order; the scene's vertices and indices serve only the hit's attributes. The static
// BVH is walked through its compact nodes (boxes rounded outward to a 16-bit grid), in
// the layout their header names: binary (walk_bvh, 32 bytes) or wide (walk_wide, 64
// bytes: up to WIDE children, a binary node's with each internal one opened); the
// dynamic BVH through the binary 64-byte nodes its refit keeps (walk_bvh). A rounded box holds the exact one, so the walk finds the hits it finds
// over the exact boxes, stepping into a few more nodes (tests/trace.rs: both walks).
// Nodes and triangles are read as uniform texel buffers of uvec4 (2 or 4, and 3 texels):
// lavapipe fetches a texel for all lanes without a branch, where it loads a storage
// buffer one lane and one word at a time, each behind a branch (1.2-1.4x the rays/s).
#ifndef TRAVERSE_GLSL
#define TRAVERSE_GLSL
#include "bvh.glsl"
#include "hit.glsl"

layout(binding = TRAVERSE_BINDING + 0) uniform utextureBuffer s_nodes;
layout(binding = TRAVERSE_BINDING + 1, std430) readonly buffer StaticVertices { Vertex s_vertices[]; };
layout(binding = TRAVERSE_BINDING + 2, std430) readonly buffer StaticIndices { uint s_indices[]; };
layout(binding = TRAVERSE_BINDING + 3) uniform utextureBuffer d_nodes;
layout(binding = TRAVERSE_BINDING + 4, std430) readonly buffer DynamicVertices { Vertex d_vertices[]; };
layout(binding = TRAVERSE_BINDING + 5, std430) readonly buffer DynamicIndices { uint d_indices[]; };
layout(binding = TRAVERSE_BINDING + 6) uniform utextureBuffer s_tris;
layout(binding = TRAVERSE_BINDING + 7) uniform utextureBuffer d_tris;


// Node i of `bvh`: the static BVH's from its binary compact nodes on the grid (g, st),
// its boxes rounded outward; the dynamic BVH's as built or refit (parent and unused are
// not read).
TraversalNode fetch_node(uint bvh, uint i, vec3 g, vec3 st) {
    if (bvh != 0u) {
        return node_from_texels(d_nodes, i);
    }
    uvec4 h0 = texelFetch(s_nodes, int(2u * i + 2u));
    uvec4 h1 = texelFetch(s_nodes, int(2u * i + 3u));
    TraversalNode n;
    compact_box(h0, g, st, n.lo0, n.hi0);
    compact_box(h1, g, st, n.lo1, n.hi1);
    n.child0 = h0.w;
    n.child1 = h1.w;
    n.parent = 0u;
    n.unused = 0u;
    return n;
}

// Triangle `k` (in leaf order) from a triangle buffer seen as texels of uvec4 (3 per
// TraversalTri).
void triangle_from_texels(utextureBuffer tris, uint k, out vec3 a, out vec3 b, out vec3 c, out uint id) {
    uvec4 w0 = texelFetch(tris, int(3u * k));
    a = uintBitsToFloat(w0.xyz);
    id = w0.w;
    b = uintBitsToFloat(texelFetch(tris, int(3u * k + 1u)).xyz);
    c = uintBitsToFloat(texelFetch(tris, int(3u * k + 2u)).xyz);
}

void fetch_triangle(uint bvh, uint k, out vec3 a, out vec3 b, out vec3 c, out uint id) {
    if (bvh == 0u) {
        triangle_from_texels(s_tris, k, a, b, c, id);
    } else {
        triangle_from_texels(d_tris, k, a, b, c, id);
    }
}

// The watertight ray/triangle test (Woop, Benthin & Wald 2013, "Watertight
// Ray/Triangle Intersection", JCGT 2(1)) without its divisions, mirrored by
// cpu_ref::trace::intersect. The axes are turned so the ray's largest component is z
// (kz); each corner p, relative to the origin, projects to two components of cross(p, d)
// (d.z times Woop's sheared x and y), and the edge functions U, V, W are 2D cross
// products of the projected corners. All of it is `precise` mul and sub, which Vulkan
// rounds correctly (no FMA contraction): every device and the CPU get the same U, V, W
// bit for bit, so whether a ray hits a triangle is exact, and two triangles sharing an
// edge see that edge's function with opposite signs: a ray through the edge hits at
// least one. t and the barycentrics are one division each (2.5 ULP in Vulkan).
// Contract: hit or miss exact on every device (unless an edge function falls in the
// subnormal range, which a device may flush); t, u, v within a few ULP.
struct TriRay {
    vec3 o; // the origin, axes turned
    vec3 d; // the direction, axes turned: |d.z| is its largest component
    uint kz; // the axis turned to z
};

vec3 turn_axes(vec3 v, uint kz) {
    return kz == 0u ? v.yzx : (kz == 1u ? v.zxy : v);
}

TriRay tri_ray(vec3 origin, vec3 dir) {
    vec3 m = abs(dir);
    uint kz = m.x >= m.y ? (m.x >= m.z ? 0u : 2u) : (m.y >= m.z ? 1u : 2u);
    return TriRay(turn_axes(origin, kz), turn_axes(dir, kz), kz);
}

// Corner v relative to the origin, projected: (x, y) across the ray, z along its axis.
vec3 tri_corner(TriRay r, vec3 v) {
    precise vec3 p = turn_axes(v, r.kz) - r.o;
    precise float x = p.y * r.d.z - p.z * r.d.y;
    precise float y = p.z * r.d.x - p.x * r.d.z;
    return vec3(x, y, p.z);
}

// Whether the ray hits triangle (a, b, c): then t along d and the barycentrics u, v of
// b and c.
bool tri_hit(TriRay r, vec3 a, vec3 b, vec3 c, out float t, out float u, out float v) {
    vec3 pa = tri_corner(r, a), pb = tri_corner(r, b), pc = tri_corner(r, c);
    precise float eu = pc.x * pb.y - pc.y * pb.x;
    precise float ev = pa.x * pc.y - pa.y * pc.x;
    precise float ew = pb.x * pa.y - pb.y * pa.x;
    t = 0.0;
    u = 0.0;
    v = 0.0;
    if ((eu < 0.0 || ev < 0.0 || ew < 0.0) && (eu > 0.0 || ev > 0.0 || ew > 0.0)) {
        return false;
    }
    precise float det = eu + ev + ew;
    if (det == 0.0) {
        return false;
    }
    precise float depth = eu * pa.z + ev * pb.z + ew * pc.z;
    precise float scale = det * r.d.z;
    t = depth / scale;
    u = ev / det;
    v = ew / det;
    return true;
}

// Entry distance of the ray into the box, or +inf when it misses within [tmin, tmax].
float box_entry(vec3 lo, vec3 hi, vec3 o, vec3 inv_dir, float tmin, float tmax) {
    vec3 t0 = (lo - o) * inv_dir;
    vec3 t1 = (hi - o) * inv_dir;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, tmin));
    float exit = min(min(tf.x, tf.y), min(tf.z, tmax));
    return enter <= exit ? enter : 1.0 / 0.0;
}


// Tests triangle k (in leaf order) of `bvh`; true when it is hit within (tmin,
// best.t), or at best.t with a smaller id, and then `best` is that hit.
bool hit_triangle(uint bvh, uint k, TriRay r, float tmin, inout Hit best) {
    vec3 a, b, c;
    uint t;
    fetch_triangle(bvh, k, a, b, c, t);
    float th, u, v;
    bool inside = tri_hit(r, a, b, c, th, u, v);
    uint id = bvh == 0u ? t : t | HIT_DYNAMIC;
    bool closer = th < best.t || (th == best.t && id < best.prim);
    if (inside && th > tmin && closer) {
        best = Hit(th, id, u, v);
        return true;
    }
    return false;
}

// Tests the triangles of leaf `ref` (hit_triangle); true when `any_hit` and one was
// hit (the walk can stop).
bool hit_leaf(uint bvh, uint ref, TriRay r, float tmin, bool any_hit, inout Hit best) {
    uint first = bvh_leaf_first(ref);
    uint last = first + bvh_leaf_count(ref);
    for (uint k = first; k < last; ++k) {
        if (hit_triangle(bvh, k, r, tmin, best) && any_hit) {
            return true;
        }
    }
    return false;
}

// Vertex `k` (0..2) of hit triangle `prim` (HIT_DYNAMIC: the dynamic BVH's).
Vertex hit_vertex(uint prim, uint k) {
    uint t = prim & ~HIT_DYNAMIC;
    if ((prim & HIT_DYNAMIC) == 0u) {
        return s_vertices[s_indices[3u * t + k]];
    }
    return d_vertices[d_indices[3u * t + k]];
}

// The walk's stack of internal nodes still to visit (a leaf is tested in the step that
// hits its box); one for both walks. Its top entry is kept in a register (`top` in
// walk_bvh) and spilled to the array only under a new push: most pops then take the
// register, not a private array that lavapipe reads and writes lane by lane (rays/s
// about 1.04x, rt.reflect 0.95-0.98x).
uint trace_stack[TRACE_STACK];

// Pushes `link` on the walk's stack (the top in a register, the rest in trace_stack);
// sets `failed` instead when the stack is full.
void push_node(uint link, inout uint sp, inout uint top, inout bool failed) {
    if (sp < TRACE_STACK) {
        if (top != BVH_INVALID) {
            trace_stack[sp - 1u] = top;
        }
        top = link;
        ++sp;
    } else {
        failed = true;
    }
}

// Pops the walk's next node into `node`; false when the stack is empty.
bool pop_node(inout uint node, inout uint sp, inout uint top) {
    if (sp == 0u) {
        return false;
    }
    --sp;
    if (top != BVH_INVALID) {
        node = top;
        top = BVH_INVALID;
    } else {
        node = trace_stack[sp];
    }
    return true;
}

// One step of a ray's walk of BVH `bvh` through binary nodes (0: the static BVH's
// binary compact nodes on the grid g, st; 1: the dynamic BVH's): visits `node`, tests
// the triangles of the leaves among its hit children and goes on to the nearer
// internal child (the farther pushed), else pops. True when the walk has ended: the
// stack is empty, or with `any_hit` a triangle was hit. `failed` as in push_node.
bool walk_bvh_step(uint bvh, inout uint node, inout uint sp, inout uint top, vec3 g, vec3 st, vec3 origin,
                   TriRay r, vec3 inv_dir, float tmin, bool any_hit, inout Hit best, inout bool failed) {
    TraversalNode nd = fetch_node(bvh, node, g, st);
    float t0 = box_entry(nd.lo0, nd.hi0, origin, inv_dir, tmin, best.t);
    float t1 = box_entry(nd.lo1, nd.hi1, origin, inv_dir, tmin, best.t);
    bool hit0 = t0 != 1.0 / 0.0;
    bool hit1 = t1 != 1.0 / 0.0;
    bool found = false;
    if (hit0 && (nd.child0 & BVH_LEAF_BIT) != 0u) {
        found = hit_leaf(bvh, nd.child0, r, tmin, any_hit, best);
        hit0 = false;
    }
    if (hit1 && !found && (nd.child1 & BVH_LEAF_BIT) != 0u) {
        found = hit_leaf(bvh, nd.child1, r, tmin, any_hit, best);
        hit1 = false;
    }
    if (found) {
        return true;
    }
    if (hit0 && hit1) {
        uint near = t0 <= t1 ? nd.child0 : nd.child1;
        uint far = t0 <= t1 ? nd.child1 : nd.child0;
        push_node(far, sp, top, failed);
        node = near;
        return false;
    } else if (hit0 || hit1) {
        node = hit0 ? nd.child0 : nd.child1;
        return false;
    }
    return !pop_node(node, sp, top);
}

// The static BVH's compact grid (origin, step), from its header.
void static_grid(out vec3 g, out vec3 st) {
    g = uintBitsToFloat(texelFetch(s_nodes, 0).xyz);
    st = uintBitsToFloat(texelFetch(s_nodes, 1).xyz);
}

// One ray's walk of BVH `bvh` through binary nodes (0: the static BVH's binary compact
// nodes, 1: the dynamic BVH's), a step at a time (walk_bvh_step). Called with a
// constant `bvh`, so each call compiles to the fetches of its own BVH only. Sets
// `failed` when a push would pass TRACE_STACK (the push is dropped), or when the walk
// would take more than `max_steps` steps: a step visits one internal node, and a walk
// of a valid tree visits each of its N-1 nodes at most once, so a walk past N steps is
// in a cycle (a corrupted tree) and stops instead of hanging the device.
void walk_bvh(uint bvh, vec3 origin, TriRay r, vec3 inv_dir, float tmin, bool any_hit, uint max_steps,
              inout Hit best, inout bool failed) {
    uint sp = 0u;
    uint steps = 0u;
    uint top = BVH_INVALID; // when set, the top of the sp entries; the array holds the rest
    uint node = 0u; // the root, an internal node (or two links to the single leaf)
    vec3 grid_origin = vec3(0.0), grid_step = vec3(0.0);
    if (bvh == 0u) {
        static_grid(grid_origin, grid_step);
    }
    while (true) {
        if (++steps > max_steps) {
            failed = true;
            break;
        }
        if (walk_bvh_step(bvh, node, sp, top, grid_origin, grid_step, origin, r, inv_dir, tmin, any_hit, best,
                          failed)) {
            break;
        }
    }
}

// Orders slots a and b of four children (vectors t of entry distances, link of links)
// by entry distance; WIDE_ORDER4 orders all four by a sorting network (walk_wide's
// node: WIDE is 4, shader_defines.rs asserts it; walk_wide8's two halves).
#define WIDE_ORDER(t, link, a, b)                                                          \
    if (t[b] < t[a]) {                                                                     \
        float tt = t[a];                                                                   \
        t[a] = t[b];                                                                       \
        t[b] = tt;                                                                         \
        uint ll = link[a];                                                                 \
        link[a] = link[b];                                                                 \
        link[b] = ll;                                                                      \
    }
#define WIDE_ORDER4(t, link)                                                               \
    WIDE_ORDER(t, link, 0, 1)                                                              \
    WIDE_ORDER(t, link, 2, 3)                                                              \
    WIDE_ORDER(t, link, 0, 2)                                                              \
    WIDE_ORDER(t, link, 1, 3)                                                              \
    WIDE_ORDER(t, link, 1, 2)

// One step of walk_wide: visits wide node `node` (on the grid g, st) and goes on as
// walk_bvh_step does; true when the walk has ended.
bool walk_wide_step(inout uint node, inout uint sp, inout uint top, vec3 g, vec3 st, vec3 origin, TriRay r,
                    vec3 inv_dir, float tmin, bool any_hit, inout Hit best, inout bool failed) {
    // Vectors, not arrays: a vector stays in registers where lavapipe keeps a private
    // array in memory, read and written lane by lane.
    vec4 t;
    uvec4 link;
    for (uint k = 0u; k < WIDE; ++k) {
        uvec4 h = texelFetch(s_nodes, int(2u + WIDE * node + k));
        vec3 lo, hi;
        compact_box(h, g, st, lo, hi);
        link[k] = h.w;
        t[k] = h.w == BVH_INVALID ? 1.0 / 0.0 : box_entry(lo, hi, origin, inv_dir, tmin, best.t);
    }
    bool found = false;
    for (uint k = 0u; k < WIDE; ++k) {
        if (!found && t[k] != 1.0 / 0.0 && (link[k] & BVH_LEAF_BIT) != 0u) {
            found = hit_leaf(0u, link[k], r, tmin, any_hit, best);
            t[k] = 1.0 / 0.0;
        }
    }
    if (found) {
        return true;
    }
    for (uint k = 0u; k < WIDE; ++k) {
        // A child entered beyond the best hit so far (a leaf may have just made it)
        // holds no closer hit.
        if (t[k] > best.t) {
            t[k] = 1.0 / 0.0;
        }
    }
    WIDE_ORDER4(t, link)
    if (t[0] != 1.0 / 0.0) {
        for (int k = int(WIDE) - 1; k > 0; --k) {
            if (t[k] != 1.0 / 0.0) {
                push_node(link[k], sp, top, failed);
            }
        }
        node = link[0];
        return false;
    }
    return !pop_node(node, sp, top);
}

// One ray's walk of the static BVH through its wide nodes (lbvh.compact): a step tests
// a node's WIDE slots, the leaves among the hit ones at once, and goes on to the
// nearest internal child, the others pushed far first (so the nearer pops first).
// Every pushed or visited node is a grandchild of the binary tree: a step descends two
// levels and pushes at most WIDE - 1, so a tree of depth D needs (WIDE - 1) ceil(D / 2)
// entries (tracers::lbvh asserts TRACE_STACK holds them). `failed` and `max_steps` as
// in walk_bvh.
void walk_wide(vec3 origin, TriRay r, vec3 inv_dir, float tmin, bool any_hit, uint max_steps, inout Hit best,
               inout bool failed) {
    uint sp = 0u;
    uint steps = 0u;
    uint top = BVH_INVALID; // when set, the top of the sp entries; the array holds the rest
    uint node = 0u;         // the root's wide node
    vec3 g, st;
    static_grid(g, st);
    while (true) {
        if (++steps > max_steps) {
            failed = true;
            break;
        }
        if (walk_wide_step(node, sp, top, g, st, origin, r, inv_dir, tmin, any_hit, best, failed)) {
            break;
        }
    }
}

// The entry distances of four children of a compressed wide node (bvh.glsl) into
// vectors: their boxes' coordinate bytes (a word each: lo x, y, z, hi x, y, z) on the
// grid (g, st), their links; +inf for a box missed within [tmin, tmax] or an unused
// slot. The same arithmetic as box_entry per child.
vec4 wide8_entries(uvec3 wlo, uvec3 whi, uvec4 link, vec3 g, vec3 st, vec3 o, vec3 inv_dir, float tmin,
                   float tmax) {
    const uvec4 sh = uvec4(0u, 8u, 16u, 24u);
    vec4 lx = g.x + vec4((uvec4(wlo.x) >> sh) & 0xffu) * st.x;
    vec4 ly = g.y + vec4((uvec4(wlo.y) >> sh) & 0xffu) * st.y;
    vec4 lz = g.z + vec4((uvec4(wlo.z) >> sh) & 0xffu) * st.z;
    vec4 hx = g.x + vec4((uvec4(whi.x) >> sh) & 0xffu) * st.x;
    vec4 hy = g.y + vec4((uvec4(whi.y) >> sh) & 0xffu) * st.y;
    vec4 hz = g.z + vec4((uvec4(whi.z) >> sh) & 0xffu) * st.z;
    vec4 t0x = (lx - o.x) * inv_dir.x, t1x = (hx - o.x) * inv_dir.x;
    vec4 t0y = (ly - o.y) * inv_dir.y, t1y = (hy - o.y) * inv_dir.y;
    vec4 t0z = (lz - o.z) * inv_dir.z, t1z = (hz - o.z) * inv_dir.z;
    vec4 enter = max(max(min(t0x, t1x), min(t0y, t1y)), max(min(t0z, t1z), vec4(tmin)));
    vec4 exit = min(min(max(t0x, t1x), max(t0y, t1y)), min(max(t0z, t1z), vec4(tmax)));
    bvec4 hit = bvec4(uvec4(lessThanEqual(enter, exit)) & uvec4(notEqual(link, uvec4(BVH_INVALID))));
    return mix(vec4(1.0 / 0.0), enter, hit);
}

// One step of walk_wide8: visits compressed wide node `node` and goes on as
// walk_bvh_step does; true when the walk has ended.
bool walk_wide8_step(inout uint node, inout uint sp, inout uint top, vec3 origin, TriRay r, vec3 inv_dir,
                     float tmin, bool any_hit, inout Hit best, inout bool failed) {
    int base = int(2u + WIDE8_TEXELS * node);
    uvec4 h = texelFetch(s_nodes, base);
    uvec4 q0 = texelFetch(s_nodes, base + 1);
    uvec4 q1 = texelFetch(s_nodes, base + 2);
    uvec4 q2 = texelFetch(s_nodes, base + 3);
    uvec4 la = texelFetch(s_nodes, base + 4);
    uvec4 lb = texelFetch(s_nodes, base + 5);
    vec3 g = uintBitsToFloat(h.xyz);
    vec3 st = uintBitsToFloat(((uvec3(h.w) >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u);
    vec4 ta = wide8_entries(uvec3(q0.x, q0.z, q1.x), uvec3(q1.z, q2.x, q2.z), la, g, st, origin, inv_dir, tmin,
                            best.t);
    vec4 tb = wide8_entries(uvec3(q0.y, q0.w, q1.y), uvec3(q1.w, q2.y, q2.w), lb, g, st, origin, inv_dir, tmin,
                            best.t);
    bool found = false;
    for (uint k = 0u; k < 4u; ++k) {
        if (!found && ta[k] != 1.0 / 0.0 && (la[k] & BVH_LEAF_BIT) != 0u) {
            found = hit_leaf(0u, la[k], r, tmin, any_hit, best);
            ta[k] = 1.0 / 0.0;
        }
    }
    for (uint k = 0u; k < 4u; ++k) {
        if (!found && tb[k] != 1.0 / 0.0 && (lb[k] & BVH_LEAF_BIT) != 0u) {
            found = hit_leaf(0u, lb[k], r, tmin, any_hit, best);
            tb[k] = 1.0 / 0.0;
        }
    }
    if (found) {
        return true;
    }
    // A child entered beyond the best hit so far (a leaf may have just made it)
    // holds no closer hit.
    ta = mix(ta, vec4(1.0 / 0.0), greaterThan(ta, vec4(best.t)));
    tb = mix(tb, vec4(1.0 / 0.0), greaterThan(tb, vec4(best.t)));
    WIDE_ORDER4(ta, la)
    WIDE_ORDER4(tb, lb)
    // Entered children first in each four: how many, and which four the nearest.
    int na = int(dot(vec4(notEqual(ta, vec4(1.0 / 0.0))), vec4(1.0)));
    int nb = int(dot(vec4(notEqual(tb, vec4(1.0 / 0.0))), vec4(1.0)));
    if (na + nb == 0) {
        return !pop_node(node, sp, top);
    }
    bool near_a = na > 0 && (nb == 0 || ta[0] <= tb[0]);
    int ia = na - 1, ib = nb - 1;
    int stop_a = near_a ? 1 : 0, stop_b = near_a ? 0 : 1;
    for (int k = 0; k < int(WIDE8) - 1; ++k) {
        bool more_a = ia >= stop_a, more_b = ib >= stop_b;
        if (!more_a && !more_b) {
            break;
        }
        bool take_a = more_a && (!more_b || ta[ia] > tb[ib]);
        push_node(take_a ? la[ia] : lb[ib], sp, top, failed);
        ia -= take_a ? 1 : 0;
        ib -= take_a ? 0 : 1;
    }
    node = near_a ? la[0] : lb[0];
    return false;
}

// One ray's walk of the static BVH through its compressed wide nodes (lbvh.compact):
// a step tests a node's WIDE8 children (two vectors of four), the leaves among the
// hit ones at once, and goes on to the nearest internal child; the others are pushed
// far first: each four ordered by walk_wide's network, the two merged from their far
// ends (ties to the first four). A step descends three levels and pushes at most
// WIDE8 - 1 (tracers::lbvh asserts TRACE_STACK holds them). `failed` and `max_steps`
// as in walk_bvh. Mirrored by cpu_ref::walk::replay.
void walk_wide8(vec3 origin, TriRay r, vec3 inv_dir, float tmin, bool any_hit, uint max_steps, inout Hit best,
                inout bool failed) {
    uint sp = 0u;
    uint steps = 0u;
    uint top = BVH_INVALID; // when set, the top of the sp entries; the array holds the rest
    uint node = 0u;         // the root's compressed wide node
    while (true) {
        if (++steps > max_steps) {
            failed = true;
            break;
        }
        if (walk_wide8_step(node, sp, top, origin, r, inv_dir, tmin, any_hit, best, failed)) {
            break;
        }
    }
}

// The inverse of a ray's direction for the box tests: a zero component becomes a huge
// finite inverse (not inf: 0 * inf = NaN).
vec3 ray_inv_dir(vec3 dir) {
    return 1.0 / mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
}

// Traces one ray through both BVHs (a BVH with 0 triangles is skipped). Returns the
// closest hit, or with any_hit the first found; t = -1 if a walk failed (its stack
// overflowed, or it overran its step bound: the tree is not what the walk expects).
Hit trace_ray(vec3 origin, vec3 dir, float tmin, float tmax, uint static_tris, uint dynamic_tris, bool any_hit) {
    vec3 inv_dir = ray_inv_dir(dir);
    Hit best = Hit(tmax, BVH_INVALID, 0.0, 0.0);
    bool failed = false;
    TriRay r = tri_ray(origin, dir);
    if (static_tris != 0u) {
        // The static BVH's layout, as its compact nodes' header says (the same for
        // every ray: a uniform branch).
        uint slots = texelFetch(s_nodes, 0).w;
        if (slots == WIDE8) {
            walk_wide8(origin, r, inv_dir, tmin, any_hit, static_tris, best, failed);
        } else if (slots == WIDE) {
            walk_wide(origin, r, inv_dir, tmin, any_hit, static_tris, best, failed);
        } else {
            walk_bvh(0u, origin, r, inv_dir, tmin, any_hit, static_tris, best, failed);
        }
    }
    if (dynamic_tris != 0u && !(any_hit && best.prim != BVH_INVALID)) {
        walk_bvh(1u, origin, r, inv_dir, tmin, any_hit, dynamic_tris, best, failed);
    }
    if (failed) {
        best = Hit(-1.0, BVH_INVALID, 0.0, 0.0); // reported as an error, never silently wrong
    }
    return best;
}
#endif
