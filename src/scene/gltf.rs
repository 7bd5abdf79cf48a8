//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`) through the
//! `gltf` crate: the default scene's node hierarchy with its transforms, indexed (or
//! not) triangle primitives, normals (computed by `geometry::smooth_normals` when
//! absent), and the metallic-roughness materials.
//!
//! Material mapping: albedo = `baseColorFactor.rgb`, times the mean colour of
//! `baseColorTexture` (textures are not sampled per texel yet); roughness =
//! `roughnessFactor`; reflectivity = `metallicFactor` (a metal reflects, a dielectric
//! does not until Fresnel weighting lands). UVs are not read yet.

use super::geometry::{smooth_normals, CREASE_ANGLE_DEG};
use super::{Camera, Material, Scene, SceneBuilder, TriMesh};
use crate::error::{Error, Result};
use glam::{Mat4, Vec3};
use std::path::Path;

/// Mean linear colour of an 8-bit RGB(A) image (sRGB-encoded texels), if it is one.
fn image_mean(data: &gltf::image::Data) -> Option<Vec3> {
    let channels = match data.format {
        gltf::image::Format::R8G8B8 => 3,
        gltf::image::Format::R8G8B8A8 => 4,
        _ => return None,
    };
    let mut sum = [0.0f64; 3];
    let texels = data.pixels.chunks_exact(channels);
    let n = texels.len().max(1) as f64;
    for t in texels {
        for c in 0..3 {
            sum[c] += (t[c] as f64 / 255.0).powf(2.2);
        }
    }
    Some(Vec3::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32))
}

/// Loads a glTF or GLB file as a scene with the camera framing it.
pub fn load(path: &Path) -> Result<Scene> {
    let bad = |detail: String| Error::BadAsset {
        what: "glTF file",
        path: path.into(),
        detail,
    };
    if !path.exists() {
        return Err(Error::Io {
            what: "glTF file",
            path: path.into(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        });
    }
    let (doc, buffers, images) = gltf::import(path).map_err(|e| bad(e.to_string()))?;
    let mut b = SceneBuilder::new(&path.display().to_string());
    let mut warnings = Vec::new();
    // glTF material index (None: the default material) → scene material.
    let mut ids: Vec<(Option<usize>, u32)> = Vec::new();
    let mut material_id = |b: &mut SceneBuilder, warnings: &mut Vec<String>, m: gltf::Material<'_>| -> u32 {
        if let Some(&(_, id)) = ids.iter().find(|(i, _)| *i == m.index()) {
            return id;
        }
        let pbr = m.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        let mut albedo = Vec3::new(f[0], f[1], f[2]);
        if let Some(info) = pbr.base_color_texture() {
            match images.get(info.texture().source().index()).and_then(image_mean) {
                Some(mean) => albedo *= mean,
                None => warnings.push(format!(
                    "material '{}': its base colour texture is not 8-bit RGB(A); the factor alone is used",
                    m.name().unwrap_or("(unnamed)")
                )),
            }
        }
        let name = m.name().map(str::to_string).unwrap_or_else(|| match m.index() {
            Some(i) => format!("material {i}"),
            None => "default".into(),
        });
        let material = Material::new(&name, albedo.to_array(), pbr.roughness_factor(), pbr.metallic_factor());
        let id = b.material(material);
        ids.push((m.index(), id));
        id
    };
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| bad("no scene".into()))?;
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        stack.extend(node.children().map(|c| (c, m)));
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                warnings.push(format!(
                    "mesh '{}': a {:?} primitive is skipped (triangles only)",
                    mesh.name().unwrap_or("(unnamed)"),
                    prim.mode()
                ));
                continue;
            }
            let reader = prim.reader(|buf| buffers.get(buf.index()).map(|d| &d.0[..]));
            let Some(positions) = reader.read_positions() else {
                return Err(bad(format!(
                    "mesh '{}' has no positions",
                    mesh.name().unwrap_or("(unnamed)")
                )));
            };
            let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(bad(format!("an index {i} is past the {} positions", positions.len())));
            }
            let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
            let tri = match normals {
                Some(normals) if normals.len() == positions.len() => TriMesh {
                    positions,
                    normals: normals.into_iter().map(|n| n.normalize_or(Vec3::Y)).collect(),
                    indices,
                },
                _ => smooth_normals(&positions, &indices, CREASE_ANGLE_DEG),
            };
            let id = material_id(&mut b, &mut warnings, prim.material());
            b.mesh(tri, m, id);
        }
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "gltf".into());
    let mut scene = b.build()?;
    let (lo, hi) = scene.bounds();
    scene.camera = Camera::framing(lo, hi);
    scene.name = name;
    scene.warnings = warnings;
    Ok(scene)
}
