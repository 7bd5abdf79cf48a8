//! OBJ + MTL loading through tobj.
//!
//! Material mapping (MTL → Speculum):
//! - albedo = `Kd` (grey 0.8 without one), multiplied per texel by the `map_Kd`
//!   texture when the material has one (PNG or JPEG; a missing file is a warning and
//!   the material is untextured, one that does not decode an error);
//! - roughness = `Pr` when given, else `sqrt(2 / (Ns + 2))` (the Blinn-Phong exponent
//!   to Beckmann roughness mapping), else 0.8;
//! - metallic = `Pm` when given; else 1 for a coloured `Ks` (channels differing by more
//!   than a quarter of the largest: a metal's tinted reflection, as gold MTLs give) with
//!   a reflection model (`illum` 3-9), the base colour then `Ks`; else 0;
//! - reflectivity (the traced share of the specular reflection) = `refl` (a Speculum
//!   key) when given; else 1 with `Pr` (a PBR material: the roughness cut-offs judge
//!   it, as for glTF); else `max(Ks)` for illumination models 3-9 (the MTL models with
//!   reflection on); else 0.
//!
//! Faces are triangulated; texture coordinates are read with v flipped (OBJ's v runs
//! up the image, Speculum's down); missing normals are computed by `geometry::smooth_normals`
//! (equal positions welded, angle-weighted, creases sharper than 60 degrees kept).
//! A missing MTL file is a warning, its materials the default; `map_Kd` options are
//! skipped to the file name.

use super::geometry::{smooth_normals, CREASE_ANGLE_DEG};
use super::texture;
use super::{Camera, Material, Scene, SceneBuilder, TriMesh};
use crate::error::{Error, Result};
use glam::{Mat4, Vec2, Vec3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn mtl_number(m: &tobj::Material, key: &str) -> Option<f32> {
    m.unknown_param.get(key).and_then(|v| v.trim().parse::<f32>().ok())
}

/// The file name of a texture statement's arguments (`map_Kd -s 2 2 1 -bm 0.5 a b.png`
/// → `a b.png`): the MTL options before it are skipped with their arguments (`-o`,
/// `-s`, `-t` take one to three numbers, `-mm` two, the others one).
fn texture_file(spec: &str) -> Option<String> {
    let tokens: Vec<&str> = spec.split_whitespace().collect();
    let mut i = 0;
    while i < tokens.len() && tokens[i].starts_with('-') {
        let option = tokens[i];
        i += 1;
        match option {
            "-o" | "-s" | "-t" => {
                let numbers = tokens[i..]
                    .iter()
                    .take(3)
                    .take_while(|t| t.parse::<f32>().is_ok())
                    .count();
                i += numbers.max(1);
            }
            "-mm" => i += 2,
            _ => i += 1,
        }
    }
    let name = tokens.get(i..).map(|t| t.join(" ")).unwrap_or_default();
    (!name.is_empty()).then_some(name)
}

/// Out-of-range values of a material that `Material::gpu` will clamp, described for
/// one warning line (empty when every value is in range).
fn out_of_range(m: &tobj::Material, roughness: f32, reflectivity: f32) -> Vec<String> {
    let mut notes = Vec::new();
    let unit = |v: f32| (0.0..=1.0).contains(&v);
    for (key, c) in [("Kd", m.diffuse), ("Ks", m.specular)] {
        if let Some(c) = c.filter(|c| !c.iter().all(|&v| unit(v))) {
            notes.push(format!("{key} {} {} {} clamped to [0, 1]", c[0], c[1], c[2]));
        }
    }
    if let Some(ns) = m.shininess.filter(|&ns| ns < 0.0) {
        notes.push(format!("Ns {ns} taken as 0"));
    }
    if !unit(roughness) {
        notes.push(format!("roughness {roughness} clamped to [0, 1]"));
    }
    if !unit(reflectivity) {
        notes.push(format!("reflectivity {reflectivity} clamped to [0, 1]"));
    }
    notes
}

/// The scene's textures by file, each loaded once.
#[derive(Default)]
struct Textures {
    by_path: HashMap<PathBuf, Option<u32>>,
}

impl Textures {
    /// The index of texture file `path` in `b`, loading it on first use; `None` (and a
    /// warning) when the file does not exist.
    fn get(&mut self, b: &mut SceneBuilder, path: PathBuf, warnings: &mut Vec<String>) -> Result<Option<u32>> {
        if let Some(&id) = self.by_path.get(&path) {
            return Ok(id);
        }
        let id = match texture::load(&path) {
            Ok(t) => Some(b.texture(t)),
            Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
                warnings.push(format!(
                    "texture '{}' not found: its materials use their colour alone",
                    path.display()
                ));
                None
            }
            Err(e) => return Err(e),
        };
        self.by_path.insert(path, id);
        Ok(id)
    }
}

