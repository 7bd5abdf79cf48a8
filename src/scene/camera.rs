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

impl Camera {
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
