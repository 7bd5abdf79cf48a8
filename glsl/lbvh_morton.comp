#version 460
// lbvh.morton: Morton code of each triangle's center, quantized in the center
// bounds; values start as the triangle ids. 30-bit codes (10 bits per axis) in one
// word, or 63-bit codes (21 bits per axis) in two words, low word first. The key's
// spare top bits (2 above a 30-bit code, 1 above a 63-bit one) hold the triangle's
// size class against the scene (after the extended Morton codes of Vinkler et al.
// 2017): the hierarchy splits large triangles (a wall, a floor) from small ones
// first, so the small ones' subtrees are not stretched to the walls' extent.
// Mirrored by cpu_ref::lbvh::{morton30, morton63, size_class}.
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

// The triangles' vertices and indices as texels (bvh.glsl: TRIANGLE_CORNERS).
layout(binding = 0) uniform utextureBuffer vertices;
layout(binding = 1) uniform utextureBuffer indices;
// Centroid bounds (0-5) and scene bounds (6-11) as ordered uints; this kernel stores the
// unit_scale of the centroid bounds it quantizes with (12-14, float bits), so the CPU
// reference multiplies by the GPU's own quotient.
layout(binding = 2, std430) buffer Bounds { uint bounds[15]; };
layout(binding = 3, std430) writeonly buffer Keys { uint keys[]; };
layout(binding = 4, std430) writeonly buffer Values { uint values[]; };

layout(push_constant) uniform Push {
    uint tri_count;
    uint key_words; // 1: 30-bit codes, 2: 63-bit codes
} pc;

// The size class of a triangle whose box has squared diagonal d2, in a scene whose box
// has squared diagonal s2: with 2 bits 0 (a diagonal of at least half the scene's), 1
// (a quarter), 2 (an eighth) or 3; with 1 bit 0 (a quarter) or 1.
uint size_class(float d2, float s2, uint bits) {
    if (bits == 1u) {
        return d2 >= s2 * 0.0625 ? 0u : 1u;
    }
    return d2 >= s2 * 0.25 ? 0u : (d2 >= s2 * 0.0625 ? 1u : (d2 >= s2 * 0.015625 ? 2u : 3u));
}

// Squared length of v, in this order and unfused (the CPU computes the same float).
float squared_length(vec3 v) {
    precise float x = v.x * v.x;
    precise float y = v.y * v.y;
    precise float z = v.z * v.z;
    precise float s = x + y + z;
    return s;
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.tri_count) {
        return;
    }
    TRIANGLE_CORNERS(vertices, indices, t, a, b, c)
    precise vec3 center = (a + b + c) * (1.0 / 3.0);
    vec3 lo = vec3(ordered_to_float(bounds[0]), ordered_to_float(bounds[1]), ordered_to_float(bounds[2]));
    vec3 hi = vec3(ordered_to_float(bounds[3]), ordered_to_float(bounds[4]), ordered_to_float(bounds[5]));
    vec3 scale = unit_scale(lo, hi);
    if (t == 0u) {
        bounds[12] = floatBitsToUint(scale.x);
        bounds[13] = floatBitsToUint(scale.y);
        bounds[14] = floatBitsToUint(scale.z);
    }
    vec3 unit = unit_at(center, lo, scale);
    vec3 s_lo = vec3(ordered_to_float(bounds[6]), ordered_to_float(bounds[7]), ordered_to_float(bounds[8]));
    vec3 s_hi = vec3(ordered_to_float(bounds[9]), ordered_to_float(bounds[10]), ordered_to_float(bounds[11]));
    float d2 = squared_length(max(a, max(b, c)) - min(a, min(b, c)));
    float s2 = squared_length(s_hi - s_lo);
    if (pc.key_words == 1u) {
        keys[t] = (size_class(d2, s2, 2u) << 30) | morton30(unit);
    } else {
        uvec3 q = uvec3(min(unit * 2097152.0, vec3(2097151.0)));
        // Bit 3b+2 of the code is bit b of x, 3b+1 of y, 3b of z (x most significant).
        uvec2 code = uvec2(0u);
        for (uint b = 0u; b < 21u; ++b) {
            for (uint axis = 0u; axis < 3u; ++axis) {
                uint bit = (q[axis] >> b) & 1u;
                uint pos = 3u * b + (2u - axis);
                if (pos < 32u) {
                    code.x |= bit << pos;
                } else {
                    code.y |= bit << (pos - 32u);
                }
            }
        }
        keys[2u * t] = code.x;
        keys[2u * t + 1u] = code.y | (size_class(d2, s2, 1u) << 31);
    }
    values[t] = t;
}