/// A material of the MTL file `mtl` (for messages) with its `map_Kd` texture, already
/// loaded, and the warning its out-of-range values raise, if any.
fn convert_material(m: &tobj::Material, mtl: &Path, texture: Option<u32>) -> Result<(Material, Option<String>)> {
    let mut albedo = Vec3::from(m.diffuse.unwrap_or([0.8; 3]));
    let roughness = mtl_number(m, "Pr")
        .or_else(|| m.shininess.map(|ns| (2.0 / (ns.max(0.0) + 2.0)).sqrt()))
        .unwrap_or(0.8);
    let reflective_model = matches!(m.illumination_model, Some(3..=9));
    let reflectivity = mtl_number(m, "refl")
        .or_else(|| mtl_number(m, "Pr").map(|_| 1.0))
        .unwrap_or_else(|| {
            if reflective_model {
                m.specular.map_or(0.0, |s| s[0].max(s[1]).max(s[2]))
            } else {
                0.0
            }
        });
    let tinted = m.specular.filter(|s| {
        let (lo, hi) = (s[0].min(s[1]).min(s[2]), s[0].max(s[1]).max(s[2]));
        reflective_model && hi > 0.0 && hi - lo > 0.25 * hi
    });
    let metallic = match (mtl_number(m, "Pm"), tinted) {
        (Some(pm), _) => pm,
        (None, Some(ks)) => {
            albedo = Vec3::from(ks);
            1.0
        }
        (None, None) => 0.0,
    };
    let mut mat = Material::new(&m.name, albedo.to_array(), roughness, reflectivity).metal(metallic);
    mat.texture = texture;
    if !(mat.albedo.is_finite() && mat.roughness.is_finite() && mat.reflectivity.is_finite() && metallic.is_finite()) {
        return Err(Error::BadAsset {
            what: "MTL file",
            path: mtl.into(),
            detail: format!("material '{}' has a non-finite value", m.name),
        });
    }
    let notes = out_of_range(m, roughness, reflectivity);
    let warning =
        (!notes.is_empty()).then(|| format!("material '{}' in '{}': {}", m.name, mtl.display(), notes.join("; ")));
    Ok((mat, warning))
}

/// Colour statements need three numbers: tobj 4 panics on fewer, so they are checked
/// here first, with the line number in the error.
fn check_mtl_colors(bytes: &[u8], path: &Path) -> Result<()> {
    for (i, line) in String::from_utf8_lossy(bytes).lines().enumerate() {
        let mut parts = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke" | "Tf")) = parts.next() {
            let numbers: Vec<_> = parts.map(str::parse::<f32>).collect();
            if numbers.len() != 3 || numbers.iter().any(|n| n.is_err()) {
                return Err(Error::BadAsset {
                    what: "MTL file",
                    path: path.into(),
                    detail: format!("line {}: '{key}' needs three numbers, got '{}'", i + 1, line.trim()),
                });
            }
        }
    }
    Ok(())
}

/// `bytes` as UTF-8, any invalid sequence replaced by U+FFFD (no copy when valid).
fn utf8_lossy(bytes: Vec<u8>) -> Vec<u8> {
    match String::from_utf8(bytes) {
        Ok(s) => s.into_bytes(),
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned().into_bytes(),
    }
}

/// What tobj read of an OBJ file: its objects, its materials, the MTL files it named,
/// and a warning per MTL file that was missing.
struct Parsed {
    models: Vec<tobj::Model>,
    materials: Vec<tobj::Material>,
    mtl_files: Vec<PathBuf>,
    missing_mtl: Vec<String>,
}

/// Parses the OBJ `text` (of `path`), reading the MTL files it names from `dir`
/// (bounded, their colours checked); a missing MTL file is a warning, any other MTL
/// failure an error.
fn parse(path: &Path, text: &[u8], dir: &Path) -> Result<Parsed> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mtl_failure: RefCell<Option<Error>> = RefCell::new(None);
    let mtl_files: RefCell<Vec<PathBuf>> = RefCell::new(Vec::new());
    let missing_mtl: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut &text[..], &options, |mtl: &Path| {
        let mtl_path: PathBuf = dir.join(mtl);
        mtl_files.borrow_mut().push(mtl_path.clone());
        match crate::error::read_file(&mtl_path, "MTL file", crate::error::bounds::TEXT) {
            Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
                // A missing MTL is not fatal: its materials take the default.
                missing_mtl.borrow_mut().push(format!(
                    "MTL file '{}' not found: the materials of '{}' are the default grey",
                    mtl_path.display(),
                    path.display()
                ));
                Err(tobj::LoadError::OpenFileFailed)
            }
            Err(e) => {
                mtl_failure.replace(Some(e));
                Err(tobj::LoadError::OpenFileFailed)
            }
            Ok(bytes) => Ok(utf8_lossy(bytes))
                .and_then(|bytes| check_mtl_colors(&bytes, &mtl_path).map(|_| bytes))
                .map_err(|e| {
                    mtl_failure.replace(Some(e));
                    tobj::LoadError::MaterialParseError
                })
                .and_then(|bytes| tobj::load_mtl_buf(&mut bytes.as_slice()))
                .inspect_err(|e| {
                    if mtl_failure.borrow().is_some() {
                        return;
                    }
                    mtl_failure.replace(Some(Error::BadAsset {
                        what: "MTL file",
                        path: mtl_path.clone(),
                        detail: e.to_string(),
                    }));
                }),
        }
    })
    .map_err(|e| Error::BadAsset {
        what: "OBJ file",
        path: path.into(),
        detail: e.to_string(),
    })?;
    if let Some(e) = mtl_failure.into_inner() {
        return Err(e);
    }
    let missing_mtl = missing_mtl.into_inner();
    let materials = match materials {
        Ok(m) => m,
        Err(_) if !missing_mtl.is_empty() => Vec::new(),
        Err(e) => {
            return Err(Error::BadAsset {
                what: "MTL file",
                path: path.into(),
                detail: e.to_string(),
            })
        }
    };
    Ok(Parsed {
        models,
        materials,
        mtl_files: mtl_files.into_inner(),
        missing_mtl,
    })
}

