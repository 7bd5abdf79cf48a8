// BVH layout (src/gpu_types.rs: TraversalNode, TraversalTri), written by lbvh.fit,
// PLOC and the refit, read by the walk of the dynamic BVH (the static BVH's walk reads
// the compact nodes below, made from these). A BVH over N triangles is the binary radix tree of
// its sorted Morton keys (Karras 2012): N leaves in key order and N-1 internal nodes,
// each internal node stored with both children's boxes, so one 64-byte fetch tests both.
//
//   node:     | lo0 | child0 | hi0 | child1 | lo1 | parent | hi1 | unused |   64 bytes
//   triangle: | a | triangle id | b - a | parent | c - a | 0 |               48 bytes
//
// child: an internal node's slot, or a leaf: BVH_LEAF_BIT | (count - 1) <<
// BVH_LEAF_COUNT_SHIFT | the position of its first triangle in key order, its
// 1..BVH_LEAF_MAX triangles consecutive there.
// parent: the link to the half of the parent node that holds this node's box,
// slot << 1 | side (side 0: child0, 1: child1); BVH_INVALID at the root. `unused` is
// never written. Every internal node of the binary radix tree has its slot and links,
// also those inside a leaf of several triangles (out of the traversal's reach, their
// boxes kept by the refit). The internal node that splits keys p | p+1 sits in slot
//   0      for the root,
//   p + 1  when p is left of the root's split,
//   p      when p is right of it,
// so the root is slot 0 and the N-1 slots are dense. A single triangle has one node
// (slot 0) whose two children are that leaf, whose link is (0, side 0).
#ifndef BVH_GLSL
#define BVH_GLSL
#extension GL_EXT_samplerless_texture_functions : require
#include "types.glsl"

struct TraversalNode {
    vec3 lo0;
    uint child0;
    vec3 hi0;
    uint child1;
    vec3 lo1;
    uint parent;
    vec3 hi1;
    uint unused;
};

struct TraversalTri {
    vec3 a;
    uint id;
    vec3 b;
    uint parent;
    vec3 c;
    uint _pad0;
};

// A leaf's child reference: `count` triangles from key position `first`.
uint bvh_leaf_ref(uint first, uint count) {
    return BVH_LEAF_BIT | ((count - 1u) << BVH_LEAF_COUNT_SHIFT) | first;
}

// First triangle and count of a leaf's child reference.
uint bvh_leaf_first(uint ref) {
    return ref & ((1u << BVH_LEAF_COUNT_SHIFT) - 1u);
}
uint bvh_leaf_count(uint ref) {
    return ((ref & ~BVH_LEAF_BIT) >> BVH_LEAF_COUNT_SHIFT) + 1u;
}

// Surface area of a box, without contraction, in the order cpu_ref (Aabb::area) uses:
// the fit's leaf decisions are bit-exact on both sides.
float bvh_area(vec3 lo, vec3 hi) {
    vec3 d = hi - lo;
    precise float a = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    return a;
}

// The leaf rule of both builders (cpu_ref::lbvh::collapse, the same additions): a node
// of `count` triangles with this `area` and its children's SAH costs (left, right)
// becomes a leaf when its triangles are `one_run` in key order, it holds at most
// BVH_LEAF_MAX and that costs no more than the split (unit costs for a node step and
// a triangle test). Returns whether it does; `cost` gets the node's cost.
bool bvh_collapse(float area, float left_cost, float right_cost, uint count, bool one_run, out float cost) {
    precise float split = area + (left_cost + right_cost);
    precise float leaf = area * float(count);
    bool collapse = one_run && count <= BVH_LEAF_MAX && leaf <= split;
    cost = collapse ? leaf : split;
    return collapse;
}

// A box into one half of a node: child0's (side 0) or child1's (side 1). A macro on
// the includer's node buffer (GLSL cannot pass a buffer to a function).
#define STORE_HALF(tnodes, slot, side, lo, hi)                                           \
    if ((side) == 0u) {                                                                   \
        tnodes[slot].lo0 = (lo);                                                          \
        tnodes[slot].hi0 = (hi);                                                          \
    } else {                                                                              \
        tnodes[slot].lo1 = (lo);                                                          \
        tnodes[slot].hi1 = (hi);                                                          \
    }

