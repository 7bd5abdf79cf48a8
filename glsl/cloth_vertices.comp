#version 460
// sim.cloth (vertices): the cloth's vertices in the dynamic vertex buffer, from the
// particles, with normals from the grid's central differences (one-sided at the edges).
// CPU reference: cpu_ref::cloth::vertices (tests/sim.rs).
#include "cloth.glsl"
#include "types.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Particles { Particle particles[]; };
layout(binding = 1, std430) writeonly buffer World { Vertex world_vertices[]; };

layout(push_constant) uniform Push { CLOTH_PUSH_BLOCK } pc;

vec3 at(int x, int y) {
    return particles[uint(y) * pc.grid.x + uint(x)].pos;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.grid.x * pc.grid.y) {
        return;
    }
    int x = int(i % pc.grid.x), y = int(i / pc.grid.x);
    int gx = int(pc.grid.x) - 1, gy = int(pc.grid.y) - 1;
    vec3 du = at(min(x + 1, gx), y) - at(max(x - 1, 0), y);
    vec3 dv = at(x, min(y + 1, gy)) - at(x, max(y - 1, 0));
    vec3 n = cross(dv, du);
    float len = length(n);
    Vertex v;
    v.position = particles[i].pos;
    v.material = pc.material;
    v.normal = len > 1e-12 ? n / len : vec3(0.0, 1.0, 0.0);
    v.object = 0u;
    world_vertices[pc.vertex_base + i] = v;
}
