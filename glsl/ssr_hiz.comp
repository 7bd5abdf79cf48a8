#version 460
// ssr.hiz: two levels of the min-depth pyramid (Hi-Z) that the hierarchical march steps
// through, per dispatch. Level 0 is the G-buffer depth itself; texel (x, y) of level
// k + 1 is the minimum (the nearest surface) of texels 2x..2x+1, 2y..2y+1 of level k,
// clamped to that level, whose sizes round up (ceil(w / 2)), so every texel has exactly
// one parent and a cell's value bounds every pixel it covers. Levels lie one after
// another in one buffer, row-major. One invocation per texel of level src + 2 reads
// the 4x4 texels of level src below it and writes the 2x2 of level src + 1 and the one
// of src + 2 (the first dispatch reads the depth image and writes level 0 too), so the
// pyramid takes half the dispatches and level src + 1 is never read back.
// CPU reference: cpu_ref::ssr::hiz (tests/ssr.rs), exactly.

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(binding = 0) uniform sampler2D gb_depth;
layout(binding = 1, std430) buffer Pyramid { float pyramid[]; };

layout(push_constant) uniform Push {
    uint src_offset;  // where level src starts in `pyramid` (0 and unused from depth)
    uint mid_offset;  // where level src + 1 starts
    uint top_offset;  // where level src + 2 starts
    uint from_depth;  // 1: level src is the depth image (and is written as level 0)
    uvec2 src_size;   // level src's size
    uvec2 mid_size;   // level src + 1's
    uvec2 top_size;   // level src + 2's (0 x 0: src + 1 is the last level)
                      // (mid_size 0 x 0: a 1x1 image, level 0 alone)
} pc;

float src_at(uvec2 p) {
    p = min(p, pc.src_size - 1u);
    return pc.from_depth != 0u ? texelFetch(gb_depth, ivec2(p), 0).r : pyramid[pc.src_offset + p.y * pc.src_size.x + p.x];
}

void main() {
    uvec2 t = gl_GlobalInvocationID.xy;
    // The grid covers the 4x4 blocks of level src (level src + 2, where there is one).
    if (any(greaterThanEqual(t, (pc.src_size + 3u) / 4u))) {
        return;
    }
    if (pc.from_depth != 0u) {
        for (uint j = 0u; j < 4u; ++j) {
            for (uint i = 0u; i < 4u; ++i) {
                uvec2 p = 4u * t + uvec2(i, j);
                if (all(lessThan(p, pc.src_size))) {
                    pyramid[p.y * pc.src_size.x + p.x] = texelFetch(gb_depth, ivec2(p), 0).r;
                }
            }
        }
    }
    float mids[4];
    for (uint k = 0u; k < 4u; ++k) {
        // Level src + 1's texel m (clamped to that level, as level src + 2 reads it).
        uvec2 m = min(2u * t + uvec2(k & 1u, k >> 1u), pc.mid_size - 1u);
        uvec2 a = 2u * m;
        mids[k] = min(min(src_at(a), src_at(a + uvec2(1u, 0u))), min(src_at(a + uvec2(0u, 1u)), src_at(a + 1u)));
        uvec2 own = 2u * t + uvec2(k & 1u, k >> 1u);
        if (all(lessThan(own, pc.mid_size))) {
            pyramid[pc.mid_offset + own.y * pc.mid_size.x + own.x] = mids[k];
        }
    }
    if (pc.top_size.x > 0u) {
        pyramid[pc.top_offset + t.y * pc.top_size.x + t.x] = min(min(mids[0], mids[1]), min(mids[2], mids[3]));
    }
}
