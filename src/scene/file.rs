//! Scene files (TOML): a camera, a sun, a sky, named materials and a list of instances —
//! primitives (plane, box, sphere) or model files — each with a transform. The built-in
//! scenes are such files (`assets/scenes/*.toml`, compiled into the binary). The format
//! is documented in `docs/scenes.md`; every field here says what it is.
//!
//! A transform is `translate * rotate * scale`, `rotate` in degrees about x, then y, then
//! z (the matrix `Rz * Ry * Rx`), `scale` uniform or per axis.

use super::instance::plays_as;
pub use super::instance::{Instance, Scale};
use super::{Camera, Light, Material, Scene, SceneBuilder, Sky, TriMesh};
use crate::error::{Error, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A whole scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Name in reports (default: the file's stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub camera: CameraDesc,
    pub sun: SunDesc,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<SkyDesc>,
    /// Materials in order; instances name them.
    #[serde(default)]
    pub materials: Vec<MaterialDesc>,
    #[serde(rename = "instance")]
    pub instances: Vec<Instance>,
    /// Rigid bodies (dynamic geometry): simulated, they fall and collide with the
    /// instances and each other.
    #[serde(default, rename = "body", skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyDesc>,
    /// A grid of bodies dropped into the scene (`scene::Spawn`; `--bodies` overrides
    /// `count`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spawn: Option<SpawnDesc>,
    /// Cloths (`scene::cloth`), simulated on the GPU.
    #[serde(default, rename = "cloth", skip_serializing_if = "Vec::is_empty")]
    pub cloths: Vec<ClothDesc>,
}

/// A square cloth, horizontal at first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothDesc {
    /// Side length.
    pub size: f32,
    /// Particles per side (2..=512).
    pub resolution: u32,
    /// Where its centre starts.
    pub center: [f32; 3],
    pub material: String,
    /// none (default), corners (of the first row) or edge (the first row).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pins: Option<crate::scene::cloth::Pins>,
    /// Jacobi relaxation factor in (0, 1] (default 0.9).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f32>,
    /// Constraint iterations per step (default 16).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// Spheres it collides with, [x, y, z, radius] each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spheres: Vec<[f32; 4]>,
    /// The height of a floor it stays above (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<f32>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpawnDesc {
    /// How many bodies (1..=`MAX_BODIES`, 4000).
    pub count: u32,
    /// Ball radius, and 1/1.6 of the cubes' edge.
    pub size: f32,
    /// Centre of the lowest layer's bottom.
    pub center: [f32; 3],
    /// Materials by name, cycled through.
    pub materials: Vec<String>,
}

/// A rigid body: exactly one shape key, a material, its initial pose and motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyDesc {
    /// A ball of this radius.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<f32>,
    /// A box of these full extents.
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub cuboid: Option<[f32; 3]>,
    /// A model file (OBJ, glTF, GLB, PLY; relative to the scene file), centred on its
    /// bounds' centre and scaled by `scale`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// A model's collider: `hull` (its convex hull, the default) or `mesh` (its
    /// triangles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collider: Option<String>,
    /// A model's uniform scale (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f32>,
    /// A material of `materials` by name.
    pub material: String,
    /// Where its centre starts.
    pub translate: [f32; 3],
    /// Degrees about x, then y, then z (as instances).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<[f32; 3]>,
    /// Initial velocity, units per second (default at rest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f32; 3]>,
    /// Initial angular velocity about the world axes, radians per second.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<[f32; 3]>,
    /// kg per cubic unit (default 1000, water).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f32>,
    /// Bounciness in [0, 1] (default 0.4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f32>,
    /// Coulomb friction (default 0.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f32>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub position: [f32; 3],
    pub target: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov: f32,
    /// Near and far clip distances (defaults 0.05 and 100).
    #[serde(default = "default_near")]
    pub near: f32,
    #[serde(default = "default_far")]
    pub far: f32,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

