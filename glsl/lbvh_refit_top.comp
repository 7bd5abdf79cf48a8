#version 460
// lbvh.refit (scheduled), last pass: one workgroup refits every remaining level (each
// at most REFIT_TOP_WG nodes: a level never holds more nodes than the one below it),
// level by level, a workgroup barrier between levels (bvh.glsl, REFIT_NODE).
// CPU reference: cpu_ref::lbvh::build of the same keys over the moved vertices, the
// scheduled refit as a whole (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = REFIT_TOP_WG) in;

layout(binding = 0, std430) coherent buffer TNodes { TraversalNode tnodes[]; };
layout(binding = 1, std430) readonly buffer Order { uint order[]; };
layout(binding = 2, std430) readonly buffer Levels { uvec2 levels[]; }; // (first, count)

layout(push_constant) uniform Push {
    uint first_level;
    uint level_count;
    uint n; // triangles
} pc;

void main() {
    uint i = gl_LocalInvocationID.x;
    for (uint k = pc.first_level; k < pc.level_count; ++k) {
        uvec2 lv = levels[k];
        if (i < lv.y) {
            uint slot = order[lv.x + i];
            REFIT_NODE(tnodes, slot)
        }
        // The next level reads this one's boxes.
        memoryBarrierBuffer();
        barrier();
    }
}
