// BVH traversal shared by rt.trace and the reflection tracer: closest hit or any hit
// over two BVHs (static, dynamic), stack-based, nearest child first. Moller-Trumbore,
// double-sided. Epsilon policy: a triangle whose determinant is exactly 0 (parallel to
// the ray or zero area) is never hit; a hit counts when tmin < t < tmax and it is
// closer than the best so far, equal t going to the smaller (bvh, triangle) id. No
// offset is applied to the origin: callers set tmin or offset origins. Mirrored by
// cpu_ref::trace.
//
// The includer defines TRAVERSE_BINDING (first of six consecutive bindings) first.
#ifndef TRAVERSE_GLSL
#define TRAVERSE_GLSL
#include "bvh.glsl"

struct Hit {
    float t;    // distance along dir (in units of |dir|); tmax on a miss
    uint prim;  // triangle id, bit 31 set for the dynamic BVH; BVH_INVALID on a miss
    float u;    // barycentric weight of corner b
    float v;    // barycentric weight of corner c
};

layout(binding = TRAVERSE_BINDING + 0, std430) readonly buffer StaticNodes { BvhNode s_nodes[]; };
layout(binding = TRAVERSE_BINDING + 1, std430) readonly buffer StaticVertices { Vertex s_vertices[]; };
layout(binding = TRAVERSE_BINDING + 2, std430) readonly buffer StaticIndices { uint s_indices[]; };
layout(binding = TRAVERSE_BINDING + 3, std430) readonly buffer DynamicNodes { BvhNode d_nodes[]; };
layout(binding = TRAVERSE_BINDING + 4, std430) readonly buffer DynamicVertices { Vertex d_vertices[]; };
layout(binding = TRAVERSE_BINDING + 5, std430) readonly buffer DynamicIndices { uint d_indices[]; };

BvhNode fetch_node(uint bvh, uint i) {
    // Member-wise copies: glslang cannot select between two buffer struct loads.
    BvhNode nd;
    if (bvh == 0u) {
        nd.lo = s_nodes[i].lo; nd.left = s_nodes[i].left; nd.hi = s_nodes[i].hi; nd.right = s_nodes[i].right;
    } else {
        nd.lo = d_nodes[i].lo; nd.left = d_nodes[i].left; nd.hi = d_nodes[i].hi; nd.right = d_nodes[i].right;
    }
    return nd;
}

void fetch_triangle(uint bvh, uint t, out vec3 a, out vec3 b, out vec3 c) {
    if (bvh == 0u) {
        TRIANGLE_CORNERS(s_vertices, s_indices, t, sa, sb, sc)
        a = sa; b = sb; c = sc;
    } else {
        TRIANGLE_CORNERS(d_vertices, d_indices, t, da, db, dc)
        a = da; b = db; c = dc;
    }
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


// Vertex `k` (0..2) of hit triangle `prim` (bit 31: dynamic BVH).
Vertex hit_vertex(uint prim, uint k) {
    uint t = prim & 0x7fffffffu;
    if ((prim & 0x80000000u) == 0u) {
        return s_vertices[s_indices[3u * t + k]];
    }
    return d_vertices[d_indices[3u * t + k]];
}

// Traces one ray through both BVHs (a BVH with 0 triangles is skipped). Returns the
// closest hit, or with any_hit the first found; t = -1 if the stack overflowed.
Hit trace_ray(vec3 origin, vec3 dir, float tmin, float tmax, uint static_tris, uint dynamic_tris, bool any_hit) {
    // A zero direction component becomes a huge finite inverse (not inf: 0 * inf = NaN).
    vec3 safe_dir = mix(dir, vec3(1e-30), equal(dir, vec3(0.0)));
    vec3 inv_dir = 1.0 / safe_dir;
    Hit best = Hit(tmax, BVH_INVALID, 0.0, 0.0);
    bool overflow = false;
    uint stack[TRACE_STACK];

    for (uint bvh = 0u; bvh < 2u; ++bvh) {
        uint tris = bvh == 0u ? static_tris : dynamic_tris;
        if (tris == 0u || (any_hit && best.prim != BVH_INVALID)) {
            continue;
        }
        uint sp = 0u;
        uint node = 0u;
        BvhNode root = fetch_node(bvh, 0u);
        if (box_entry(root.lo, root.hi, origin, inv_dir, tmin, best.t) == 1.0 / 0.0) {
            continue;
        }
        while (true) {
            BvhNode nd = fetch_node(bvh, node);
            if ((nd.left & BVH_LEAF_BIT) != 0u) {
                uint t = nd.left & ~BVH_LEAF_BIT;
                vec3 a, b, c;
                fetch_triangle(bvh, t, a, b, c);
                vec3 e1 = b - a;
                vec3 e2 = c - a;
                vec3 p = cross(dir, e2);
                float det = dot(e1, p);
                if (det != 0.0) {
                    float inv_det = 1.0 / det;
                    vec3 s = origin - a;
                    float u = dot(s, p) * inv_det;
                    vec3 q = cross(s, e1);
                    float v = dot(dir, q) * inv_det;
                    float th = dot(e2, q) * inv_det;
                    uint id = t | (bvh << 31);
                    bool inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
                    bool closer = th < best.t || (th == best.t && id < best.prim);
                    if (inside && th > tmin && closer) {
                        best = Hit(th, id, u, v);
                        if (any_hit) {
                            break;
                        }
                    }
                }
            } else {
                BvhNode cl = fetch_node(bvh, nd.left);
                BvhNode cr = fetch_node(bvh, nd.right);
                float tl = box_entry(cl.lo, cl.hi, origin, inv_dir, tmin, best.t);
                float tr = box_entry(cr.lo, cr.hi, origin, inv_dir, tmin, best.t);
                bool hit_l = tl != 1.0 / 0.0;
                bool hit_r = tr != 1.0 / 0.0;
                if (hit_l && hit_r) {
                    uint near = tl <= tr ? nd.left : nd.right;
                    uint far = tl <= tr ? nd.right : nd.left;
                    if (sp < TRACE_STACK) {
                        stack[sp++] = far;
                    } else {
                        overflow = true;
                    }
                    node = near;
                    continue;
                } else if (hit_l || hit_r) {
                    node = hit_l ? nd.left : nd.right;
                    continue;
                }
            }
            if (sp == 0u) {
                break;
            }
            node = stack[--sp];
        }
    }
    if (overflow) {
        best = Hit(-1.0, BVH_INVALID, 0.0, 0.0); // reported as an error, never silently wrong
    }
    return best;
}
#endif
