#version 460
// lbvh.compact: the compact nodes of a built (or refit) BVH, what the walk of the
// static BVH reads (bvh.glsl: the layout, the grid over the root's box, the rounding
// outward). One invocation per internal node; the first also writes the header.
// Mirrored by cpu_ref::lbvh::compact_nodes (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0) uniform utextureBuffer nodes;
layout(binding = 1, std430) writeonly buffer Compact { uvec4 compact[]; };

layout(push_constant) uniform Push { uint node_count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    TraversalNode root = node_from_texels(nodes, 0u);
    vec3 g, st;
    compact_grid(min(root.lo0, root.lo1), max(root.hi0, root.hi1), g, st);
    if (i == 0u) {
        compact[0] = uvec4(floatBitsToUint(g), 0u);
        compact[1] = uvec4(floatBitsToUint(st), 0u);
    }
    TraversalNode n = node_from_texels(nodes, i);
    compact[2u + 2u * i] = compact_half(n.lo0, n.hi0, n.child0, g, st);
    compact[3u + 2u * i] = compact_half(n.lo1, n.hi1, n.child1, g, st);
}