fn default_near() -> f32 {
    0.05
}
fn default_far() -> f32 {
    100.0
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunDesc {
    /// Towards the sun (normalized on load).
    pub direction: [f32; 3],
    /// Linear RGB.
    pub color: [f32; 3],
    pub intensity: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyDesc {
    /// Linear RGB straight up and at the horizon.
    pub zenith: [f32; 3],
    pub horizon: [f32; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    pub name: String,
    /// Linear RGB in [0, 1].
    pub base_color: [f32; 3],
    /// 0 = mirror, 1 = fully rough.
    pub roughness: f32,
    /// The share of the specular reflection that is a traced mirror image, in [0, 1]
    /// (0: no reflection traced).
    #[serde(default)]
    pub reflectivity: f32,
    /// 0: dielectric (reflects 4% head-on, more at grazing angles), 1: metal (reflects
    /// its base colour); default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub metallic: f32,
    /// A base-colour texture (PNG or JPEG, relative to the scene file) multiplying
    /// `base_color` per texel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<String>,
    /// A roughness texture (PNG or JPEG, relative to the scene file) whose green channel
    /// multiplies `roughness` per texel (as glTF's `metallicRoughnessTexture`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roughness_texture: Option<String>,
}

/// Most segments around and rings from pole to pole of a scene file's sphere.
const MAX_SEGMENTS: u32 = 1024;
const MAX_RINGS: u32 = 512;

/// One line for a TOML error: the message and the line it is on (for scene and sweep
/// files alike).
pub(crate) fn toml_detail(text: &str, e: &toml::de::Error) -> String {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let message = e.message().trim().replace('\n', " ");
    match line {
        Some(l) => format!("line {l}: {message}"),
        None => message,
    }
}

fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    Error::BadAsset {
        what: "scene file",
        path: path.into(),
        detail: toml_detail(text, e),
    }
}

impl SceneFile {
    /// Parses a scene file's text (`path` names it in errors).
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| toml_error(path, text, &e))
    }

    /// The file as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("scene files serialize")
    }

    /// Builds the scene; model paths resolve against `dir`, errors name `path`.
    pub fn build(&self, path: &Path, dir: &Path) -> Result<Scene> {
        self.build_with(path, dir, &mut Models::default())
    }

    /// `build`, reading each model file through `models` (once, however many instances
    /// and bodies name it).
    fn build_with(&self, path: &Path, dir: &Path, models: &mut Models) -> Result<Scene> {
        let name = self.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        });
        let mut build = Build {
            path,
            dir,
            b: SceneBuilder::new(&name),
            ids: Vec::new(),
            models,
        };
        build.materials(&self.materials)?;
        if self.instances.is_empty() {
            return Err(build.bad("no [[instance]]: the scene is empty".into()));
        }
        for (i, inst) in self.instances.iter().enumerate() {
            build.instance(i, inst)?;
        }
        for (i, body) in self.bodies.iter().enumerate() {
            build.body(i, body)?;
        }
        for (i, c) in self.cloths.iter().enumerate() {
            build.cloth(i, c)?;
        }
        if let Some(sp) = &self.spawn {
            build.spawn(sp)?;
        }
        let (c, s, b) = (&self.camera, &self.sun, &mut build.b);
        b.camera(Camera {
            position: Vec3::from(c.position),
            target: Vec3::from(c.target),
            up: Vec3::Y,
            fov_y_deg: c.fov,
            near: c.near,
            far: c.far,
        });
        b.light(Light {
            direction: Vec3::from(s.direction),
            color: Vec3::from(s.color),
            intensity: s.intensity,
        });
        if let Some(sky) = &self.sky {
            b.sky(Sky {
                zenith: Vec3::from(sky.zenith),
                horizon: Vec3::from(sky.horizon),
            });
        }
        // What the checks find is in this file: name it, not only the scene.
        build.b.build().map_err(|e| match e {
            Error::BadGeometry { detail, .. } => bad_file(path, detail),
            e => e,
        })
    }
}

fn bad_file(path: &Path, detail: String) -> Error {
    Error::BadAsset {
        what: "scene file",
        path: path.into(),
        detail,
    }
}

/// The model files a scene file's build has read, by path (as canonical as the file
/// system makes it, so `t.obj` and `./t.obj` are one file): each is read and parsed
/// once, however many instances and bodies name it.
#[derive(Default)]
struct Models {
    read: Vec<(std::path::PathBuf, std::rc::Rc<Scene>)>,
}

impl Models {
    fn get(&mut self, path: &Path) -> Result<std::rc::Rc<Scene>> {
        let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some((_, m)) = self.read.iter().find(|(k, _)| *k == key) {
            return Ok(m.clone());
        }
        let m = std::rc::Rc::new(super::load_model(path)?);
        self.read.push((key, m.clone()));
        Ok(m)
    }
}

/// A scene file being built: the builder, the materials by name so far, and the model
/// files read so far.
struct Build<'a> {
    path: &'a Path,
    dir: &'a Path,
    b: SceneBuilder,
    ids: Vec<(String, u32)>,
    models: &'a mut Models,
}

