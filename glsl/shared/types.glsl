// Structs shared with Rust: src/gpu_types.rs. Offsets are checked by tests/layout.rs.
#ifndef TYPES_GLSL
#define TYPES_GLSL

struct Vertex {
    vec3 position;
    uint material;
    vec3 normal;
    uint object; // dynamic geometry: the body's index; 0 in static geometry
};

// A skinned vertex's joints (four 16-bit indices, two to a uint, low half first) and
// their weights (sim.skin normalizes them by their sum).
struct Influence {
    uvec2 joints;
    uvec2 pad;
    vec4 weights;
};

struct Material {
    vec3 albedo;
    float roughness;
    float reflectivity;
    uint texture_layer; // TEXTURE_NONE: untextured
    float metallic;     // 0: dielectric, 1: metal (the base colour is its reflectance)
    uint roughness_layer; // green channel (linear data) x roughness; TEXTURE_NONE: none
};

#define FRAME_UNIFORMS_BLOCK                                                         \
    mat4 view_proj;                                                                   \
    mat4 inv_view_proj;                                                               \
    mat4 light_view_proj;                                                             \
    mat4 view;                                                                        \
    mat4 proj;                                                                        \
    vec4 camera_pos;                                                                  \
    vec4 light_dir;                                                                   \
    vec4 light_color;                                                                 \
    vec4 sky_zenith;                                                                  \
    vec4 sky_horizon;                                                                 \
    uvec2 resolution;                                                                 \
    uint shadow_map_size;                                                             \
    uint pcf_radius;                                                                  \
    float shadow_bias;                                                                \
    float exposure;                                                                   \
    float ambient;                                                                    \
    float shadow_band;                                                                \
    uint frame_index;                                                                 \
    uint reflection_rays;                                                             \
    float mirror_roughness;                                                           \
    float rough_roughness;                                                            \
    uint sample_stream;                                                               \
    uint glossy;                                                                      \
    uint _pad0;                                                                       \
    uint _pad1;

#endif
