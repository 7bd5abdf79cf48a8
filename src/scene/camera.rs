//! A pinhole camera with position, look-at target and vertical field of view.

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// A perspective camera. Units are the scene's world units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Near and far clip distances.
    pub near: f32,
    pub far: f32,
}

/// The farthest a camera may stand from the origin (units): scenes are refused beyond
/// this span too (f32 precision).
pub const MAX_COORDINATE: f32 = 1e7;
/// The narrowest vertical field of view (degrees): below it the projection degenerates.
pub const MIN_FOV_DEG: f32 = 0.01;

impl Camera {
    /// What the passes rely on, whatever the camera came from (a scene file, a model's
    /// default view, the command line): finite coordinates within `MAX_COORDINATE`, a
    /// target apart from the position and off the up axis, a field of view in
    /// [`MIN_FOV_DEG`, 180), 0 < near < far, both finite. The error is one sentence.
    pub fn check(&self) -> Result<(), String> {
        for (what, p) in [("position", self.position), ("target", self.target)] {
            if !p.is_finite() {
                return Err(format!("the camera {what} {p} is not finite"));
            }
            if p.abs().max_element() > MAX_COORDINATE {
                return Err(format!(
                    "the camera {what} {p} is beyond {MAX_COORDINATE:e} units from the origin (f32 precision)"
                ));
            }
        }
        if !(self.fov_y_deg >= MIN_FOV_DEG && self.fov_y_deg < 180.0) {
            return Err(format!(
                "the camera's field of view {} is outside [{MIN_FOV_DEG}, 180) degrees",
                self.fov_y_deg
            ));
        }
        if !(self.near > 0.0 && self.near.is_finite() && self.far.is_finite() && self.far > self.near) {
            return Err(format!(
                "the camera's near {} and far {} must be finite with 0 < near < far",
                self.near, self.far
            ));
        }
        let dir = self.target - self.position;
        if dir.length() < 1e-6 * self.position.length().max(1.0) {
            return Err(format!(
                "the camera's position and target are the same point ({})",
                self.position
            ));
        }
        if !self.up.is_finite() || dir.normalize().cross(self.up.normalize_or_zero()).length() < 1e-4 {
            return Err("the camera looks straight along its up axis (y): tilt its target a little".into());
        }
        Ok(())
    }

    /// World → view (right-handed, looking down -z).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.position, self.target, self.up)
    }

    /// View → Vulkan clip space: depth 0..1, y pointing down in the image.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::vulkan::perspective(self.fov_y_deg.to_radians(), aspect, self.near, self.far)
    }

    /// World → clip.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// A camera that frames a bounding box from the front and a little above.
    pub fn framing(min: Vec3, max: Vec3) -> Self {
        let center = 0.5 * (min + max);
        let radius = (0.5 * (max - min).length()).max(1e-3);
        let fov_y_deg = 50.0f32;
        let distance = radius / (0.5 * fov_y_deg.to_radians()).sin();
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        Self {
            position: center + dir * distance,
            target: center,
            up: Vec3::Y,
            fov_y_deg,
            near: (distance - radius).max(distance * 1e-3),
            far: distance + radius * 2.0,
        }
    }
}