impl Build<'_> {
    fn bad(&self, detail: String) -> Error {
        bad_file(self.path, detail)
    }

    fn id(&self, name: &str) -> Option<u32> {
        self.ids.iter().find(|(n, _)| n == name).map(|(_, id)| *id)
    }

    fn materials(&mut self, materials: &[MaterialDesc]) -> Result<()> {
        for m in materials {
            if self.id(&m.name).is_some() {
                return Err(self.bad(format!("material '{}' is defined twice", m.name)));
            }
            let (mut material, note) = Material::new(&m.name, m.base_color, m.roughness, m.reflectivity)
                .metal(m.metallic)
                .clamped();
            if let Some(note) = note {
                self.b.warn(format!("{} in '{}'", note, self.path.display()));
            }
            // A texture that cannot be read fails the scene, named with its material.
            let (dir, path) = (self.dir, self.path);
            let load = |file: &String| {
                super::texture::load(&dir.join(file)).map_err(|e| bad_file(path, format!("material '{}': {e}", m.name)))
            };
            if let Some(file) = &m.texture {
                let t = load(file)?;
                material.texture = Some(self.b.texture(t));
            }
            if let Some(file) = &m.roughness_texture {
                // Blue 1: the G-buffer reads glTF's layout (blue x metallic).
                let mut t = load(file)?;
                t.image.pixels_mut().for_each(|p| p.0[2] = 255);
                let t = super::texture::data_texture(t);
                material.roughness_texture = Some(self.b.texture(t));
            }
            let id = self.b.material(material);
            self.ids.push((m.name.clone(), id));
        }
        Ok(())
    }

    fn instance(&mut self, i: usize, inst: &Instance) -> Result<()> {
        let shapes = [
            inst.plane.is_some(),
            inst.cuboid.is_some(),
            inst.sphere.is_some(),
            inst.model.is_some(),
        ];
        if shapes.iter().filter(|s| **s).count() != 1 {
            return Err(self.bad(format!(
                "instance {}: give exactly one of plane, box, sphere, model",
                i + 1
            )));
        }
        let loaded = inst
            .model
            .as_ref()
            .map(|m| self.models.get(&self.dir.join(m)))
            .transpose()?;
        let find = |name: &str| {
            self.id(name).ok_or_else(|| {
                let known: Vec<&str> = self.ids.iter().map(|(n, _)| n.as_str()).collect();
                self.bad(format!(
                    "instance {}: unknown material '{name}' (materials: {})",
                    i + 1,
                    known.join(", ")
                ))
            })
        };
        let transform = inst.transform();
        let plays = inst.animation.is_some() || inst.speed.is_some() || inst.looping.is_some();
        if let (Some(model), Some(scene)) = (&inst.model, loaded) {
            let material = inst.material.as_deref().map(find).transpose()?;
            match (&scene.animated, &self.b.scene.animated) {
                (Some(_), Some(_)) => {
                    return Err(self.bad(format!(
                        "instance {}: a second animated model ('{model}'); a scene plays one",
                        i + 1
                    )))
                }
                (None, _) if plays => {
                    return Err(self.bad(format!(
                        "instance {}: animation, speed and loop are for a model with animations; '{model}' has none",
                        i + 1
                    )))
                }
                _ => {}
            }
            self.b.append(&scene, transform, material);
            if scene.animated.is_some() {
                let a = self.b.scene.animated.as_mut().expect("appended");
                plays_as(a, inst).map_err(|e| self.bad(format!("instance {}: {e}", i + 1)))?;
            }
            return Ok(());
        }
        if plays {
            return Err(self.bad(format!(
                "instance {}: animation, speed and loop are for an animated model",
                i + 1
            )));
        }
        let mesh = if let Some([w, d]) = inst.plane {
            TriMesh::quad(w, d)
        } else if let Some(size) = inst.cuboid {
            TriMesh::cuboid(Vec3::from(size))
        } else {
            let r = inst.sphere.expect("one shape");
            let (segments, rings) = (inst.segments.unwrap_or(48), inst.rings.unwrap_or(24));
            // Bounded before tessellating (2 x 1024 x 512 = 1M triangles at most).
            if !(3..=MAX_SEGMENTS).contains(&segments) || !(2..=MAX_RINGS).contains(&rings) {
                return Err(self.bad(format!(
                    "instance {}: a sphere takes segments in 3..={MAX_SEGMENTS} and rings in 2..={MAX_RINGS}, not {segments} and {rings}",
                    i + 1
                )));
            }
            TriMesh::sphere(r, segments, rings)
        };
        let material = inst
            .material
            .as_deref()
            .ok_or_else(|| self.bad(format!("instance {}: a primitive needs a material", i + 1)))?;
        let material = find(material)?;
        self.b.mesh(mesh, transform, material);
        Ok(())
    }

    fn body(&mut self, i: usize, body: &BodyDesc) -> Result<()> {
        let shape = match (body.sphere, body.cuboid, &body.model) {
            (Some(radius), None, None) => super::BodyShape::Sphere { radius },
            (None, Some(size), None) => super::BodyShape::Cuboid { size: Vec3::from(size) },
            (None, None, Some(model)) => self.body_mesh(i, body, model)?,
            _ => return Err(self.bad(format!("body {}: give exactly one of sphere, box, model", i + 1))),
        };
        let material = self
            .id(&body.material)
            .ok_or_else(|| self.bad(format!("body {}: unknown material '{}'", i + 1, body.material)))?;
        let [x, y, z] = body.rotate.unwrap_or([0.0; 3]).map(f32::to_radians);
        self.b.body(super::Body {
            shape,
            material,
            density: body.density.unwrap_or(1000.0),
            restitution: body.restitution.unwrap_or(0.4),
            friction: body.friction.unwrap_or(0.5),
            position: Vec3::from(body.translate),
            rotation: glam::Quat::from_rotation_z(z) * glam::Quat::from_rotation_y(y) * glam::Quat::from_rotation_x(x),
            velocity: Vec3::from(body.velocity.unwrap_or([0.0; 3])),
            angular_velocity: Vec3::from(body.angular_velocity.unwrap_or([0.0; 3])),
        });
        Ok(())
    }

    /// A model body's shape: the model centred on its bounds and scaled, with a hull
    /// or mesh collider.
    fn body_mesh(&mut self, i: usize, body: &BodyDesc, model: &str) -> Result<super::BodyShape> {
        let hull = match body.collider.as_deref() {
            None | Some("hull") => true,
            Some("mesh") => false,
            Some(other) => return Err(self.bad(format!("body {}: collider '{other}' is neither hull nor mesh", i + 1))),
        };
        let m = self.models.get(&self.dir.join(model))?;
        if m.animated.is_some() {
            return Err(self.bad(format!(
                "body {}: '{model}' is animated; an animated model plays as an [[instance]], not as a body",
                i + 1
            )));
        }
        let scale = body.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(self.bad(format!("body {}: scale {scale} must be > 0", i + 1)));
        }
        let (lo, hi) = m.bounds();
        let center = 0.5 * (lo + hi);
        let mesh = TriMesh {
            positions: m
                .vertices
                .iter()
                .map(|v| (Vec3::from(v.position) - center) * scale)
                .collect(),
            normals: m.vertices.iter().map(|v| Vec3::from(v.normal)).collect(),
            uvs: m.uvs.iter().map(|t| glam::Vec2::from(*t)).collect(),
            indices: m.indices.clone(),
        };
        let radius = mesh.positions.iter().map(|p| p.length()).fold(0.0f32, f32::max);
        Ok(super::BodyShape::Mesh {
            mesh: self.b.body_mesh(mesh),
            hull,
            radius,
        })
    }

    fn cloth(&mut self, i: usize, c: &ClothDesc) -> Result<()> {
        let material = self
            .id(&c.material)
            .ok_or_else(|| self.bad(format!("cloth {}: unknown material '{}'", i + 1, c.material)))?;
        self.b.cloth(crate::scene::cloth::Cloth {
            size: c.size,
            resolution: c.resolution,
            center: Vec3::from(c.center),
            pins: c.pins.unwrap_or(crate::scene::cloth::Pins::None),
            stiffness: c.stiffness.unwrap_or(0.9),
            iterations: c.iterations.unwrap_or(16),
            material,
            spheres: c.spheres.iter().map(|s| glam::Vec4::from(*s)).collect(),
            floor_y: c.floor.unwrap_or(0.0),
        });
        Ok(())
    }

    fn spawn(&mut self, sp: &SpawnDesc) -> Result<()> {
        if sp.count == 0 || sp.count > super::MAX_BODIES {
            return Err(self.bad(format!(
                "spawn: count {} is outside 1..={}",
                sp.count,
                super::MAX_BODIES
            )));
        }
        if !(sp.size.is_finite() && sp.size > 0.0) {
            return Err(self.bad(format!("spawn: size {} must be > 0", sp.size)));
        }
        let materials = sp
            .materials
            .iter()
            .map(|name| {
                self.id(name)
                    .ok_or_else(|| self.bad(format!("spawn: unknown material '{name}'")))
            })
            .collect::<Result<Vec<u32>>>()?;
        if materials.is_empty() {
            return Err(self.bad("spawn: give at least one material".into()));
        }
        let spawn = super::Spawn {
            count: sp.count,
            size: sp.size,
            center: Vec3::from(sp.center),
            materials,
        };
        for body in spawn.bodies() {
            self.b.body(body);
        }
        self.b.spawn(spawn);
        Ok(())
    }
}

