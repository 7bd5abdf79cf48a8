#version 460
// The vendor tracer's closest hit (trace_khr.glsl): the triangle's id in its
// geometry's numbering (HIT_DYNAMIC for the dynamic geometry), the distance and the
// barycentrics, as traverse.glsl's walk reports them.
#extension GL_EXT_ray_tracing : require
#include "hit.glsl"

layout(location = 0) rayPayloadInEXT Hit payload;
hitAttributeEXT vec2 bary;

void main() {
    uint c = gl_InstanceCustomIndexEXT;
    uint prim = (c & KHR_FIRST_TRIANGLE) + uint(gl_PrimitiveID);
    if ((c & KHR_DYNAMIC_INSTANCE) != 0u) {
        prim |= HIT_DYNAMIC;
    }
    payload = Hit(gl_HitTEXT, prim, bary.x, bary.y);
}
