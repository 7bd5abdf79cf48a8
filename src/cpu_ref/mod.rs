//! CPU references of the GPU kernels, written to mirror the GLSL line by line. Tests
//! and benchmarks compare GPU output against these.

pub mod cloth;
pub mod compact;
pub mod compose;
pub mod denoise;
pub mod glossy;
pub mod lbvh;
pub mod merge;
pub mod primary;
pub mod reflect;
pub mod shading;
pub mod shadows;
pub mod sim;
pub mod ssr;
pub mod texture;
pub mod trace;
pub mod walk;

/// A G-buffer base-colour texel (`gbuffer::ALBEDO_FORMAT`) as the shaders decode it
/// (`srgb_decode`): linear base colour and roughness.
pub fn albedo_texel(t: &[u8]) -> (glam::Vec3, f32) {
    use crate::scene::texture::srgb_to_linear;
    let rgb = glam::Vec3::new(srgb_to_linear(t[0]), srgb_to_linear(t[1]), srgb_to_linear(t[2]));
    (rgb, t[3] as f32 / 255.0)
}

/// Encodes RGBA f32 texels as tightly packed RGBA16F (round to nearest).
pub fn f32_to_rgba16f(texels: &[[f32; 4]]) -> Vec<u8> {
    texels
        .iter()
        .flat_map(|t| t.iter().flat_map(|&c| half::f16::from_f32(c).to_le_bytes()))
        .collect()
}
