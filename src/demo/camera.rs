//! The demo's fly camera: WASD to move in the view plane, Q/E down and up, the mouse
//! (right button held) to look, the scroll wheel for speed. It starts as the scene's
//! camera and hands the renderer a `Camera` each frame.

use crate::scene::Camera;
use glam::Vec3;

/// Movement keys held down.
#[derive(Clone, Copy, Debug, Default)]
pub struct Held {
    pub forward: bool,
    pub back: bool,
    pub left: bool,
    pub right: bool,
    pub down: bool,
    pub up: bool,
    /// Shift: 4x faster.
    pub fast: bool,
}

#[derive(Clone, Debug)]
pub struct FlyCamera {
    /// The scene's camera, to reset to.
    home: Camera,
    pub position: Vec3,
    /// Radians about +y (0 looks down -z) and above the horizon.
    pub yaw: f32,
    pub pitch: f32,
    /// World units per second.
    pub speed: f32,
    home_speed: f32,
    /// The scene's radius, for the far plane as the camera flies away.
    scene_center: Vec3,
    scene_radius: f32,
    pub held: Held,
}

/// Radians of turn per pixel of mouse movement.
const LOOK_RATE: f32 = 0.004;
/// Pitch stays short of straight up or down (the view's up vector is +y).
const PITCH_LIMIT: f32 = 1.55;

impl FlyCamera {
    /// A fly camera at `home`, moving at a speed that crosses a scene of `bounds` in
    /// about four seconds.
    pub fn new(home: Camera, bounds: (Vec3, Vec3)) -> Self {
        let radius = (0.5 * (bounds.1 - bounds.0).length()).max(1e-3);
        let speed = radius * 0.5;
        let mut c = Self {
            home,
            position: home.position,
            yaw: 0.0,
            pitch: 0.0,
            speed,
            home_speed: speed,
            scene_center: 0.5 * (bounds.0 + bounds.1),
            scene_radius: radius,
            held: Held::default(),
        };
        c.reset();
        c
    }

    /// Back to the scene's camera and the starting speed.
    pub fn reset(&mut self) {
        self.set(self.home);
        self.speed = self.home_speed;
    }

    /// Takes `camera`'s position and direction (its up vector stays +y).
    pub fn set(&mut self, camera: Camera) {
        self.position = camera.position;
        let d = (camera.target - camera.position).normalize_or(Vec3::NEG_Z);
        self.yaw = (-d.x).atan2(-d.z);
        self.pitch = d.y.clamp(-1.0, 1.0).asin().clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, sp, -cy * cp)
    }

    /// Turns by a mouse movement of (dx, dy) pixels.
    pub fn look(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * LOOK_RATE;
        self.pitch = (self.pitch - dy * LOOK_RATE).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Scroll: each notch is 25% faster or slower.
    pub fn scroll(&mut self, notches: f32) {
        self.speed = (self.speed * 1.25f32.powf(notches)).clamp(self.home_speed * 1e-3, self.home_speed * 1e3);
    }

    /// Moves for `dt` seconds with the keys held; whether it moved.
    pub fn update(&mut self, dt: f32) -> bool {
        let h = self.held;
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or(Vec3::X);
        let axis = |plus: bool, minus: bool| (plus as i32 - minus as i32) as f32;
        let dir = f * axis(h.forward, h.back) + right * axis(h.right, h.left) + Vec3::Y * axis(h.up, h.down);
        if dir == Vec3::ZERO {
            return false;
        }
        let speed = self.speed * if h.fast { 4.0 } else { 1.0 };
        self.position += dir.normalize() * speed * dt.min(0.25);
        true
    }

    /// The camera to render with: the scene camera's lens, looking along `forward`,
    /// with the far plane pushed out to keep the whole scene in view.
    pub fn camera(&self) -> Camera {
        let reach = (self.position - self.scene_center).length() + self.scene_radius;
        Camera {
            position: self.position,
            target: self.position + self.forward(),
            up: Vec3::Y,
            far: self.home.far.max(reach * 1.05),
            ..self.home
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_as_the_scene_camera_and_resets_to_it() {
        let home = Camera {
            position: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(-2.0, 0.5, -1.0),
            up: Vec3::Y,
            fov_y_deg: 45.0,
            near: 0.1,
            far: 50.0,
        };
        let mut c = FlyCamera::new(home, (Vec3::splat(-5.0), Vec3::splat(5.0)));
        let dir = (home.target - home.position).normalize();
        assert!((c.forward() - dir).length() < 1e-5, "{:?} vs {dir:?}", c.forward());
        let cam = c.camera();
        assert_eq!((cam.position, cam.fov_y_deg, cam.near), (home.position, 45.0, 0.1));
        assert!(((cam.target - cam.position).normalize() - dir).length() < 1e-5);
        c.held.forward = true;
        assert!(c.update(0.1));
        assert!((c.position - (home.position + dir * c.speed * 0.1)).length() < 1e-4);
        c.look(100.0, -40.0);
        c.scroll(2.0);
        c.reset();
        assert_eq!(c.position, home.position);
        assert!((c.forward() - dir).length() < 1e-5);
        c.held = Held::default();
        assert!(!c.update(1.0), "no key held, no move");
    }

    #[test]
    fn pitch_stays_below_the_poles() {
        let home = Camera::framing(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut c = FlyCamera::new(home, (Vec3::splat(-1.0), Vec3::splat(1.0)));
        c.look(0.0, -1e6);
        assert!(c.pitch <= PITCH_LIMIT && c.forward().y < 1.0);
        let cam = c.camera();
        assert!(cam.target.is_finite() && cam.far >= home.far);
    }
}
