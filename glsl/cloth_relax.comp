#version 460
// sim.cloth (relax): one Jacobi iteration of the distance constraints (structural,
// shear, bend), read from `src` and written to `dst`, then the colliders (spheres, the
// floor plane) push the particle out. Each particle moves by the mean of its
// constraints' corrections times the stiffness; pinned particles do not move.
// CPU reference: cpu_ref::cloth::relax (tests/sim.rs).
#include "cloth.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Src { Particle src[]; };
layout(binding = 1, std430) writeonly buffer Dst { Particle dst[]; };
layout(binding = 2, std430) readonly buffer Spheres { vec4 spheres[]; };

layout(push_constant) uniform Push { CLOTH_PUSH_BLOCK } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint n = pc.grid.x * pc.grid.y;
    if (i >= n) {
        return;
    }
    Particle p = src[i];
    if (p.inv_mass > 0.0) {
        ivec2 at = ivec2(int(i % pc.grid.x), int(i / pc.grid.x));
        vec3 sum = vec3(0.0);
        float count = 0.0;
        for (int k = 0; k < 12; ++k) {
            ivec2 q = at + CLOTH_NEIGHBOURS[k];
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.grid)))) {
                continue;
            }
            Particle o = src[uint(q.y) * pc.grid.x + uint(q.x)];
            vec3 d = o.pos - p.pos;
            float len = length(d);
            float w = p.inv_mass / (p.inv_mass + o.inv_mass);
            if (len > 1e-9) {
                sum += d * ((len - CLOTH_REST[k] * pc.spacing) / len * w);
            }
            count += 1.0;
        }
        if (count > 0.0) {
            p.pos += sum * (pc.stiffness / count);
        }
        for (uint s = 0u; s < pc.sphere_count; ++s) {
            vec3 c = spheres[s].xyz;
            float r = spheres[s].w + pc.margin;
            vec3 d = p.pos - c;
            float len = length(d);
            if (len < r && len > 1e-9) {
                p.pos = c + d * (r / len);
            }
        }
        p.pos.y = max(p.pos.y, pc.floor_y + pc.margin);
    }
    dst[i] = p;
}
