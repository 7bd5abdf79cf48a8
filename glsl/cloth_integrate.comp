#version 460
// sim.cloth (integrate): Verlet with damping and gravity for every free particle.
// CPU reference: cpu_ref::cloth::integrate (tests/sim.rs).
#include "cloth.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) buffer Particles { Particle particles[]; };

layout(push_constant) uniform Push { CLOTH_PUSH_BLOCK } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.grid.x * pc.grid.y) {
        return;
    }
    Particle p = particles[i];
    if (p.inv_mass > 0.0) {
        vec3 velocity = (p.pos - p.prev) * pc.damping;
        p.prev = p.pos;
        p.pos = p.pos + velocity + vec3(0.0, -pc.gravity * pc.dt * pc.dt, 0.0);
    }
    particles[i] = p;
}
