#version 460
// sim.skin: linear blend skinning. Each skinned vertex's world-space position is the
// blend of its (up to four) joints' skinning matrices, weighted by its influences
// divided by their sum, applied to its bind-pose position; its normal goes through
// the blend's inverse transpose (non-uniform scale) and is renormalized. A vertex
// whose weights sum to zero keeps its bind pose. Joint matrices come from the host
// (scene::animation::Rig::joint_matrices). Mirrored by scene::animation::skin_vertex.
#include "types.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Objects { Vertex object_vertices[]; };
layout(binding = 1, std430) readonly buffer Influences { Influence influences[]; };
layout(binding = 2, std430) readonly buffer Joints { mat4 joints[]; };
layout(binding = 3, std430) writeonly buffer World { Vertex world_vertices[]; };

layout(push_constant) uniform Push {
    uint vertex_count;
    // Where the first vertex goes in the world vertices.
    uint first;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.vertex_count) {
        return;
    }
    Vertex v = object_vertices[i];
    Influence f = influences[i];
    float total = f.weights.x + f.weights.y + f.weights.z + f.weights.w;
    if (total > 0.0) {
        uint j[4] = uint[4](f.joints.x & 0xffffu, f.joints.x >> 16, f.joints.y & 0xffffu, f.joints.y >> 16);
        mat4 m = mat4(0.0);
        for (int k = 0; k < 4; ++k) {
            if (f.weights[k] != 0.0) {
                m += joints[j[k]] * (f.weights[k] / total);
            }
        }
        v.position = (m * vec4(v.position, 1.0)).xyz;
        vec3 n = transpose(inverse(mat3(m))) * v.normal;
        float len = length(n);
        v.normal = len > 0.0 ? n / len : v.normal;
    }
    world_vertices[pc.first + i] = v;
}