// The refits' two steps on the includer's `tnodes` and `ttris` over n triangles.
// REFIT_LEAF: leaf j's triangle from the moved vertices, and its box into its parent's
// half (both halves for a single triangle).
#define REFIT_LEAF(vertices, indices, tnodes, ttris, j, n)                               \
    {                                                                                     \
        uint prim_ = ttris[j].id;                                                         \
        uint link_ = ttris[j].parent;                                                     \
        TRIANGLE_CORNERS(vertices, indices, prim_, a_, b_, c_)                            \
        ttris[j].a = a_;                                                                  \
        ttris[j].b = b_;                                                                  \
        ttris[j].c = c_;                                                                  \
        vec3 lo_ = min(a_, min(b_, c_)), hi_ = max(a_, max(b_, c_));                      \
        STORE_HALF(tnodes, link_ >> 1u, link_ & 1u, lo_, hi_)                             \
        if ((n) == 1u) {                                                                  \
            STORE_HALF(tnodes, 0u, 1u, lo_, hi_)                                          \
        }                                                                                 \
    }
// REFIT_UNION: an internal node's box, the union of its halves (lo0, hi0) and (lo1,
// hi1), into the half of its parent its `link` names (nothing for the root).
#define REFIT_UNION(tnodes, link, lo0, hi0, lo1, hi1)                                     \
    if ((link) != BVH_INVALID) {                                                          \
        vec3 lo_ = min(lo0, lo1), hi_ = max(hi0, hi1); /* once: STORE_HALF has 2 sides */ \
        STORE_HALF(tnodes, (link) >> 1u, (link) & 1u, lo_, hi_)                           \
    }
// REFIT_NODE: REFIT_UNION of internal node `slot`, read from `tnodes`.
#define REFIT_NODE(tnodes, slot)                                                          \
    {                                                                                     \
        uint link_ = tnodes[slot].parent;                                                 \
        REFIT_UNION(tnodes, link_, tnodes[slot].lo0, tnodes[slot].hi0, tnodes[slot].lo1,  \
                    tnodes[slot].hi1)                                                     \
    }

// Node `i` from a node buffer seen as texels of uvec4 (4 per node, in the layout
// above): what the walk and the refit's levels read. Texels, not a storage buffer:
// lavapipe fetches a texel for all lanes without a branch, where it loads a storage
// buffer one lane and one word at a time, each behind a branch.
TraversalNode node_from_texels(utextureBuffer nodes, uint i) {
    uvec4 w0 = texelFetch(nodes, int(4u * i));
    uvec4 w1 = texelFetch(nodes, int(4u * i + 1u));
    uvec4 w2 = texelFetch(nodes, int(4u * i + 2u));
    uvec4 w3 = texelFetch(nodes, int(4u * i + 3u));
    return TraversalNode(uintBitsToFloat(w0.xyz), w0.w, uintBitsToFloat(w1.xyz), w1.w, uintBitsToFloat(w2.xyz),
                         w2.w, uintBitsToFloat(w3.xyz), w3.w);
}

// The compact nodes (lbvh.compact, what the walk of the static BVH reads): each
// internal node's two halves as one 16-byte texel each, the child's box rounded
// outward to a grid of at most 65,535 steps an axis over the root's box, after a
// 2-texel header:
//
//   texel 0: grid origin g (f32 x3), 0     texel 1: grid step s (f32 x3), 0
//   texel 2 + 2i + side: | lo.x | lo.y | lo.z | hi.x | hi.y | hi.z | child |
//                         16-bit steps, two to a word; child as in the node
//
// A coordinate q steps up the grid is g + q * s: s is a power of two and q < 2^16, so
// q * s is exact and the one rounding is the addition's (a fused multiply-add gives
// the same). The step is at least 2 units in the last place of the grid's largest
// coordinate, so rounding never moves a coordinate by a whole step. Mirrored by
// cpu_ref::lbvh::{compact_grid, compact_half, compact_box}.
//
// The compressed wide layout (WIDE8 children, WIDE8_TEXELS texels a node after the same
// header; Ylitie, Karras & Laine 2017's quantization): node i at texel 2 + 6i,
//
//   texel 0: the node's grid origin (f32 x3, its children's lower corner), its steps'
//            exponent bytes (x | y << 8 | z << 16: each step a power of two)
//   texels 1-3: each child's box on that grid, 255 steps an axis, a byte a coordinate:
//            words lo.x[0-3], lo.x[4-7], lo.y.., lo.z.., hi.x.., hi.y.., hi.z..
//            (child j in byte j % 4)
//   texels 4-5: the children's links, BVH_INVALID for an unused slot
//
// Mirrored by cpu_ref::lbvh::{wide8_node, wide8_boxes}.

