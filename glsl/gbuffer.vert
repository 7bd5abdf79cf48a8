#version 460
// gbuffer: transforms pulled vertices; passes world position, normal, texture
// coordinates, material and motion (the vertex's position the frame before, minus
// this frame's: 0 where `previous` is `vertices` itself).
#include "frame.glsl"

layout(binding = 1, std430) readonly buffer Vertices { Vertex vertices[]; };
layout(binding = 3, std430) readonly buffer Uvs { vec2 uvs[]; };
layout(binding = 5, std430) readonly buffer Previous { Vertex previous[]; };

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) flat out uint out_material;
layout(location = 3) out vec2 out_uv;
layout(location = 4) out vec3 out_motion;

void main() {
    Vertex v = vertices[gl_VertexIndex];
    out_world = v.position;
    out_normal = v.normal;
    out_material = v.material;
    out_uv = uvs[gl_VertexIndex];
    out_motion = previous[gl_VertexIndex].position - v.position;
    gl_Position = frame.view_proj * vec4(v.position, 1.0);
}
