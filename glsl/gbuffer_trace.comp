#version 460
// gbuffer.trace: the G-buffer by one primary ray a pixel through Speculum's BVHs
// (primary.glsl says what each texel holds), one invocation a pixel in 8x8 tiles.
// CPU reference: cpu_ref::primary::gbuffer_texel (tests/suite/gbuffer.rs).
#include "frame.glsl"
#define TRAVERSE_BINDING 8
#include "traverse.glsl"
#include "primary.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(p, ivec2(frame.resolution)))) {
        primary_pixel(p);
    }
}
