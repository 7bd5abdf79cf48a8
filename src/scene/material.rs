//! A surface's material: base colour, metallic, roughness, reflectivity and texture
//! (the model is in `docs/scenes.md`, "Materials").

use crate::gpu_types::GpuMaterial;
use crate::shader_defines::TEXTURE_NONE;
use glam::Vec3;

/// A surface description.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGB albedo in [0, 1].
    pub albedo: Vec3,
    /// 0 = mirror, 1 = fully rough.
    pub roughness: f32,
    /// The share in [0, 1] of the specular reflection (Fresnel-weighted, see
    /// `metallic`) that is a mirror image of the scene: the reflection passes trace
    /// where it is > 0; the rest of the specular reflection sees the sky.
    pub reflectivity: f32,
    /// 0: a dielectric (specular reflectance 0.04 at normal incidence), 1: a metal
    /// (reflectance = `albedo`, no diffuse); in between blends the two.
    pub metallic: f32,
    /// Base-colour texture (an index into `Scene::textures`), multiplying `albedo`.
    pub texture: Option<u32>,
    /// Roughness texture (an index into `Scene::textures`, linear data: `Texture::data`,
    /// read through the texture array's UNORM view) in glTF's `metallicRoughnessTexture` layout:
    /// its green channel multiplies `roughness`, its blue channel `metallic` (a scene
    /// file's roughness texture has its blue set to 1).
    pub roughness_texture: Option<u32>,
}

impl Material {
    /// Every factor a finite number. (Out-of-range ones are clamped into [0, 1] on
    /// the way to the GPU; the loaders say so in a warning.)
    pub fn check(&self) -> std::result::Result<(), String> {
        let finite = self.albedo.is_finite()
            && self.roughness.is_finite()
            && self.reflectivity.is_finite()
            && self.metallic.is_finite();
        if !finite {
            return Err(format!(
                "material '{}': base colour {}, roughness {}, reflectivity {} and metallic {} must be finite numbers",
                self.name, self.albedo, self.roughness, self.reflectivity, self.metallic
            ));
        }
        Ok(())
    }

    /// The material with every factor clamped into [0, 1], and a note of what changed
    /// (`None` when nothing did). NaN is not clamped: `check` refuses it.
    pub fn clamped(mut self) -> (Self, Option<String>) {
        let mut notes = Vec::new();
        let mut clamp = |what: &str, x: &mut f32| {
            if *x < 0.0 || *x > 1.0 {
                let c = x.clamp(0.0, 1.0);
                notes.push(format!("{what} {x} clamped to {c}"));
                *x = c;
            }
        };
        let mut a = self.albedo.to_array();
        for (i, c) in a.iter_mut().enumerate() {
            clamp(["base colour red", "base colour green", "base colour blue"][i], c);
        }
        self.albedo = Vec3::from(a);
        clamp("roughness", &mut self.roughness);
        clamp("reflectivity", &mut self.reflectivity);
        clamp("metallic", &mut self.metallic);
        let note = (!notes.is_empty()).then(|| format!("material '{}': {}", self.name, notes.join(", ")));
        (self, note)
    }

    pub fn new(name: &str, albedo: [f32; 3], roughness: f32, reflectivity: f32) -> Self {
        Self {
            name: name.into(),
            albedo: Vec3::from(albedo),
            roughness,
            reflectivity,
            metallic: 0.0,
            texture: None,
            roughness_texture: None,
        }
    }

    /// The same material with `metallic` set.
    pub fn metal(mut self, metallic: f32) -> Self {
        self.metallic = metallic;
        self
    }

    /// The same material with base-colour texture `texture` (a `Scene::textures` index).
    pub fn textured(mut self, texture: u32) -> Self {
        self.texture = Some(texture);
        self
    }

    pub fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            albedo: self.albedo.clamp(Vec3::ZERO, Vec3::ONE).to_array(),
            roughness: self.roughness.clamp(0.0, 1.0),
            reflectivity: self.reflectivity.clamp(0.0, 1.0),
            texture_layer: self.texture.unwrap_or(TEXTURE_NONE),
            metallic: self.metallic.clamp(0.0, 1.0),
            roughness_layer: self.roughness_texture.unwrap_or(TEXTURE_NONE),
        }
    }
}
