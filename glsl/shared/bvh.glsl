// BVH node layout (src/gpu_types.rs: BvhNode), shared by the LBVH kernels and the
// traversal. A BVH over N triangles has 2N-1 nodes: internal nodes 0..N-2 (node 0 is
// the root), leaves N-1..2N-2 (for N = 1 the root is the single leaf).
//
//   node: | lo.x lo.y lo.z | left  | hi.x hi.y hi.z | right |   32 bytes
//   internal: left/right = child node indices
//   leaf:     left = BVH_LEAF_BIT | triangle id, right = BVH_INVALID
#ifndef BVH_GLSL
#define BVH_GLSL
#include "types.glsl"

struct BvhNode {
    vec3 lo;
    uint left;
    vec3 hi;
    uint right;
};

// Float <-> uint mapping that preserves order, so atomicMin/atomicMax on uint act as
// float min/max (negative floats: all bits flipped; positive: the sign bit set).
uint float_to_ordered(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
float ordered_to_float(uint u) {
    return uintBitsToFloat((u & 0x80000000u) != 0u ? (u & 0x7fffffffu) : ~u);
}

// The three corners of triangle `t` from an indexed vertex buffer.
#define TRIANGLE_CORNERS(vertices, indices, t, a, b, c)                                 \
    vec3 a = vertices[indices[3u * (t)]].position;                                      \
    vec3 b = vertices[indices[3u * (t) + 1u]].position;                                 \
    vec3 c = vertices[indices[3u * (t) + 2u]].position;
#endif
