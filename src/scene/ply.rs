//! PLY loading (ASCII and binary, through `ply-rs-bw`): the `vertex` element's `x`, `y`,
//! `z` (and `nx`, `ny`, `nz` when all present), the `face` element's `vertex_indices`
//! (or `vertex_index`) lists, fan-triangulated in file order. Without normals the mesh
//! gets `geometry::smooth_normals`. PLY has no materials: the model is the default grey
//! (vertex colours are not read).

use super::geometry::{smooth_normals, CREASE_ANGLE_DEG};
use super::{Camera, Material, Scene, SceneBuilder, TriMesh};
use crate::error::{Error, Result};
use glam::{Mat4, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;

/// Loads a PLY file as a scene with the camera framing it.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = crate::error::read_file(path, "PLY file", crate::error::bounds::MODEL)?;
    let bad = |detail: String| Error::BadAsset {
        what: "PLY file",
        path: path.into(),
        detail,
    };
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut bytes.as_slice())
        .map_err(|e| bad(e.to_string().replace('\n', " ")))?;
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| bad("no 'vertex' element".into()))?;
    let scalar = |v: &DefaultElement, k: &str| v.get(k).and_then(Property::to_f32_lossy);
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let p = ["x", "y", "z"].map(|k| scalar(v, k));
        let [Some(x), Some(y), Some(z)] = p else {
            return Err(bad(format!("vertex {i} lacks a numeric x, y or z")));
        };
        positions.push(Vec3::new(x, y, z));
        if let [Some(x), Some(y), Some(z)] = ["nx", "ny", "nz"].map(|k| scalar(v, k)) {
            normals.push(Vec3::new(x, y, z).normalize_or(Vec3::Y));
        }
    }
    let faces = ply.payload.get("face").ok_or_else(|| bad("no 'face' element".into()))?;
    let mut indices = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let list = face.get("vertex_indices").or_else(|| face.get("vertex_index"));
        let corners: Vec<i64> = match list {
            Some(Property::ListChar(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUChar(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListShort(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUShort(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListInt(l)) => l.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUInt(l)) => l.iter().map(|&i| i as i64).collect(),
            _ => return Err(bad(format!("face {f} has no integer 'vertex_indices' list"))),
        };
        if let Some(&i) = corners.iter().find(|&&i| i < 0 || i as usize >= positions.len()) {
            return Err(bad(format!(
                "face {f} names vertex {i}, but there are {}",
                positions.len()
            )));
        }
        // Fan triangulation: (0, k, k + 1).
        for k in 1..corners.len().saturating_sub(1) {
            indices.extend([corners[0], corners[k], corners[k + 1]].map(|i| i as u32));
        }
    }
    let mesh = if normals.len() == positions.len() {
        TriMesh {
            uvs: Vec::new(),
            positions,
            normals,
            indices,
        }
    } else {
        smooth_normals(&positions, &[], &indices, CREASE_ANGLE_DEG)
    };
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    let mut b = SceneBuilder::new(&path.display().to_string());
    let material = b.material(Material::new("default", [0.8; 3], 0.8, 0.0));
    b.mesh(mesh, Mat4::IDENTITY, material);
    let mut scene = b.build()?;
    let (lo, hi) = scene.bounds();
    scene.camera = Camera::framing(lo, hi);
    scene.name = name;
    Ok(scene)
}
