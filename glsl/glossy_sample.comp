#version 460
// A test kernel, in no frame: glossy_direction (glossy.glsl) of each case, so the
// directions every glossy ray takes can be checked against cpu_ref::glossy on random
// inputs (tests/suite/glossy.rs).
#include "glossy.glsl"
layout(local_size_x = 64) in;
// Per case three vec4: (normal, roughness), (view, sample index), (pixel x, y, -, -).
layout(binding = 1, std430) readonly buffer Cases { vec4 cases[]; };
layout(binding = 2, std430) writeonly buffer Directions { vec4 directions[]; };
layout(push_constant) uniform Push {
    uint count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    vec4 a = cases[3u * i], b = cases[3u * i + 1u], c = cases[3u * i + 2u];
    vec3 d = glossy_direction(ivec2(c.xy), a.xyz, b.xyz, a.w, uint(b.w));
    directions[i] = vec4(d, 0.0);
}