/// Reads and builds a scene file.
pub fn load(path: &Path) -> Result<Scene> {
    let text = crate::error::read_text(path, "scene file", crate::error::bounds::TEXT)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    SceneFile::parse(path, &text)?.build(path, &dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "[camera]\nposition = [0, 2, 6]\ntarget = [0, 0, 0]\nfov = 50\n\
        [sun]\ndirection = [0, 1, 0]\ncolor = [1, 1, 1]\nintensity = 2\n\
        [[materials]]\nname = \"m\"\nbase_color = [0.5, 0.5, 0.5]\nroughness = 0.2\nreflectivity = 0.5\n";

    fn build(text: &str, dir: &Path) -> Result<Scene> {
        let path = dir.join("s.toml");
        SceneFile::parse(&path, text)?.build(&path, dir)
    }

    /// Transforms compose as translate * Rz * Ry * Rx * scale.
    #[test]
    fn transform_order() {
        let inst = Instance {
            translate: Some([1.0, 2.0, 3.0]),
            rotate: Some([90.0, 0.0, 0.0]),
            scale: Some(Scale::Axes([2.0, 1.0, 1.0])),
            ..SceneFile::parse(
                Path::new("x"),
                &format!("{HEAD}[[instance]]\nplane = [1, 1]\nmaterial = \"m\"\n"),
            )
            .unwrap()
            .instances[0]
                .clone()
        };
        let p = inst.transform().transform_point3(Vec3::new(1.0, 1.0, 0.0));
        // Scaled to (2, 1, 0), rotated about x by 90 degrees to (2, 0, 1), moved.
        assert!((p - Vec3::new(3.0, 2.0, 4.0)).length() < 1e-6, "{p}");
    }

    /// A model instance places the file's triangles with the transform, and a material
    /// override replaces the file's materials.
    #[test]
    fn model_instances_are_transformed_and_overridden() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let text = format!(
            "{HEAD}[[instance]]\nmodel = \"t.obj\"\ntranslate = [10, 0, 0]\nscale = 2\n\
             [[instance]]\nmodel = \"t.obj\"\nmaterial = \"m\"\n"
        );
        let s = build(&text, dir.path()).unwrap();
        assert_eq!(s.triangle_count(), 2);
        let (lo, hi) = s.bounds();
        assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(12.0, 2.0, 0.0)));
        // The first instance brings the OBJ's default material; the second uses "m".
        assert_eq!(s.vertices[3].material, 0, "overridden with 'm'");
        assert_eq!(s.materials[s.vertices[0].material as usize].name, "default");
    }

    /// Twelve instances and a body of one model (named two ways) read the file once,
    /// and place twelve copies of its triangles.
    #[test]
    fn each_model_file_is_read_once() {
        let dir = tempfile::tempdir().unwrap();
        let tetrahedron = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";
        std::fs::write(dir.path().join("t.obj"), tetrahedron).unwrap();
        let mut text = HEAD.to_string();
        for i in 0..12 {
            let name = if i % 2 == 0 { "t.obj" } else { "./t.obj" };
            text += &format!("[[instance]]\nmodel = \"{name}\"\ntranslate = [{i}, 0, 0]\n");
        }
        text += "[[body]]\nmodel = \"t.obj\"\nmaterial = \"m\"\ntranslate = [0, 5, 0]\n";
        let file = SceneFile::parse(Path::new("s.toml"), &text).unwrap();
        let mut models = Models::default();
        let s = file.build_with(Path::new("s.toml"), dir.path(), &mut models).unwrap();
        assert_eq!(models.read.len(), 1, "one file, read once");
        assert_eq!(s.triangle_count(), 12 * 4, "twelve instances");
        assert_eq!(s.bodies.len(), 1);
    }

    /// Bad files get one line naming the file, the line and the field.
    #[test]
    fn bad_files_name_the_line_and_field() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            (
                format!("{HEAD}[[instance]]\nplane = [1, 1]\nmaterial = \"m\"\ncolour = 3\n"),
                "line 17: unknown field `colour`",
            ),
            (
                format!("{HEAD}[[instance]]\nplane = [1, 1]\nmaterial = \"nope\"\n"),
                "unknown material 'nope'",
            ),
            (
                format!("{HEAD}[[instance]]\nplane = [1, 1]\nsphere = 1\nmaterial = \"m\"\n"),
                "exactly one of",
            ),
            (format!("{HEAD}[[instance]]\nplane = [1, 1]\n"), "needs a material"),
            (format!("{HEAD}[[instance]]\nmodel = \"missing.obj\"\n"), "missing.obj"),
            (HEAD.replace("fov = 50", "fov = \"wide\""), "line 4"),
            (HEAD.to_string(), "missing field `instance`"),
        ];
        for (text, needle) in cases {
            let e = build(&text, dir.path()).unwrap_err().to_string();
            assert!(e.contains(needle) && !e.contains('\n'), "{needle}: {e}");
        }
    }

    /// A body may be a model (centred, scaled, a hull or a mesh collider); an unknown
    /// collider kind is an error naming it.
    #[test]
    fn model_bodies_are_centred_and_scaled() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("tri.obj"), "v 2 0 0\nv 4 0 0\nv 2 2 0\nf 1 2 3\n").unwrap();
        let text = |collider: &str| {
            format!(
                "[camera]\nposition = [0.0, 1.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 50.0\n\
                 [sun]\ndirection = [0.0, 1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\nintensity = 1.0\n\
                 [[materials]]\nname = \"m\"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\n\
                 [[instance]]\nplane = [4.0, 4.0]\nmaterial = \"m\"\n\
                 [[body]]\nmodel = \"tri.obj\"\ncollider = \"{collider}\"\nscale = 0.5\nmaterial = \"m\"\n\
                 translate = [0.0, 2.0, 0.0]\n"
            )
        };
        let s = build(&text("mesh"), dir.path()).unwrap();
        match s.bodies[0].shape {
            crate::scene::BodyShape::Mesh { mesh, hull, radius } => {
                assert!(!hull);
                let m = &s.body_meshes[mesh as usize];
                let xs: Vec<f32> = m.positions.iter().map(|p| p.x).collect();
                assert_eq!(xs, [-0.5, 0.5, -0.5], "centred on the bounds, half size");
                assert!((radius - 0.5f32.hypot(0.5)).abs() < 1e-6);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(s.dynamic_triangle_count(), 1);
        let e = build(&text("blob"), dir.path()).unwrap_err().to_string();
        assert!(e.contains("collider 'blob'"), "{e}");
    }

    /// The complete example of `docs/scenes.md` is a valid scene file (with a model in place).
    #[test]
    fn documented_example_builds() {
        let readme = include_str!("../../docs/scenes.md");
        let start = readme.find("## Scene files").expect("the section");
        let block = &readme[start..];
        let toml_start = block.find("```toml\n").expect("an example") + 8;
        let text = &block[toml_start..toml_start + block[toml_start..].find("```").unwrap()];
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("models")).unwrap();
        std::fs::write(
            dir.path().join("models/teapot.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::create_dir(dir.path().join("textures")).unwrap();
        let tiles = image::RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 30) as u8, (y * 30) as u8, 128]));
        tiles.save(dir.path().join("textures/tiles.jpg")).unwrap();
        let rough = image::GrayImage::from_fn(4, 4, |x, y| image::Luma([((x + y) * 30) as u8]));
        rough.save(dir.path().join("textures/tiles_rough.png")).unwrap();
        let s = build(text, dir.path()).unwrap();
        assert_eq!(s.name, "teapot on a mirror");
        assert_eq!(s.triangle_count(), 2 + 12 + 1);
        assert_eq!(s.textures.len(), 2);
        let mirror = &s.materials[0];
        assert_eq!((mirror.metallic, mirror.reflectivity, mirror.texture), (1.0, 1.0, None));
        assert_eq!(
            (s.materials[1].texture, s.materials[1].roughness_texture),
            (Some(0), Some(1))
        );
    }
}
