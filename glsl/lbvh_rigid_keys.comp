#version 460
// lbvh.morton of a rigid-body rebuild (passes/lbvh/rigid.rs): every triangle's key and
// slot, without sorting the triangles. Each body's triangles keep the order of their
// object-space keys (fixed: the body is rigid), computed once. A key is, from the top:
// the first `cell_bits` bits of its body's Morton code (the cell the body's center is
// in: the top levels split space, as a scene's LBVH does), its body's rank
// (`rank_bits`: bodies in one cell apart), and the triangle's object-space key (its
// size class and Morton code in the body) in the bits left. Slots follow the ranks, so
// the keys come out sorted and lbvh.fit builds the tree from them: the bodies' tree
// above, each body's subtree below.
// CPU reference: cpu_ref::lbvh::rigid_keys (tests/lbvh.rs).
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

// Per triangle (input order): (body, place in the body's order, local key, 0).
layout(binding = 0) uniform utextureBuffer tri_info;
// Per body: (rank, first slot, Morton code, 0), from lbvh_body_ranks.comp.
layout(binding = 1) uniform utextureBuffer places;
layout(binding = 2, std430) writeonly buffer Keys { uint keys[]; };
layout(binding = 3, std430) writeonly buffer Values { uint values[]; };

layout(push_constant) uniform Push {
    uint tri_count;
    uint rank_bits; // bits that hold every rank (0 for one body)
    uint cell_bits; // a multiple of 3, at most 30; rank_bits + cell_bits < 32
} pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.tri_count) {
        return;
    }
    uvec4 info = texelFetch(tri_info, int(t));
    uvec4 place = texelFetch(places, int(info.x));
    uint slot = place.y + info.y;
    uint top = pc.rank_bits + pc.cell_bits; // < 32
    uint cell = pc.cell_bits == 0u ? 0u : (place.z >> (30u - pc.cell_bits)) << (32u - pc.cell_bits);
    uint rank = pc.rank_bits == 0u ? 0u : place.x << (32u - top);
    keys[slot] = cell | rank | (info.z >> top);
    values[slot] = t;
}
