//! `SceneBuilder`: a scene put together mesh by mesh, with its materials and textures.

use super::*;
use crate::error::Result;
use crate::gpu_types::GpuVertex;
use glam::{Mat4, Vec2, Vec3};

/// Accumulates meshes into a scene.
pub struct SceneBuilder {
    pub(super) scene: Scene,
}

impl SceneBuilder {
    pub fn new(name: &str) -> Self {
        Self {
            scene: Scene {
                name: name.into(),
                vertices: Vec::new(),
                uvs: Vec::new(),
                indices: Vec::new(),
                materials: Vec::new(),
                textures: Vec::new(),
                bodies: Vec::new(),
                spawn: None,
                cloths: Vec::new(),
                body_meshes: Vec::new(),
                camera: Camera {
                    position: Vec3::new(0.0, 2.0, 6.0),
                    target: Vec3::ZERO,
                    up: Vec3::Y,
                    fov_y_deg: 50.0,
                    near: 0.05,
                    far: 100.0,
                },
                light: Light {
                    direction: Vec3::new(-0.4, 0.8, 0.45).normalize(),
                    color: Vec3::new(1.0, 0.96, 0.9),
                    intensity: 3.0,
                },
                sky: Sky {
                    zenith: Vec3::new(0.25, 0.45, 0.85),
                    horizon: Vec3::new(0.75, 0.8, 0.9),
                },
                warnings: Vec::new(),
                animated: None,
            },
        }
    }

    /// Adds a material and returns its index.
    pub fn material(&mut self, m: Material) -> u32 {
        self.scene.materials.push(m);
        self.scene.materials.len() as u32 - 1
    }

    /// Records the spawn whose bodies were just added (the last `spawn.count` bodies).
    pub fn spawn(&mut self, spawn: Spawn) -> &mut Self {
        self.scene.spawn = Some(spawn);
        self
    }

    /// Adds a body mesh (for `BodyShape::Mesh`) and returns its index.
    pub fn body_mesh(&mut self, mesh: TriMesh) -> u32 {
        self.scene.body_meshes.push(mesh);
        self.scene.body_meshes.len() as u32 - 1
    }

    /// Adds a cloth (dynamic geometry).
    pub fn cloth(&mut self, cloth: crate::scene::cloth::Cloth) -> &mut Self {
        self.scene.cloths.push(cloth);
        self
    }

    /// Adds a rigid body (dynamic geometry).
    pub fn body(&mut self, body: Body) -> &mut Self {
        self.scene.bodies.push(body);
        self
    }

    /// Adds a texture and returns its index, for `Material::textured`.
    pub fn texture(&mut self, t: Texture) -> u32 {
        self.scene.textures.push(t);
        self.scene.textures.len() as u32 - 1
    }

    /// Adds a mesh moved by `transform`, using material `material`.
    pub fn mesh(&mut self, mesh: TriMesh, transform: Mat4, material: u32) -> &mut Self {
        let mesh = mesh.transformed(transform);
        let base = self.scene.vertices.len() as u32;
        let uvs = (0..mesh.positions.len()).map(|i| mesh.uvs.get(i).copied().unwrap_or(Vec2::ZERO).to_array());
        self.scene.uvs.extend(uvs);
        self.scene
            .vertices
            .extend(mesh.positions.iter().zip(&mesh.normals).map(|(p, n)| GpuVertex {
                position: p.to_array(),
                material,
                normal: n.to_array(),
                object: 0,
            }));
        self.scene.indices.extend(mesh.indices.iter().map(|i| base + i));
        self
    }

    /// Adds every triangle of `scene` moved by `transform`, with its own materials, or
    /// all with `material` when given; its animated model too (placed by `transform`),
    /// replacing any this scene had.
    pub fn append(&mut self, scene: &Scene, transform: Mat4, material: Option<u32>) -> &mut Self {
        let offset = self.scene.materials.len() as u32;
        if material.is_none() {
            let textures = self.scene.textures.len() as u32;
            self.scene.textures.extend(scene.textures.iter().cloned());
            self.scene.materials.extend(scene.materials.iter().map(|m| Material {
                texture: m.texture.map(|t| t + textures),
                ..m.clone()
            }));
        }
        self.scene.uvs.extend(&scene.uvs);
        let normals = transform.inverse().transpose();
        let base = self.scene.vertices.len() as u32;
        self.scene.vertices.extend(scene.vertices.iter().map(|v| {
            GpuVertex {
                position: transform.transform_point3(Vec3::from(v.position)).to_array(),
                material: material.unwrap_or(v.material + offset),
                normal: normals
                    .transform_vector3(Vec3::from(v.normal))
                    .normalize_or(Vec3::Y)
                    .to_array(),
                object: 0,
            }
        }));
        self.scene.indices.extend(scene.indices.iter().map(|i| base + i));
        self.scene.warnings.extend(scene.warnings.iter().cloned());
        if let Some(a) = &scene.animated {
            let mut a = a.clone();
            a.placement = transform * a.placement;
            for v in &mut a.vertices {
                v.material = material.unwrap_or(v.material + offset);
            }
            // One animated model a scene (the caller refuses a second).
            self.scene.animated = Some(a);
        }
        self
    }

    /// Adds a warning the scene's user sees (one line).
    pub fn warn(&mut self, warning: String) -> &mut Self {
        self.scene.warnings.push(warning);
        self
    }

    pub fn sky(&mut self, sky: Sky) -> &mut Self {
        self.scene.sky = sky;
        self
    }

    pub fn camera(&mut self, camera: Camera) -> &mut Self {
        self.scene.camera = camera;
        self
    }

    pub fn light(&mut self, light: Light) -> &mut Self {
        self.scene.light = Light {
            direction: light.direction.normalize(),
            ..light
        };
        self
    }

    /// Finishes and validates the scene.
    pub fn build(self) -> Result<Scene> {
        self.scene.validate()?;
        Ok(self.scene)
    }
}
