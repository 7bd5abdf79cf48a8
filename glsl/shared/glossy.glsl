// Glossy reflections: which surfaces reflect a lobe, and the directions of its rays.
// Mirrored by cpu_ref::glossy (tests/suite/glossy.rs compares them on random inputs).
//
// A reflective surface of perceptual roughness r (GGX alpha = r^2) is
// - a mirror below frame.mirror_roughness: one ray, today's exact mirror direction;
// - glossy up to frame.rough_roughness: frame.reflection_rays rays per frame, each
//   reflecting the view about a microfacet normal drawn from the GGX distribution of
//   visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals",
//   JCGT 7(4)), by an R2 sequence (Roberts 2018) that advances with the frame, rotated
//   per pixel (Cranley-Patterson) by a hash;
// - rough from there on: no traced reflection (reflectivity 0 to every reflection pass);
//   its specular reflection is the prefiltered sky of shade_direct's ambient term.
// With frame.glossy 0 every reflective surface is a mirror and neither cut-off applies.
#ifndef GLOSSY_GLSL
#define GLOSSY_GLSL
#include "shading.glsl"

bool is_glossy(float roughness) {
    return frame.glossy != 0u && roughness >= frame.mirror_roughness && roughness < frame.rough_roughness;
}

// The reflectivity the reflection passes see: 0 past the rough cut-off (with glossy
// reflections on or off: such a surface's reflection is the prefiltered sky).
float traced_reflectivity(float reflectivity, float roughness) {
    return roughness >= frame.rough_roughness ? 0.0 : reflectivity;
}

// Rays a reflective pixel of this roughness takes per frame.
uint reflection_rays(float roughness) {
    return is_glossy(roughness) ? frame.reflection_rays : 1u;
}

// PCG's output permutation on a one-step LCG (Jarzynski & Olano 2020, "Hash Functions
// for GPU Rendering", pcg).
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A hash of pixel p and `seed` (the glossy rays' rotation, the denoiser's turn).
uint pixel_hash(ivec2 p, uint seed) {
    return pcg_hash(uint(p.x) + pcg_hash(uint(p.y) + pcg_hash(seed)));
}

// The pixel's rotation of the sequence, in 32-bit fixed point.
uvec2 sample_rotation(ivec2 p, uint stream) {
    uint h = pixel_hash(p, stream);
    return uvec2(h, pcg_hash(h));
}

// Sample k of the rotated R2 sequence in [0, 1)^2 (24 bits each: exact in f32).
vec2 r2_sample(uint k, uvec2 rotation) {
    uvec2 f = uvec2(k * R2_A1, k * R2_A2) + rotation;
    return vec2(f >> 8u) * (1.0 / 16777216.0);
}

// A microfacet normal in the frame whose z is the surface normal, for the unit view
// direction `ve` (z > 0) and GGX alpha: Heitz 2018, listing 1.
vec3 ggx_vndf(vec3 ve, float alpha, vec2 u) {
    vec3 vh = normalize(vec3(alpha * ve.x, alpha * ve.y, ve.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// An orthonormal basis (b1, b2, n) around unit n (Duff et al. 2017, "Building an
// Orthonormal Basis, Revisited").
void basis(vec3 n, out vec3 b1, out vec3 b2) {
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float b = n.x * n.y * a;
    b1 = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    b2 = vec3(b, sgn + n.y * n.y * a, -n.y);
}

// The hit distance of a reflection that met nothing (ssr.hit_distance).
#define HIT_FAR uintBitsToFloat(HIT_FAR_BITS)

// Tries at a direction above the surface before falling back to the mirror direction.
const uint GLOSSY_TRIES = 4u;

// The unit direction of glossy ray `s` of pixel p this frame: the view `v` (unit, towards
// the viewer) reflected about a VNDF-sampled microfacet normal of the unit normal `n`
// (facing v). A direction at or below the surface's plane is drawn again with the next
// rotation, up to GLOSSY_TRIES times, then the mirror direction is taken (always above
// the facet: clamp_bent_normal).
vec3 glossy_direction(ivec2 p, vec3 n, vec3 v, float roughness, uint s) {
    float alpha = max(roughness * roughness, 1e-4);
    vec3 b1, b2;
    basis(n, b1, b2);
    vec3 ve = vec3(dot(v, b1), dot(v, b2), max(dot(v, n), 1e-4));
    ve = normalize(ve);
    uint k = frame.frame_index * frame.reflection_rays + s;
    uvec2 rot = sample_rotation(p, frame.sample_stream);
    for (uint t = 0u; t < GLOSSY_TRIES; ++t) {
        vec3 h = ggx_vndf(ve, alpha, r2_sample(k, rot));
        vec3 l = reflect(-ve, h);
        if (l.z > 0.0) {
            return normalize(l.x * b1 + l.y * b2 + l.z * n);
        }
        rot = uvec2(pcg_hash(rot.x), pcg_hash(rot.y));
    }
    return reflect(-v, n);
}
#endif
