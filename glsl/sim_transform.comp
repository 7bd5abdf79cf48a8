#version 460
// sim.transform: the dynamic geometry's world-space vertices from its object-space
// ones and each body's pose (rigid transforms: the normal turns with the rotation).
// Mirrored by cpu_ref::sim::transform.
#include "types.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Objects { Vertex object_vertices[]; };
layout(binding = 1, std430) readonly buffer Poses { mat4 poses[]; };
layout(binding = 2, std430) writeonly buffer World { Vertex world_vertices[]; };

layout(push_constant) uniform Push {
    uint vertex_count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.vertex_count) {
        return;
    }
    Vertex v = object_vertices[i];
    mat4 m = poses[v.object];
    v.position = (m * vec4(v.position, 1.0)).xyz;
    v.normal = normalize(mat3(m) * v.normal);
    world_vertices[i] = v;
}
