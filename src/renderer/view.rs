//! The view maths: what the frame uniforms are made of besides the settings (camera,
//! light, sky, the shadow map's box), and the renderer's origin for far-away scenes.

use crate::gpu_types::FrameUniforms;
use crate::scene::{Camera, Light, Scene, Sky};
use crate::settings::Settings;
use glam::{Mat4, Vec3};

/// What the frame uniforms are made from besides the settings: the scene's camera,
/// light, sky and bounds (the shadow map's box).
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub camera: Camera,
    pub light: Light,
    pub sky: Sky,
    pub bounds: (Vec3, Vec3),
}

impl View {
    pub fn of(scene: &Scene) -> Self {
        Self {
            camera: scene.camera,
            light: scene.light,
            sky: scene.sky,
            bounds: scene.bounds(),
        }
    }

    /// The same view with the world moved by `-origin`.
    pub(super) fn relative_to(mut self, origin: Vec3) -> Self {
        self.camera.position -= origin;
        self.camera.target -= origin;
        self.bounds = (self.bounds.0 - origin, self.bounds.1 - origin);
        self
    }

    /// The frame uniforms of this view seen with `settings`.
    pub(super) fn uniforms(&self, settings: &Settings) -> FrameUniforms {
        let aspect = settings.width as f32 / settings.height as f32;
        let view_proj = self.camera.view_proj(aspect);
        let (lo, hi) = self.bounds;
        let light = &self.light;
        FrameUniforms {
            view_proj,
            inv_view_proj: view_proj.inverse(),
            light_view_proj: light_view_proj(light.direction, lo, hi),
            view: self.camera.view(),
            proj: self.camera.projection(aspect),
            camera_pos: self.camera.position.extend(1.0),
            light_dir: light.direction.normalize().extend(0.0),
            light_color: (light.color * light.intensity).extend(0.0),
            sky_zenith: self.sky.zenith.extend(0.0),
            sky_horizon: self.sky.horizon.extend(0.0),
            resolution: [settings.width, settings.height],
            shadow_map_size: settings.shadow_map_size,
            pcf_radius: settings.pcf_radius,
            shadow_bias: settings.shadow_bias,
            exposure: settings.exposure,
            ambient: settings.ambient,
            shadow_band: settings.shadow_band,
            frame_index: 0,
            reflection_rays: settings.reflection_rays,
            mirror_roughness: settings.glossy_mirror_max,
            rough_roughness: settings.glossy_rough_max,
            sample_stream: 0,
            glossy: settings.glossy as u32,
            _pad0: 0,
            _pad1: 0,
        }
    }
}

/// Where the renderer puts its origin for `scene`: the scene's centre when that is
/// farther from the world origin than the scene's own radius (a model at 1e4 units
/// would lose depth and shadow precision in f32 otherwise), else the world origin (a
/// scene around the origin renders in world coordinates, exactly as given).
pub fn render_origin(scene: &Scene) -> Vec3 {
    let (lo, hi) = scene.bounds();
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    if center.length() > radius.max(1e-6) {
        center
    } else {
        Vec3::ZERO
    }
}

/// The light's world → clip transform: an orthographic box around the scene's
/// bounding sphere, looking along the light direction.
fn light_view_proj(direction: Vec3, lo: Vec3, hi: Vec3) -> Mat4 {
    let center = 0.5 * (lo + hi);
    let r = (0.5 * (hi - lo).length()).max(1e-3) * 1.01;
    let up = if direction.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let view = glam::camera::rh::view::look_at_mat4(center + direction * 2.0 * r, center, up);
    glam::camera::rh::proj::vulkan::orthographic(-r, r, -r, r, r, 3.0 * r) * view
}

/// Frame uniforms for `scene` seen with `settings`.
pub fn frame_uniforms(scene: &Scene, settings: &Settings) -> FrameUniforms {
    View::of(scene).uniforms(settings)
}
