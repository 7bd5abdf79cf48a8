//! The glTF showcase (`assets/models/showcase.glb`): a checker backdrop (PNG texture),
//! a gold and a silver metal sphere, a white box beside the gold one, and a brick crate
//! (JPEG texture), under a node hierarchy with translations, a rotation and scales.
//! `cargo run --example showcase` writes the shipped file; the tests build the same
//! bytes and check them, and load them.

use glam::{Quat, Vec3};
use serde_json::{json, Value};
use speculum::scene::TriMesh;

/// Checker squares per side of the backdrop texture, and their two colours (sRGB).
pub const CHECKER_SQUARES: u32 = 8;
pub const CHECKER_A: [u8; 3] = [235, 225, 200];
pub const CHECKER_B: [u8; 3] = [30, 105, 120];
/// Where the gold sphere's centre ends up in the world, and its radius.
pub const GOLD_CENTER: Vec3 = Vec3::new(-0.75, 0.45, 0.0);
pub const GOLD_RADIUS: f32 = 0.45;
/// Gold's base colour (linear; the metal's F0).
pub const GOLD: [f32; 3] = [1.0, 0.766, 0.336];
/// The white box: its centre and edge.
pub const WHITE_BOX_CENTER: Vec3 = Vec3::new(-1.45, 0.25, 0.55);
pub const WHITE_BOX_EDGE: f32 = 0.5;

