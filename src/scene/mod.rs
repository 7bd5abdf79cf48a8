//! Scenes: triangles in world space with texture coordinates, materials (the model is
//! in `docs/scenes.md`, "Materials"), base-colour textures, a camera and a light.
//!
//! A scene comes from a scene file (`file`: TOML, primitives and models with
//! transforms; the built-in scenes are such files, `builtin`) or a model file (`obj`,
//! `gltf`, `ply`), which stands on a floor: `load.rs` reads the walk top-down. Either
//! way it is validated before the GPU sees it: at least one triangle, finite
//! coordinates and texture coordinates, indices and texture references in range.

pub mod animated;
pub mod animation;
mod bodies;
mod builder;
pub mod builtin;
pub mod camera;
pub mod cloth;
pub mod file;
pub mod geometry;
pub mod gltf;
mod gltf_rig;
mod instance;
mod load;
mod material;
pub mod obj;
pub mod ply;
pub mod soup;
pub mod texture;

pub use bodies::{Body, BodyShape, Spawn, MAX_BODIES};
pub use builder::SceneBuilder;
pub use camera::Camera;
pub use geometry::TriMesh;
pub use load::{is_model, load, load_model, load_with, Floor, FORMATS};
pub use material::Material;
pub use texture::Texture;

use crate::error::{Error, Result};
use crate::gpu_types::GpuVertex;
use glam::{Vec2, Vec3};

/// The dynamic geometry in its own spaces, as `sim.transform` reads it: each vertex's
/// `object` is its body's index; triangles index these vertices.
#[derive(Clone, Debug, Default)]
pub struct DynamicMeshes {
    /// The rigid bodies' vertices first (`rigid_vertices` of them), then the cloths',
    /// then the animated model's (from `animated_vertices` on), in their bind pose.
    pub vertices: Vec<GpuVertex>,
    pub rigid_vertices: usize,
    pub animated_vertices: usize,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
}

/// A directional light (the sun): parallel rays, one shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector from surfaces towards the light.
    pub direction: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Radiance scale.
    pub intensity: f32,
}

impl Light {
    /// A finite direction that is not zero, a finite colour and intensity >= 0.
    pub fn check(&self) -> std::result::Result<(), String> {
        if !self.direction.is_finite() || self.direction.length() < 1e-6 {
            return Err(format!("the sun direction {} has no direction", self.direction));
        }
        if !(self.color.is_finite() && self.color.min_element() >= 0.0) {
            return Err(format!("the sun colour {} must be finite and >= 0", self.color));
        }
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(format!("the sun intensity {} must be finite and >= 0", self.intensity));
        }
        Ok(())
    }
}

/// Sky colours, also used as hemispherical ambient light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    pub zenith: Vec3,
    pub horizon: Vec3,
}

impl Sky {
    /// Finite colours >= 0.
    pub fn check(&self) -> std::result::Result<(), String> {
        for (what, c) in [("zenith", self.zenith), ("horizon", self.horizon)] {
            if !(c.is_finite() && c.min_element() >= 0.0) {
                return Err(format!("the sky {what} colour {c} must be finite and >= 0"));
            }
        }
        Ok(())
    }
}

/// A renderable scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub vertices: Vec<GpuVertex>,
    /// Texture coordinates of each vertex (same length as `vertices`).
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
    pub materials: Vec<Material>,
    /// Base-colour textures, which materials name by index.
    pub textures: Vec<Texture>,
    /// Rigid bodies: the dynamic geometry (none in a static scene); the last ones are
    /// `spawn`'s when there is one.
    pub bodies: Vec<Body>,
    /// The grid of bodies the scene file asked for, if any (`set_spawn_count`).
    pub spawn: Option<Spawn>,
    /// Cloths: dynamic geometry simulated on the GPU (`scene::cloth`).
    pub cloths: Vec<crate::scene::cloth::Cloth>,
    /// Meshes of the bodies shaped by a model (`BodyShape::Mesh`), in their own space.
    pub body_meshes: Vec<TriMesh>,
    pub camera: Camera,
    pub light: Light,
    pub sky: Sky,
    /// What loading changed without failing (e.g. out-of-range MTL values clamped), one
    /// line each, for the command line to print.
    pub warnings: Vec<String>,
    /// A glTF model's animated parts (skinned meshes, meshes its node animations
    /// move) and the animation they play (`animated::Animated`): dynamic geometry.
    pub animated: Option<animated::Animated>,
}

