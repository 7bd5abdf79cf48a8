// A ray's hit, as both tracers return it (traverse.glsl's walk, trace_khr.glsl's
// vendor trace) and gpu_types::Hit mirrors.
#ifndef HIT_GLSL
#define HIT_GLSL
struct Hit {
    float t;    // distance along dir (in units of |dir|); tmax on a miss
    uint prim;  // triangle id, HIT_DYNAMIC set for the dynamic geometry; BVH_INVALID on a miss
    float u;    // barycentric weight of corner b
    float v;    // barycentric weight of corner c
};

// A vendor-tracer instance's custom index (24 bits): KHR_DYNAMIC_INSTANCE marks the
// dynamic geometry; the low 23 bits are the index, in its geometry's numbering, of the
// instance's first triangle (the BLAS's primitive 0).
const uint KHR_DYNAMIC_INSTANCE = 0x800000u;
const uint KHR_FIRST_TRIANGLE = 0x7fffffu;
#endif
