//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`) through the
//! `gltf` crate: the default scene's node hierarchy with its transforms, indexed (or
//! not) triangle primitives, normals (computed by `geometry::smooth_normals` when
//! absent), texture coordinates, and the metallic-roughness materials.
//!
//! Material mapping: albedo = `baseColorFactor.rgb`, multiplied per texel by
//! `baseColorTexture` (sampled with the texture coordinate set it names; sampler
//! wrap modes and `KHR_texture_transform` are not read: textures repeat); roughness =
//! `roughnessFactor`; metallic = `metallicFactor`; reflectivity (the traced mirror
//! share of the specular reflection) = `reflectivity_from_roughness(roughnessFactor)`.

use super::geometry::{smooth_normals, CREASE_ANGLE_DEG};
use super::Texture;
use super::{Camera, Material, Scene, SceneBuilder, TriMesh};
use crate::error::{Error, Result};
use glam::{Mat4, Vec2, Vec3};
use std::path::Path;

/// Roughness at and above which a PBR material (glTF, MTL with `Pr`) gets no traced
/// mirror reflection.
pub const MIRROR_ROUGHNESS_MAX: f32 = 0.6;

/// The traced mirror share of a PBR material's specular reflection: 1 for a perfectly
/// smooth surface, falling linearly to 0 at `MIRROR_ROUGHNESS_MAX` (Speculum traces
/// sharp reflections only; a rougher surface's blurred one is left to the sky term).
pub fn reflectivity_from_roughness(roughness: f32) -> f32 {
    (1.0 - roughness / MIRROR_ROUGHNESS_MAX).clamp(0.0, 1.0)
}

/// A decoded glTF image as sRGB RGBA8 texels: 8- and 16-bit images with one to four
/// channels (grey is spread to RGB, a missing alpha is opaque); `None` for float ones.
fn image_rgba8(data: &gltf::image::Data) -> Option<image::RgbaImage> {
    use gltf::image::Format as F;
    let (channels, bytes) = match data.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        _ => return None,
    };
    // 16-bit channels are little-endian; their high byte is the 8-bit value.
    let at = |t: &[u8], c: usize| t[c * bytes + bytes - 1];
    let texels: Vec<u8> = data
        .pixels
        .chunks_exact(channels * bytes)
        .flat_map(|t| match channels {
            1 => [at(t, 0), at(t, 0), at(t, 0), 255],
            2 => [at(t, 0), at(t, 0), at(t, 0), at(t, 1)],
            3 => [at(t, 0), at(t, 1), at(t, 2), 255],
            _ => [at(t, 0), at(t, 1), at(t, 2), at(t, 3)],
        })
        .collect();
    image::RgbaImage::from_raw(data.width, data.height, texels).filter(|i| i.width() > 0 && i.height() > 0)
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
    // glTF material index (None: the default material) → scene material and the
    // texture coordinate set its base colour texture uses.
    let mut ids: Vec<(Option<usize>, u32, u32)> = Vec::new();
    // glTF image index → scene texture (None: not usable, warned about once).
    let mut textures: Vec<(usize, Option<u32>)> = Vec::new();
    let file = path.display().to_string();
    let mut material_id = |b: &mut SceneBuilder, warnings: &mut Vec<String>, m: gltf::Material<'_>| -> (u32, u32) {
        if let Some(&(_, id, set)) = ids.iter().find(|(i, _, _)| *i == m.index()) {
            return (id, set);
        }
        let pbr = m.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        let name = m.name().map(str::to_string).unwrap_or_else(|| match m.index() {
            Some(i) => format!("material {i}"),
            None => "default".into(),
        });
        let roughness = pbr.roughness_factor();
        let mut material = Material::new(
            &name,
            [f[0], f[1], f[2]],
            roughness,
            reflectivity_from_roughness(roughness),
        )
        .metal(pbr.metallic_factor());
        let mut set = 0;
        if let Some(info) = pbr.base_color_texture() {
            let image = info.texture().source().index();
            let texture = match textures.iter().find(|(i, _)| *i == image) {
                Some(&(_, t)) => t,
                None => {
                    let t = match images.get(image).and_then(image_rgba8) {
                        Some(img) => Some(b.texture(Texture {
                            name: format!("{file} image {image}"),
                            image: img,
                        })),
                        None => {
                            warnings.push(format!(
                                "image {image}: not 8- or 16-bit; material '{name}' uses its base colour factor alone"
                            ));
                            None
                        }
                    };
                    textures.push((image, t));
                    t
                }
            };
            material.texture = texture;
            set = info.tex_coord();
        }
        let id = b.material(material);
        ids.push((m.index(), id, set));
        (id, set)
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
            let (id, set) = material_id(&mut b, &mut warnings, prim.material());
            let uvs: Vec<Vec2> = match reader.read_tex_coords(set) {
                Some(t) => t.into_f32().map(Vec2::from).collect(),
                None => Vec::new(),
            };
            if uvs.len() != positions.len() && !uvs.is_empty() {
                return Err(bad(format!(
                    "mesh '{}' has {} texture coordinates for {} positions",
                    mesh.name().unwrap_or("(unnamed)"),
                    uvs.len(),
                    positions.len()
                )));
            }
            let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
            let tri = match normals {
                Some(normals) if normals.len() == positions.len() => TriMesh {
                    positions,
                    normals: normals.into_iter().map(|n| n.normalize_or(Vec3::Y)).collect(),
                    uvs,
                    indices,
                },
                _ => smooth_normals(&positions, &uvs, &indices, CREASE_ANGLE_DEG),
            };
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
