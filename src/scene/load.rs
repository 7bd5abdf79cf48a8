//! Loading a scene, top-down: `load_with` looks at the name once and takes one of
//! three roads, each read in one place —
//!
//! 1. a built-in name (`builtin::by_name`): its scene file, compiled in (the gallery's
//!    made as a `SceneFile` value), built as any scene file is;
//! 2. a scene file (`assets/scenes/NAME.toml`, or a `.toml` path: `file::load`): parsed
//!    (`SceneFile::parse`), then built (`SceneFile::build`): materials, instances (each
//!    model file read once however many instances name it: `file::Models`, through
//!    `load_model`), bodies, cloths, the spawn, camera and sun, into a `SceneBuilder`;
//! 3. a model file (`load_model`: OBJ, glTF, PLY), which stands on a `Floor`
//!    (`stand_on_floor`).
//!
//! Every road ends in `SceneBuilder::build`, which validates the scene (`Scene::validate`)
//! before anything else sees it.

use super::builder::SceneBuilder;
use super::{builtin, file, gltf, obj, ply, Camera, Material, Scene, TriMesh};
use crate::error::{Error, Result};
use glam::{Mat4, Vec3};

/// Scene file formats `load` reads, by extension.
pub const FORMATS: &str = ".toml, .obj, .gltf, .glb, .ply";

/// Model file formats (a model stands on a floor as a scene; a scene file places it).
const MODELS: [&str; 4] = ["obj", "gltf", "glb", "ply"];

/// Loads a scene as `load_with`, a bare model on a mirror floor.
pub fn load(name_or_path: &str) -> Result<Scene> {
    load_with(name_or_path, Floor::Mirror)
}

/// Loads a scene: a built-in name, `assets/scenes/NAME.toml` under the current folder,
/// a path to a scene file (`.toml`), or a path to a model (`.obj`), which stands on
/// `floor` with the camera framing it.
pub fn load_with(name_or_path: &str, floor: Floor) -> Result<Scene> {
    if let Some(scene) = builtin::by_name(name_or_path) {
        return scene;
    }
    let path = std::path::Path::new(name_or_path);
    let in_assets = std::path::Path::new("assets/scenes").join(format!("{name_or_path}.toml"));
    if path.extension().is_none() && !name_or_path.contains('/') && in_assets.is_file() {
        return file::load(&in_assets);
    }
    let looks_like_path = path.extension().is_some() || name_or_path.contains('/') || path.exists();
    if !looks_like_path {
        return Err(Error::UnknownScene {
            name: name_or_path.into(),
            known: builtin::NAMES.join(", "),
        });
    }
    match extension(path).as_deref() {
        Some("toml") => file::load(path),
        Some("obj" | "gltf" | "glb" | "ply") => stand_on_floor(load_model(path)?, floor),
        other => Err(unsupported("scene", other, path, FORMATS)),
    }
}

/// Loads a model file (OBJ with its MTL, or PLY) by its extension.
pub fn load_model(path: &std::path::Path) -> Result<Scene> {
    match extension(path).as_deref() {
        Some("obj") => obj::load(path),
        Some("ply") => ply::load(path),
        Some("gltf" | "glb") => gltf::load(path),
        other => Err(unsupported("model", other, path, ".obj, .gltf, .glb, .ply")),
    }
}

/// Puts a model on a square floor `floor` under its lowest point, 8x its footprint
/// wide; on a mirror, the camera frames the model and the upper half of its
/// reflection (the far plane taking in the floor).
fn stand_on_floor(mut scene: Scene, floor: Floor) -> Result<Scene> {
    let material = match floor {
        Floor::None => return scene.validate().map(|_| scene),
        Floor::Mirror => Material::new("floor (mirror)", [0.6, 0.6, 0.62], 0.03, 1.0).metal(1.0),
        Floor::Matte => Material::new("floor (matte)", [0.55, 0.55, 0.55], 0.9, 0.0),
    };
    let (lo, hi) = scene.bounds();
    let size = hi - lo;
    let side = 8.0 * size.x.max(size.z).max(size.y).max(1e-3);
    // A hair below the lowest point: a flat-bottomed model does not z-fight the floor.
    let y = lo.y - 1e-4 * size.max_element().max(1e-3);
    let center = Vec3::new(0.5 * (lo.x + hi.x), y, 0.5 * (lo.z + hi.z));
    if floor == Floor::Mirror {
        // Frame the model with the upper half of its reflection: the floor's point.
        scene.camera = Camera::framing(Vec3::new(lo.x, y - 0.5 * size.y, lo.z), hi);
    }
    scene.camera.far = scene.camera.far.max((scene.camera.position - center).length() + side);
    let mut b = SceneBuilder { scene };
    let id = b.material(material);
    b.mesh(TriMesh::quad(side, side), Mat4::from_translation(center), id);
    b.build()
}

/// The ground a bare model (a model file given as the scene) stands on (`about` says
/// what each is).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Floor {
    None,
    #[default]
    Mirror,
    Matte,
}

impl Floor {
    pub const ALL: [Floor; 3] = [Floor::None, Floor::Mirror, Floor::Matte];

    pub fn name(self) -> &'static str {
        match self {
            Floor::None => "none",
            Floor::Mirror => "mirror",
            Floor::Matte => "matte",
        }
    }

    /// What the floor is, in a line (the CLI's help).
    pub fn about(self) -> &'static str {
        match self {
            Floor::None => "No floor: the model alone",
            Floor::Mirror => "A mirror-like floor (the default), so the model has a reflection to show",
            Floor::Matte => "A rough, non-reflective floor",
        }
    }
}

/// Whether `name_or_path` names a model file (which stands on a `Floor`) rather than a
/// built-in scene or a scene file.
pub fn is_model(name_or_path: &str) -> bool {
    let ext = std::path::Path::new(name_or_path).extension().and_then(|e| e.to_str());
    ext.is_some_and(|e| MODELS.iter().any(|m| e.eq_ignore_ascii_case(m))) && builtin::by_name(name_or_path).is_none()
}

/// A path's extension, lower-cased.
fn extension(path: &std::path::Path) -> Option<String> {
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase)
}

/// "unsupported scene format '.xyz' in 'f.xyz' (supported: ...)".
fn unsupported(kind: &str, ext: Option<&str>, path: &std::path::Path, supported: &str) -> Error {
    let ext = ext.map(|e| format!(".{e}")).unwrap_or_else(|| "(no extension)".into());
    Error::Input(format!(
        "unsupported {kind} format '{ext}' in '{}' (supported: {supported})",
        path.display()
    ))
}
