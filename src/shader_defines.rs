// Constants shared by Rust and GLSL, defined here once.
//
// build.rs `include!`s this file and passes every entry of `SHADER_DEFINES` to shaderc
// as a `#define`, so a GLSL kernel and the Rust code that dispatches it can never
// disagree. (Plain `//` comments only: this file is also compiled inside build.rs.)

/// Edge of the square workgroup of every 2D image kernel. 8x8 = 64 invocations is a
/// whole number of subgroups on lavapipe (8 wide) and NVIDIA (32 wide); larger groups
/// help little for these bandwidth-bound passes and hurt occupancy on small images.
pub const WG_2D: u32 = 8;

/// Material id written to the G-buffer where no geometry covers the pixel (the sky).
/// Real materials are numbered from 0, so later passes test `id == MATERIAL_NONE`.
pub const MATERIAL_NONE: u32 = 0xffff_ffff;

/// Largest PCF kernel radius in shadow-map texels that `light.direct` accepts: the
/// (2r+1)^2 taps bound the cost of the shadow lookup per pixel.
pub const MAX_PCF_RADIUS: u32 = 4;

/// Every constant above, as `(name, value)`, in the form build.rs hands to shaderc.
pub const SHADER_DEFINES: &[(&str, u32)] = &[
    ("WG_2D", WG_2D),
    ("MATERIAL_NONE", MATERIAL_NONE),
    ("MAX_PCF_RADIUS", MAX_PCF_RADIUS),
];