/// Loads an OBJ file (and the MTL files it names) as a scene.
pub fn load(path: &Path) -> Result<Scene> {
    // OBJ is bytes: a comment (or a name) may hold anything, so bytes that are not
    // UTF-8 become U+FFFD instead of failing tobj's line reader.
    let text = utf8_lossy(crate::error::read_file(path, "OBJ file", crate::error::bounds::MODEL)?);
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let parsed = parse(path, &text, &dir)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into());
    let mut b = SceneBuilder::new(&path.display().to_string());
    // tobj does not say which MTL file a material came from: name the one file, or the
    // OBJ when it names several.
    let mtl = match parsed.mtl_files.as_slice() {
        [one] => one.clone(),
        _ => path.to_path_buf(),
    };
    let mut warnings = parsed.missing_mtl;
    let mut ids = Vec::new();
    let mut textures = Textures::default();
    for m in &parsed.materials {
        // Textures resolve against the OBJ's folder.
        let texture = match m.diffuse_texture.as_deref().and_then(texture_file) {
            Some(file) => textures.get(&mut b, dir.join(file), &mut warnings)?,
            None => None,
        };
        let (material, warning) = convert_material(m, &mtl, texture)?;
        ids.push(b.material(material));
        warnings.extend(warning);
    }
    let mut default_material = None;
    for model in &parsed.models {
        let Some(geometry) = object_mesh(path, model)? else {
            continue;
        };
        let material = match model.mesh.material_id.and_then(|i| ids.get(i)) {
            Some(&id) => id,
            None => *default_material.get_or_insert_with(|| b.material(Material::new("default", [0.8; 3], 0.8, 0.0))),
        };
        b.mesh(geometry, Mat4::IDENTITY, material);
    }
    let mut scene = b.build().map_err(|e| match e {
        Error::BadGeometry { detail, .. } => Error::BadGeometry {
            source_name: path.display().to_string(),
            detail,
        },
        other => other,
    })?;
    let (lo, hi) = scene.bounds();
    scene.camera = Camera::framing(lo, hi);
    scene.name = name;
    scene.warnings = warnings;
    Ok(scene)
}

/// One object's triangles (`None` when it has none): positions and texture coordinates
/// checked finite, the file's normals or smooth ones within the crease angle.
fn object_mesh(path: &Path, model: &tobj::Model) -> Result<Option<TriMesh>> {
    let mesh = &model.mesh;
    if mesh.indices.is_empty() {
        return Ok(None);
    }
    let bad = |detail: String| Error::BadGeometry {
        source_name: path.display().to_string(),
        detail,
    };
    let positions: Vec<Vec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(bad(format!(
            "object '{}' vertex {i} has a non-finite coordinate {:?}",
            model.name, positions[i]
        )));
    }
    let uvs: Vec<Vec2> = if mesh.texcoords.len() == 2 * positions.len() {
        mesh.texcoords
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0], 1.0 - t[1]))
            .collect()
    } else {
        Vec::new()
    };
    if let Some(i) = uvs.iter().position(|t| !t.is_finite()) {
        return Err(bad(format!(
            "object '{}' vertex {i} has non-finite texture coordinates {:?}",
            model.name, uvs[i]
        )));
    }
    if mesh.normals.len() != mesh.positions.len() {
        return Ok(Some(smooth_normals(&positions, &uvs, &mesh.indices, CREASE_ANGLE_DEG)));
    }
    let normals = mesh
        .normals
        .chunks_exact(3)
        .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or(Vec3::Y))
        .collect();
    Ok(Some(TriMesh {
        positions,
        normals,
        uvs,
        indices: mesh.indices.clone(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `map_Kd` options and their arguments are skipped; the file name may hold spaces.
    #[test]
    fn texture_options_are_skipped() {
        for (spec, want) in [
            ("wood.png", Some("wood.png")),
            ("-s 2 2 1 wood.png", Some("wood.png")),
            ("-o 0.5 wood.png", Some("wood.png")),
            ("-bm 0.3 -clamp on -mm 0 1 my wood.png", Some("my wood.png")),
            ("-t 1 1 -imfchan r w.png", Some("w.png")),
            ("-s 1 1 1", None),
            ("   ", None),
        ] {
            assert_eq!(texture_file(spec).as_deref(), want, "{spec}");
        }
    }
}