// The smallest power of two at least x (x >= 0, finite), at least the smallest normal.
float pow2_at_least(float x) {
    uint b = floatBitsToUint(x);
    uint e = b & 0x7f800000u;
    if (e == 0u) {
        return uintBitsToFloat(0x00800000u);
    }
    return uintBitsToFloat((b & 0x007fffffu) != 0u ? e + 0x00800000u : e);
}

// Two units in the last place of floats with x's exponent, at least the smallest
// normal.
float two_ulps(float x) {
    uint e = floatBitsToUint(x) & 0x7f800000u;
    return uintBitsToFloat(e >= (23u << 23) ? e - (22u << 23) : 0x00800000u);
}

// The grid over the box [lo, hi] (finite) with steps 0..top: origin lo, per axis the
// smallest power of two step whose top - 1 steps span the box and that is at least
// two_ulps of its largest coordinate (so step top lies beyond hi, rounded).
void grid_over(vec3 lo, vec3 hi, uint top, out vec3 g, out vec3 st) {
    g = lo;
    float span = float(top - 1u);
    for (int a = 0; a < 3; ++a) {
        precise float ext = hi[a] - lo[a];
        float s = pow2_at_least(ext * (1.0 / float(top + 1u)));
        s = s * span < ext ? 2.0 * s : s;
        st[a] = max(s, two_ulps(max(abs(lo[a]), abs(hi[a]))));
    }
}

// The last step of the compact nodes' 16-bit grid and of a compressed wide node's
// 8-bit one.
#define GRID16 65535u
#define GRID8 255u

// The compact nodes' grid over the root's box [lo, hi].
void compact_grid(vec3 lo, vec3 hi, out vec3 g, out vec3 st) {
    grid_over(lo, hi, GRID16, g, st);
}

// Grid coordinate q along an axis with origin g and step s.
float grid_at(uint q, float g, float s) {
    precise float p = g + float(q) * s;
    return p;
}

// (x - g) / s, in steps of the grid (s a power of two: 1 / s is exact).
float grid_units(float x, float g, float s) {
    float inv = uintBitsToFloat(0x7f000000u - floatBitsToUint(s));
    precise float d = (x - g) * inv;
    return d;
}

// The grid steps of x (g <= x, inside the grid's box of steps 0..top) rounded down
// (the largest q with grid_at(q) <= x) or up (the smallest with grid_at(q) >= x).
uint grid_down(float x, float g, float s, uint top) {
    uint q = uint(clamp(floor(grid_units(x, g, s)), 0.0, float(top)));
    for (int k = 0; k < 2 && q > 0u && grid_at(q, g, s) > x; ++k) {
        --q;
    }
    return grid_at(q, g, s) > x ? 0u : q;
}
uint grid_up(float x, float g, float s, uint top) {
    uint q = uint(clamp(ceil(grid_units(x, g, s)), 0.0, float(top)));
    for (int k = 0; k < 2 && q < top && grid_at(q, g, s) < x; ++k) {
        ++q;
    }
    return grid_at(q, g, s) < x ? top : q;
}

// One half of a compact node: the box [lo, hi] rounded outward and the child.
uvec4 compact_half(vec3 lo, vec3 hi, uint child, vec3 g, vec3 st) {
    uvec3 l = uvec3(grid_down(lo.x, g.x, st.x, GRID16), grid_down(lo.y, g.y, st.y, GRID16),
                    grid_down(lo.z, g.z, st.z, GRID16));
    uvec3 h = uvec3(grid_up(hi.x, g.x, st.x, GRID16), grid_up(hi.y, g.y, st.y, GRID16), grid_up(hi.z, g.z, st.z, GRID16));
    return uvec4(l.x | (l.y << 16u), l.z | (h.x << 16u), h.y | (h.z << 16u), child);
}

// The box of a compact half h on the grid (g, st), as the walk tests it (grid_at per
// coordinate). Mirrored by cpu_ref::lbvh::compact_box.
void compact_box(uvec4 h, vec3 g, vec3 st, out vec3 lo, out vec3 hi) {
    lo = g + vec3(uvec3(h.x & 0xffffu, h.x >> 16u, h.y & 0xffffu)) * st;
    hi = g + vec3(uvec3(h.y >> 16u, h.z & 0xffffu, h.z >> 16u)) * st;
}

