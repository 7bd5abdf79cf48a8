#version 460
// ssr.hiz: one level of the min-depth pyramid (Hi-Z) that the hierarchical march steps
// through. Level 0 is the G-buffer depth itself; texel (x, y) of level k + 1 is the
// minimum (the nearest surface) of texels 2x..2x+1, 2y..2y+1 of level k, clamped to
// that level, whose sizes round up (ceil(w / 2)), so every texel has exactly one
// parent and a cell's value bounds every pixel it covers. Levels lie one after another
// in one buffer, row-major.
// CPU reference: cpu_ref::ssr::hiz (tests/ssr.rs), exactly.

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 0) uniform sampler2D gb_depth;
layout(binding = 1, std430) buffer Pyramid { float pyramid[]; };

layout(push_constant) uniform Push {
    uint src_offset;  // where level k starts in `pyramid` (unused for level 0)
    uint dst_offset;  // where the level written starts
    uvec2 src_size;   // level k's size (the depth image's for level 0)
    uvec2 dst_size;   // the written level's size
    uint from_depth;  // 1: write level 0, a copy of the depth image
    uint _pad0;
};

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, dst_size))) {
        return;
    }
    float d;
    if (from_depth != 0u) {
        d = texelFetch(gb_depth, ivec2(p), 0).r;
    } else {
        uvec2 a = 2u * p;
        uvec2 b = min(a + 1u, src_size - 1u);
        d = min(min(pyramid[src_offset + a.y * src_size.x + a.x], pyramid[src_offset + a.y * src_size.x + b.x]),
                min(pyramid[src_offset + b.y * src_size.x + a.x], pyramid[src_offset + b.y * src_size.x + b.x]));
    }
    pyramid[dst_offset + p.y * dst_size.x + p.x] = d;
}
