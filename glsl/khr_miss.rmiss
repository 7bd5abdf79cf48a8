#version 460
// The vendor tracer's miss (trace_khr.glsl): no triangle, t = tmax.
#extension GL_EXT_ray_tracing : require
#include "hit.glsl"

layout(location = 0) rayPayloadInEXT Hit payload;

void main() {
    payload = Hit(gl_RayTmaxEXT, BVH_INVALID, 0.0, 0.0);
}
