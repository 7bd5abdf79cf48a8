#version 460
// rt.trace: closest-hit (or any-hit) traversal of two BVHs, static and dynamic, for a
// list of rays. Stack-based, nearest child first. Ray/triangle test: Moller-Trumbore,
// double-sided. Epsilon policy: a triangle whose determinant is exactly 0 (parallel
// to the ray or zero area) is never hit; a hit counts when tmin < t < tmax and it is
// closer than the best so far, equal t going to the smaller (bvh, triangle) id. No
// offset is applied to the origin: callers set tmin (or offset origins) to avoid
// self-intersection. Mirrored by cpu_ref::trace.
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

struct Ray {
    vec3 origin;
    float tmin;
    vec3 dir;
    float tmax;
};

struct Hit {
    float t;    // distance along dir (in units of |dir|); tmax on a miss
    uint prim;  // triangle id, bit 31 set for the dynamic BVH; BVH_INVALID on a miss
    float u;    // barycentric weight of corner b
    float v;    // barycentric weight of corner c
};

layout(binding = 0, std430) readonly buffer Rays { Ray rays[]; };
layout(binding = 1, std430) writeonly buffer Hits { Hit hits[]; };
layout(binding = 2, std430) readonly buffer StaticNodes { BvhNode s_nodes[]; };
layout(binding = 3, std430) readonly buffer StaticVertices { Vertex s_vertices[]; };
layout(binding = 4, std430) readonly buffer StaticIndices { uint s_indices[]; };
layout(binding = 5, std430) readonly buffer DynamicNodes { BvhNode d_nodes[]; };
layout(binding = 6, std430) readonly buffer DynamicVertices { Vertex d_vertices[]; };
layout(binding = 7, std430) readonly buffer DynamicIndices { uint d_indices[]; };

layout(push_constant) uniform Push {
    uint ray_count;
    uint static_tris;  // 0: no static BVH
    uint dynamic_tris; // 0: no dynamic BVH
    uint any_hit;      // 1: stop at the first hit (shadow rays)
} pc;

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

void main() {
    uint r = gl_GlobalInvocationID.x;
    if (r >= pc.ray_count) {
        return;
    }
    Ray ray = rays[r];
    // A zero direction component becomes a huge finite inverse (not inf: 0 * inf = NaN).
    vec3 safe_dir = mix(ray.dir, vec3(1e-30), equal(ray.dir, vec3(0.0)));
    vec3 inv_dir = 1.0 / safe_dir;
    Hit best = Hit(ray.tmax, BVH_INVALID, 0.0, 0.0);
    bool overflow = false;
    uint stack[TRACE_STACK];

    for (uint bvh = 0u; bvh < 2u; ++bvh) {
        uint tris = bvh == 0u ? pc.static_tris : pc.dynamic_tris;
        if (tris == 0u || (pc.any_hit != 0u && best.prim != BVH_INVALID)) {
            continue;
        }
        uint sp = 0u;
        uint node = 0u;
        BvhNode root = fetch_node(bvh, 0u);
        if (box_entry(root.lo, root.hi, ray.origin, inv_dir, ray.tmin, best.t) == 1.0 / 0.0) {
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
                vec3 p = cross(ray.dir, e2);
                float det = dot(e1, p);
                if (det != 0.0) {
                    float inv_det = 1.0 / det;
                    vec3 s = ray.origin - a;
                    float u = dot(s, p) * inv_det;
                    vec3 q = cross(s, e1);
                    float v = dot(ray.dir, q) * inv_det;
                    float th = dot(e2, q) * inv_det;
                    uint id = t | (bvh << 31);
                    bool inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
                    bool closer = th < best.t || (th == best.t && id < best.prim);
                    if (inside && th > ray.tmin && closer) {
                        best = Hit(th, id, u, v);
                        if (pc.any_hit != 0u) {
                            break;
                        }
                    }
                }
            } else {
                BvhNode cl = fetch_node(bvh, nd.left);
                BvhNode cr = fetch_node(bvh, nd.right);
                float tl = box_entry(cl.lo, cl.hi, ray.origin, inv_dir, ray.tmin, best.t);
                float tr = box_entry(cr.lo, cr.hi, ray.origin, inv_dir, ray.tmin, best.t);
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
    hits[r] = best;
}