impl Scene {
    /// Axis-aligned bounds of the static vertices, of the bodies where they start and
    /// of the animated model at its first frame (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let statics = self
            .vertices
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), v| {
                let p = Vec3::from(v.position);
                (lo.min(p), hi.max(p))
            });
        let with_bodies = self.bodies.iter().fold(statics, |(lo, hi), b| {
            let r = Vec3::splat(b.radius());
            (lo.min(b.position - r), hi.max(b.position + r))
        });
        let with_cloths = self.cloths.iter().fold(with_bodies, |(lo, hi), c| {
            let r = Vec3::splat(0.5 * c.size);
            (lo.min(c.center - r), hi.max(c.center + r))
        });
        let posed = self.animated.as_ref().map(|a| a.posed(a.time(0.0), Vec3::ZERO));
        posed.iter().flatten().fold(with_cloths, |(lo, hi), v| {
            let p = Vec3::from(v.position);
            (lo.min(p), hi.max(p))
        })
    }

    /// Replaces the spawned bodies by `count` of them (`--bodies`): the scene must have
    /// a spawn (`[spawn]` in its file, as `stress`), and `count` be in 1..=`MAX_BODIES`.
    pub fn set_spawn_count(&mut self, count: u32) -> Result<()> {
        if count == 0 || count > MAX_BODIES {
            return Err(Error::Input(format!("--bodies {count} is outside 1..={MAX_BODIES}")));
        }
        let Some(spawn) = &mut self.spawn else {
            return Err(Error::Input(format!(
                "--bodies needs a scene with a [spawn] table (such as stress); '{}' has none",
                self.name
            )));
        };
        let keep = self.bodies.len() - spawn.count as usize;
        spawn.count = count;
        let bodies = spawn.bodies();
        self.bodies.truncate(keep);
        self.bodies.extend(bodies);
        Ok(())
    }

    /// Whether anything moves.
    pub fn is_dynamic(&self) -> bool {
        !self.bodies.is_empty() || !self.cloths.is_empty() || self.animated.is_some()
    }

    /// A body's mesh in its own space.
    pub fn body_mesh(&self, b: &Body) -> TriMesh {
        match b.shape {
            BodyShape::Sphere { radius } => TriMesh::sphere(radius, 32, 16),
            BodyShape::Cuboid { size } => TriMesh::cuboid(size),
            BodyShape::Mesh { mesh, .. } => self.body_meshes[mesh as usize].clone(),
        }
    }

    /// The bodies' meshes in their own spaces, concatenated (`DynamicMeshes`).
    pub fn dynamic_meshes(&self) -> DynamicMeshes {
        let mut out = DynamicMeshes::default();
        for (i, b) in self.bodies.iter().enumerate() {
            let mesh = self.body_mesh(b);
            let base = out.vertices.len() as u32;
            for (k, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
                out.vertices.push(GpuVertex {
                    position: p.to_array(),
                    material: b.material,
                    normal: n.to_array(),
                    object: i as u32,
                });
                out.uvs.push(mesh.uvs.get(k).copied().unwrap_or(Vec2::ZERO).to_array());
            }
            out.indices.extend(mesh.indices.iter().map(|t| base + t));
        }
        out.rigid_vertices = out.vertices.len();
        for c in &self.cloths {
            let base = out.vertices.len() as u32;
            let (indices, uvs) = c.mesh();
            out.vertices.extend(c.rest_vertices());
            out.uvs.extend(uvs);
            out.indices.extend(indices.iter().map(|t| base + t));
        }
        out.animated_vertices = out.vertices.len();
        if let Some(a) = &self.animated {
            let base = out.vertices.len() as u32;
            out.vertices.extend(&a.vertices);
            out.uvs.extend(&a.uvs);
            out.indices.extend(a.indices.iter().map(|t| base + t));
        }
        out
    }

    /// Triangles of the dynamic geometry.
    pub fn dynamic_triangle_count(&self) -> usize {
        let cloth: usize = self.cloths.iter().map(|c| 2 * (c.resolution as usize - 1).pow(2)).sum();
        self.bodies
            .iter()
            .map(|b| self.body_mesh(b).indices.len() / 3)
            .sum::<usize>()
            + cloth
            + self.animated.as_ref().map_or(0, |a| a.indices.len() / 3)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks what the GPU passes rely on.
    pub fn validate(&self) -> Result<()> {
        let bad = |detail: String| {
            Err(Error::BadGeometry {
                source_name: self.name.clone(),
                detail,
            })
        };
        if self.indices.is_empty() || self.vertices.is_empty() {
            return bad("the scene has no triangles".into());
        }
        // One check for the view, the sun, the sky and the materials, whatever they
        // came from (the command line's flags go through the same ones).
        self.camera.check().or_else(bad)?;
        self.light.check().or_else(bad)?;
        self.sky.check().or_else(bad)?;
        for m in &self.materials {
            m.check().or_else(bad)?;
        }
        self.check_mesh().or_else(bad)?;
        for (i, b) in self.bodies.iter().enumerate() {
            self.check_body(i, b).or_else(bad)?;
        }
        for (i, c) in self.cloths.iter().enumerate() {
            self.check_cloth(i, c).or_else(bad)?;
        }
        if let Some(a) = &self.animated {
            a.check().map_err(|e| format!("the animated model: {e}")).or_else(bad)?;
            if let Some(m) = a.vertices.iter().find(|v| v.material as usize >= self.materials.len()) {
                return bad(format!(
                    "the animated model uses material {}, but there are {}",
                    m.material,
                    self.materials.len()
                ));
            }
        }
        let (lo, hi) = self.bounds();
        if (hi - lo).max_element() > 1e7 {
            return bad(format!(
                "the scene spans {:.3e} units; coordinates beyond 1e7 lose float precision",
                (hi - lo).max_element()
            ));
        }
        Ok(())
    }

    /// The triangles: whole, indexing their vertices, finite, with known materials and
    /// textures.
    fn check_mesh(&self) -> std::result::Result<(), String> {
        if !self.indices.len().is_multiple_of(3) {
            return Err(format!(
                "{} indices is not a whole number of triangles",
                self.indices.len()
            ));
        }
        if self.uvs.len() != self.vertices.len() {
            return Err(format!(
                "{} texture coordinates for {} vertices",
                self.uvs.len(),
                self.vertices.len()
            ));
        }
        if let Some(i) = self.uvs.iter().position(|uv| !uv.iter().all(|c| c.is_finite())) {
            return Err(format!(
                "vertex {i} has non-finite texture coordinates {:?}",
                self.uvs[i]
            ));
        }
        if let Some(m) = self
            .materials
            .iter()
            .find(|m| m.texture.is_some_and(|t| t as usize >= self.textures.len()))
        {
            return Err(format!(
                "material '{}' uses texture {} but the scene has {}",
                m.name,
                m.texture.unwrap_or_default(),
                self.textures.len()
            ));
        }
        if let Some(i) = self.indices.iter().position(|&i| i as usize >= self.vertices.len()) {
            return Err(format!(
                "index {} at position {i} is past the {} vertices",
                self.indices[i],
                self.vertices.len()
            ));
        }
        for (i, v) in self.vertices.iter().enumerate() {
            if !v.position.iter().chain(&v.normal).all(|c| c.is_finite()) {
                return Err(format!("vertex {i} has a non-finite coordinate {:?}", v.position));
            }
            if v.material as usize >= self.materials.len() {
                return Err(format!(
                    "vertex {i} uses material {} but the scene has {}",
                    v.material,
                    self.materials.len()
                ));
            }
        }
        Ok(())
    }

    /// Body `i`: a positive, finite size, a known material, a finite state and
    /// physical constants rapier accepts.
    fn check_body(&self, i: usize, b: &Body) -> std::result::Result<(), String> {
        let size_ok = match b.shape {
            BodyShape::Sphere { radius } => radius.is_finite() && radius > 0.0,
            BodyShape::Cuboid { size } => size.is_finite() && size.min_element() > 0.0,
            BodyShape::Mesh { mesh, radius, .. } => {
                (mesh as usize) < self.body_meshes.len() && radius.is_finite() && radius > 0.0
            }
        };
        if !size_ok {
            return Err(format!(
                "body {i} has a zero, negative or non-finite size ({:?})",
                b.shape
            ));
        }
        if b.material as usize >= self.materials.len() {
            return Err(format!(
                "body {i} uses material {} but the scene has {}",
                b.material,
                self.materials.len()
            ));
        }
        let state_ok = b.position.is_finite()
            && b.rotation.is_finite()
            && b.velocity.is_finite()
            && b.angular_velocity.is_finite();
        if !state_ok {
            return Err(format!("body {i} has a non-finite position, rotation or velocity"));
        }
        if !(b.density.is_finite() && b.density > 0.0) {
            return Err(format!("body {i} has density {} (it must be > 0)", b.density));
        }
        if !(b.restitution.is_finite() && b.friction.is_finite() && b.restitution >= 0.0 && b.friction >= 0.0) {
            return Err(format!("body {i} has a negative or non-finite restitution or friction"));
        }
        Ok(())
    }

    /// Cloth `i`: a resolution, size and solver settings the GPU step handles, a known
    /// material, finite colliders.
    fn check_cloth(&self, i: usize, c: &cloth::Cloth) -> std::result::Result<(), String> {
        let max = crate::scene::cloth::MAX_RESOLUTION;
        if c.resolution < 2 || c.resolution > max {
            return Err(format!("cloth {i}: resolution {} is outside 2..={max}", c.resolution));
        }
        if !(c.size.is_finite() && c.size > 0.0 && c.center.is_finite() && c.floor_y.is_finite()) {
            return Err(format!(
                "cloth {i}: its size, centre or floor is not finite (size must be > 0)"
            ));
        }
        if !(c.stiffness > 0.0 && c.stiffness <= 1.0) || c.iterations == 0 || c.iterations > 64 {
            return Err(format!(
                "cloth {i}: stiffness {} must be in (0, 1] and iterations {} in 1..=64",
                c.stiffness, c.iterations
            ));
        }
        if c.material as usize >= self.materials.len() {
            return Err(format!(
                "cloth {i} uses material {} but the scene has {}",
                c.material,
                self.materials.len()
            ));
        }
        if c.spheres.iter().any(|s| !s.is_finite() || s.w <= 0.0) {
            return Err(format!("cloth {i}: a collider sphere is not finite or has radius <= 0"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn room_is_valid_and_bounded() {
        let room = builtin::room().unwrap();
        assert!(room.triangle_count() > 1000);
        let (lo, hi) = room.bounds();
        assert!(lo.y >= -1e-4 && hi.y <= 6.0 + 1e-4, "{lo} {hi}");
    }

    #[test]
    fn validation_rejects_broken_geometry() {
        let mut s = builtin::room().unwrap();
        s.vertices[3].position[1] = f32::INFINITY;
        assert!(s.validate().unwrap_err().to_string().contains("non-finite"));
        let mut s = builtin::room().unwrap();
        s.indices[7] = s.vertices.len() as u32;
        assert!(s.validate().unwrap_err().to_string().contains("past the"));
        let mut s = builtin::room().unwrap();
        s.indices.clear();
        assert!(s.validate().unwrap_err().to_string().contains("no triangles"));
    }

    #[test]
    fn unknown_names_list_the_built_in_scenes() {
        let e = load("nope").unwrap_err().to_string();
        assert!(e.contains("unknown scene 'nope'") && e.contains("room"), "{e}");
    }

    #[test]
    fn sphere_vertices_lie_on_the_sphere_with_outward_normals() {
        let m = TriMesh::sphere(2.0, 16, 8);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((p.length() - 2.0).abs() < 1e-5);
            assert!(p.normalize().dot(*n) > 0.9999);
        }
        // Winding: every triangle's geometric normal points outwards.
        for t in m.indices.chunks_exact(3) {
            let (a, b, c) = (
                m.positions[t[0] as usize],
                m.positions[t[1] as usize],
                m.positions[t[2] as usize],
            );
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
    }
}
