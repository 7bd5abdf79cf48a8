// Cloth: a grid of particles stepped by position-based dynamics on the GPU (sim.cloth).
// Mirrored by cpu_ref::cloth; change both together.
#ifndef CLOTH_GLSL
#define CLOTH_GLSL

struct Particle {
    vec3 pos;
    float inv_mass; // 0: pinned
    vec3 prev;      // the position a step ago (Verlet)
    float _pad0;
};

// One step's constants, shared by the cloth kernels.
#define CLOTH_PUSH_BLOCK                                                               \
    uvec2 grid;        /* particles along u and v */                                   \
    float dt;          /* seconds per step */                                          \
    float gravity;     /* along -y, units per second squared */                        \
    float damping;     /* kept fraction of the velocity per step */                    \
    float spacing;     /* rest distance of grid neighbours */                          \
    float stiffness;   /* Jacobi relaxation factor in (0, 1] */                        \
    float floor_y;     /* a plane the cloth stays above */                             \
    float margin;      /* distance kept from colliders */                              \
    uint sphere_count; /* colliders in the Spheres buffer (xyz centre, w radius) */    \
    uint vertex_base;  /* where the cloth's vertices start in the dynamic buffer */    \
    uint material;

// Neighbour offsets and rest-length multiples: structural, shear and bend springs.
const ivec2 CLOTH_NEIGHBOURS[12] = ivec2[12](
    ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1),
    ivec2(1, 1), ivec2(-1, -1), ivec2(1, -1), ivec2(-1, 1),
    ivec2(2, 0), ivec2(-2, 0), ivec2(0, 2), ivec2(0, -2));
const float CLOTH_REST[12] = float[12](
    1.0, 1.0, 1.0, 1.0,
    1.41421356, 1.41421356, 1.41421356, 1.41421356,
    2.0, 2.0, 2.0, 2.0);
#endif
