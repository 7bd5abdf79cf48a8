//! A scene file's `[[instance]]`: what it places (a primitive or a model), where (its
//! transform), and how an animated model among them plays.

use super::animated::{Animated, Choice};
use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// What an instance places: exactly one of the shape keys.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Instance {
    /// A rectangle [width, depth] in the xz-plane facing +y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<[f32; 2]>,
    /// A box of these full extents, centred.
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub cuboid: Option<[f32; 3]>,
    /// A UV sphere of this radius (`segments` around, 3..=1024, `rings` pole to pole,
    /// 2..=512).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rings: Option<u32>,
    /// A model file (OBJ with its MTL, or PLY), relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// A material of `materials` by name: required for primitives; for a model it
    /// replaces every material of the file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f32; 3]>,
    /// Degrees about x, then y, then z.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<[f32; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Scale>,
    /// A glTF model's animation to play, by index or name (default: its first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<Choice>,
    /// Seconds of animation per second of scene time (default 1; negative plays it
    /// backwards).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f32>,
    /// Whether the animation starts over at its end (default true), or holds its last
    /// pose.
    #[serde(default, rename = "loop", skip_serializing_if = "Option::is_none")]
    pub looping: Option<bool>,
}

/// Uniform or per-axis scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

impl Instance {
    /// `translate * Rz * Ry * Rx * scale`; factors that are the identity are left out,
    /// so a plain translation is exactly `Mat4::from_translation`.
    pub fn transform(&self) -> Mat4 {
        let mut m = Mat4::IDENTITY;
        if let Some(t) = self.translate {
            m = Mat4::from_translation(Vec3::from(t));
        }
        if let Some([x, y, z]) = self.rotate {
            for (angle, rot) in [
                (z, Mat4::from_rotation_z as fn(f32) -> Mat4),
                (y, Mat4::from_rotation_y),
                (x, Mat4::from_rotation_x),
            ] {
                if angle != 0.0 {
                    m *= rot(angle.to_radians());
                }
            }
        }
        match self.scale {
            Some(Scale::Uniform(s)) if s != 1.0 => m *= Mat4::from_scale(Vec3::splat(s)),
            Some(Scale::Axes(s)) if s != [1.0; 3] => m *= Mat4::from_scale(Vec3::from(s)),
            _ => {}
        }
        m
    }
}

/// How an instance's animated model plays: its `animation`, `speed` and `loop`.
pub(super) fn plays_as(a: &mut Animated, inst: &Instance) -> std::result::Result<(), String> {
    if let Some(choice) = &inst.animation {
        a.select(choice)?;
    }
    if let Some(speed) = inst.speed {
        if !speed.is_finite() {
            return Err(format!("speed {speed} is not finite"));
        }
        a.speed = speed;
    }
    a.looping = inst.looping.unwrap_or(a.looping);
    Ok(())
}