/// A 256² checker of `CHECKER_SQUARES`² squares, as PNG bytes.
pub fn checker_png() -> Vec<u8> {
    let cell = 256 / CHECKER_SQUARES;
    let img = image::RgbImage::from_fn(256, 256, |x, y| {
        image::Rgb(if (x / cell + y / cell).is_multiple_of(2) {
            CHECKER_A
        } else {
            CHECKER_B
        })
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Running-bond bricks with mortar lines and a little deterministic mottling, as JPEG.
pub fn bricks_jpeg() -> Vec<u8> {
    let img = image::RgbImage::from_fn(256, 256, |x, y| {
        let row = y / 32;
        let shift = if row.is_multiple_of(2) { 0 } else { 32 };
        let col = (x + shift) / 64;
        let mortar = y % 32 < 3 || (x + shift) % 64 < 3;
        if mortar {
            return image::Rgb([200, 195, 185]);
        }
        let h = (row * 7919 + col * 104_729) % 37;
        let n = ((x * 31 + y * 17) % 11) as i32 - 5;
        let c = |base: i32| (base + h as i32 - 18 + n).clamp(0, 255) as u8;
        image::Rgb([c(150), c(62), c(42)])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 90)
        .encode_image(&img)
        .unwrap();
    out.into_inner()
}

/// Appends `bytes` to the binary buffer (4-byte aligned) and returns a buffer view.
pub fn view(bin: &mut Vec<u8>, views: &mut Vec<Value>, bytes: &[u8], target: Option<u32>) -> usize {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut v = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
    if let Some(t) = target {
        v["target"] = json!(t);
    }
    bin.extend_from_slice(bytes);
    views.push(v);
    views.len() - 1
}

/// The showcase as GLB bytes.
pub fn glb() -> Vec<u8> {
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
    let mut mesh = |name: &str, m: TriMesh, material: usize| -> usize {
        let f32s = |v: Vec<f32>| v.into_iter().flat_map(f32::to_le_bytes).collect::<Vec<u8>>();
        let positions: Vec<f32> = m.positions.iter().flat_map(|p| p.to_array()).collect();
        let (lo, hi) = m
            .positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let normals: Vec<f32> = m.normals.iter().flat_map(|n| n.to_array()).collect();
        let uvs: Vec<f32> = m.uvs.iter().flat_map(|t| t.to_array()).collect();
        let indices: Vec<u8> = m.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let count = m.positions.len();
        let first = accessors.len();
        for (bytes, kind, target, bounds) in [
            (f32s(positions), "VEC3", 34962, true),
            (f32s(normals), "VEC3", 34962, false),
            (f32s(uvs), "VEC2", 34962, false),
        ] {
            let v = view(&mut bin, &mut views, &bytes, Some(target));
            let mut a = json!({"bufferView": v, "componentType": 5126, "count": count, "type": kind});
            if bounds {
                a["min"] = json!(lo.to_array());
                a["max"] = json!(hi.to_array());
            }
            accessors.push(a);
        }
        let v = view(&mut bin, &mut views, &indices, Some(34963));
        accessors.push(json!({"bufferView": v, "componentType": 5125, "count": m.indices.len(), "type": "SCALAR"}));
        meshes.push(json!({"name": name, "primitives": [{
            "attributes": {"POSITION": first, "NORMAL": first + 1, "TEXCOORD_0": first + 2},
            "indices": first + 3, "material": material}]}));
        meshes.len() - 1
    };
    // Materials: 0 checker, 1 gold, 2 silver, 3 white, 4 bricks.
    let backdrop = {
        let mut quad = TriMesh::quad(3.2, 1.8);
        // Stand the quad up facing +z: (x, 0, z) -> (x, -z, 0); v runs down the image.
        for p in &mut quad.positions {
            *p = Vec3::new(p.x, -p.z, 0.0);
        }
        quad.normals.iter_mut().for_each(|n| *n = Vec3::Z);
        mesh("backdrop", quad, 0)
    };
    let gold = mesh("gold sphere", TriMesh::sphere(1.0, 64, 32), 1);
    let silver = mesh("silver sphere", TriMesh::sphere(1.0, 64, 32), 2);
    let white = mesh("white box", TriMesh::cuboid(Vec3::splat(WHITE_BOX_EDGE)), 3);
    let crate_ = mesh("brick crate", TriMesh::cuboid(Vec3::splat(0.6)), 4);
    let png = view(&mut bin, &mut views, &checker_png(), None);
    let jpeg = view(&mut bin, &mut views, &bricks_jpeg(), None);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let metals_at = Vec3::new(0.0, 0.0, 0.1);
    let crate_turn = Quat::from_rotation_y(25f32.to_radians());
    let doc = json!({
        "asset": {"version": "2.0", "generator": "speculum tests/common/showcase.rs"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "showcase", "children": [1, 2, 5, 6, 7]},
            {"name": "backdrop", "mesh": backdrop, "translation": [0.0, 0.9, -1.0]},
            {"name": "metals", "translation": metals_at.to_array(), "children": [3, 4]},
            {"name": "gold", "mesh": gold, "translation": (GOLD_CENTER - metals_at).to_array(),
             "scale": [GOLD_RADIUS, GOLD_RADIUS, GOLD_RADIUS]},
            {"name": "silver", "mesh": silver, "translation": [0.85, 0.4, -0.2], "scale": [0.4, 0.4, 0.4]},
            {"name": "white box", "mesh": white, "translation": WHITE_BOX_CENTER.to_array()},
            {"name": "crate", "mesh": crate_, "translation": [0.3, 0.3, -0.55],
             "rotation": crate_turn.to_array()},
            {"name": "empty"}
        ],
        "meshes": meshes,
        "materials": [
            {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
             "metallicFactor": 0.0, "roughnessFactor": 0.6}},
            {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [GOLD[0], GOLD[1], GOLD[2], 1.0],
             "metallicFactor": 1.0, "roughnessFactor": 0.08}},
            {"name": "silver", "pbrMetallicRoughness": {"baseColorFactor": [0.97, 0.96, 0.91, 1.0],
             "metallicFactor": 1.0, "roughnessFactor": 0.05}},
            {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1.0],
             "metallicFactor": 0.0, "roughnessFactor": 0.5}},
            {"name": "bricks", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1},
             "metallicFactor": 0.0, "roughnessFactor": 0.7}}
        ],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"bufferView": png, "mimeType": "image/png"}, {"bufferView": jpeg, "mimeType": "image/jpeg"}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    container(&serde_json::to_vec(&doc).unwrap(), &bin)
}

/// A GLB file: the header, the JSON chunk (space-padded to 4 bytes) and the BIN chunk
/// (`bin`, already a multiple of 4 bytes).
pub fn container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    assert!(bin.len().is_multiple_of(4));
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(bin);
    glb
}