// Spreads the low 10 bits of x to every third bit:
// ---- ---- ---- ---- ---- --98 7654 3210 -> ---- 9--8 --7- -6-- 5--4 --3- -2-- 1--0
uint expand_bits10(uint x) {
    x = (x | (x << 16)) & 0x030000ffu;
    x = (x | (x << 8)) & 0x0300f00fu;
    x = (x | (x << 4)) & 0x030c30c3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
}

// The per-axis scale that maps the box [lo, hi] onto [0, 1]: 1 / max(hi - lo, 1e-30).
// The one division of the Morton codes: Vulkan allows it 2.5 ULP (NVIDIA divides
// through a reciprocal), so a kernel whose codes are checked exactly stores the scale
// it used and the CPU reference multiplies by that (lbvh.morton). Mirrored by
// aabb::unit_scale.
vec3 unit_scale(vec3 lo, vec3 hi) {
    return 1.0 / max(hi - lo, vec3(1e-30));
}

// Point p's place in the box from `lo` with `scale` (unit_scale) as fractions in
// [0, 1] per axis; a flat axis gives 0. A subtraction and a multiplication, each
// rounded exactly and never fused. Mirrored by aabb::unit_at.
vec3 unit_at(vec3 p, vec3 lo, vec3 scale) {
    precise vec3 d = p - lo;
    precise vec3 u = d * scale;
    return clamp(u, 0.0, 1.0);
}

// The 30-bit Morton code (10 bits per axis, x most significant) of a point at `unit`
// (unit_at). Mirrored by aabb::morton30.
uint morton30(vec3 unit) {
    uvec3 q = uvec3(min(unit * 1024.0, vec3(1023.0)));
    return (expand_bits10(q.x) << 2) | (expand_bits10(q.y) << 1) | expand_bits10(q.z);
}

// Float <-> uint mapping that preserves order, so atomicMin/atomicMax on uint act as
// float min/max (negative floats: all bits flipped; positive: the sign bit set).
uint float_to_ordered(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
float ordered_to_float(uint u) {
    return uintBitsToFloat((u & 0x80000000u) != 0u ? (u & 0x7fffffffu) : ~u);
}

// The three indices of triangle `t` from an index buffer seen as texels of uvec4
// (tracers/lbvh: TriangleTexels; the buffer holds whole quads). Texels, not a storage
// buffer: lavapipe fetches a texel for all lanes without a branch, where it loads a
// storage buffer one lane and one word at a time, each behind a branch.
uvec3 triangle_indices(utextureBuffer indices, uint t) {
    uint w = 3u * t;
    uvec4 q0 = texelFetch(indices, int(w >> 2u));
    uvec4 q1 = texelFetch(indices, int((w + 2u) >> 2u)); // q0 when all three are in q0
    uint s = w & 3u;
    uvec3 r;
    r.x = q0[s];
    r.y = s < 3u ? q0[s + 1u] : q1[0];
    r.z = s < 2u ? q0[s + 2u] : q1[(s + 2u) & 3u];
    return r;
}

// The position of vertex `v` from a vertex buffer seen as texels of uvec4 (2 per
// Vertex, the position in the first's xyz).
vec3 vertex_position(utextureBuffer vertices, uint v) {
    return uintBitsToFloat(texelFetch(vertices, int(2u * v)).xyz);
}

// The three corners of triangle `t` from an indexed vertex buffer read as storage
// buffers (lbvh.bounds: its strided loop over 64 triangles a thread ran 2.4x as long
// at 1M triangles with the texel fetches below).
#define TRIANGLE_CORNERS_STORAGE(vertices, indices, t, a, b, c)                         \
    vec3 a = vertices[indices[3u * (t)]].position;                                      \
    vec3 b = vertices[indices[3u * (t) + 1u]].position;                                 \
    vec3 c = vertices[indices[3u * (t) + 2u]].position;

// The three corners of triangle `t` from its texel views (triangle_indices,
// vertex_position).
#define TRIANGLE_CORNERS(vertices, indices, t, a, b, c)                                 \
    uvec3 corner_ids_ = triangle_indices(indices, t);                                   \
    vec3 a = vertex_position(vertices, corner_ids_.x);                                  \
    vec3 b = vertex_position(vertices, corner_ids_.y);                                  \
    vec3 c = vertex_position(vertices, corner_ids_.z);
#endif
