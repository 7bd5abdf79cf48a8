#version 460
// shadow.map: depth-only raster from the light. Vertices are pulled from a buffer.
#include "frame.glsl"

layout(binding = 1, std430) readonly buffer Vertices { Vertex vertices[]; };

void main() {
    gl_Position = frame.light_view_proj * vec4(vertices[gl_VertexIndex].position, 1.0);
}
