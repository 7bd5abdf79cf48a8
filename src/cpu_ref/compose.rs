//! Reference of `glsl/compose.comp`.

use glam::Vec3;

/// Largest input `compose` tonemaps (the fit is flat at 1 beyond 7.24; the clamp keeps
/// x * x from overflowing f32 into NaN at absurd exposures).
pub const ACES_MAX: f32 = 1.0e4;

/// ACES filmic fit (Narkowicz 2015), clamped to [0, 1].
pub fn aces(x: Vec3) -> Vec3 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// The sRGB transfer function (IEC 61966-2-1).
pub fn srgb_encode(c: f32) -> f32 {
    if c > 0.0031308 {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    } else {
        c * 12.92
    }
}

/// One HDR texel to the RGBA8 value `compose` writes (alpha 255).
pub fn tonemap(hdr: [f32; 4], exposure: f32) -> [u8; 4] {
    let c = Vec3::new(hdr[0], hdr[1], hdr[2]).max(Vec3::ZERO) * exposure;
    // NaN-safe as the shader: NaN is black, the rest clamped to [0, ACES_MAX].
    let c = Vec3::select(c.is_nan_mask(), Vec3::ZERO, c).clamp(Vec3::ZERO, Vec3::splat(ACES_MAX));
    let m = aces(c);
    let q = |v: f32| (srgb_encode(v).clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(m.x), q(m.y), q(m.z), 255]
}
