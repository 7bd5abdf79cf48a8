//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`) through the
//! `gltf` crate: the default scene's node hierarchy with its transforms, indexed (or
//! not) triangle primitives, normals (computed by `geometry::smooth_normals` when
//! absent), texture coordinates, and the metallic-roughness materials.
//!
//! Material mapping: albedo = `baseColorFactor.rgb`, multiplied per texel by
//! `baseColorTexture` (sampled with the texture coordinate set it names; sampler
//! wrap modes and `KHR_texture_transform` are not read: textures repeat); roughness =
//! `roughnessFactor`, multiplied per texel by the green channel of
//! `metallicRoughnessTexture` (read as linear data, with the base colour's texture
//! coordinates); metallic = `metallicFactor`, multiplied per texel by that texture's
//! blue channel;
//! reflectivity (the traced share of the specular reflection, an artist's scale glTF
//! does not have) = 1: the roughness cut-offs judge each texel (a mirror below
//! `glossy_mirror_max`, a GGX lobe below `glossy_rough_max`, the sky term above).

use super::animated::{Animated, MAX_JOINTS};
use super::animation::Rig;
use super::geometry::{smooth_normals, CREASE_ANGLE_DEG};
use super::Texture;
use super::{Camera, Material, Scene, SceneBuilder, TriMesh};
use crate::error::{Error, Result};
use crate::gpu_types::GpuInfluence;
use glam::{Mat4, Vec2, Vec3};
use std::path::Path;

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

/// Loads a glTF or GLB file as a scene with the camera framing it. The file is read
/// bounded (`error::bounds::MODEL`), the document checked before anything walks it
/// (`check_nodes`, `check_accessors`), and any panic left in the `gltf` crate becomes
/// an error naming the file.
pub fn load(path: &Path) -> Result<Scene> {
    let bad = |detail: String| Error::BadAsset {
        what: "glTF file",
        path: path.into(),
        detail,
    };
    let bytes = crate::error::read_file(path, "glTF file", crate::error::bounds::MODEL)?;
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    // Indices first: the crate's own validation indexes with them unchecked.
    let gltf::Gltf { document: doc, blob } =
        guard(|| gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| e.to_string())).map_err(bad)?;
    check_indices(&doc).map_err(bad)?;
    let doc = guard(|| gltf::Document::from_json(doc.into_json()).map_err(|e| e.to_string())).map_err(bad)?;
    check_nodes(&doc).map_err(bad)?;
    check_buffer_files(&doc, &base)?;
    let buffers = guard(|| gltf::import_buffers(&doc, Some(&base), blob).map_err(|e| e.to_string())).map_err(bad)?;
    check_accessors(&doc, &buffers).map_err(bad)?;
    guard(|| walk(path, &doc, &buffers, &base).map_err(|e| e.to_string())).map_err(|e| {
        bad(e
            .trim_start_matches(&format!("invalid glTF file '{}': ", path.display()))
            .to_string())
    })
}

/// Runs `f`, turning a panic inside it (the `gltf` crate's) into an error; the panic's
/// message is not printed.
fn guard<T>(f: impl FnOnce() -> std::result::Result<T, String>) -> std::result::Result<T, String> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    result.unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(format!("the glTF reader failed on it ({why})"))
    })
}

/// Every index the document holds names something that exists (the `gltf` crate's
/// walk indexes with them unchecked and panics).
fn check_indices(doc: &gltf::Document) -> std::result::Result<(), String> {
    let j = doc.as_json();
    let within = |what: String, i: usize, n: usize, of: &str| {
        if i < n {
            Ok(())
        } else {
            Err(format!("{what} names {of} {i}, but there are {n}"))
        }
    };
    let (accessors, views, buffers) = (j.accessors.len(), j.buffer_views.len(), j.buffers.len());
    for (mi, m) in j.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let at = format!("mesh {mi} primitive {pi}");
            for (semantic, a) in &p.attributes {
                let name = match semantic {
                    gltf::json::validation::Checked::Valid(s) => format!("{s:?}"),
                    gltf::json::validation::Checked::Invalid => "(unknown)".into(),
                };
                within(format!("{at} attribute {name}"), a.value(), accessors, "accessor")?;
            }
            if let Some(a) = &p.indices {
                within(format!("{at} indices"), a.value(), accessors, "accessor")?;
            }
            if let Some(m) = &p.material {
                within(at.clone(), m.value(), j.materials.len(), "material")?;
            }
        }
    }
    for (ai, a) in j.accessors.iter().enumerate() {
        if let Some(v) = &a.buffer_view {
            within(format!("accessor {ai}"), v.value(), views, "buffer view")?;
        }
    }
    for (vi, v) in j.buffer_views.iter().enumerate() {
        within(format!("buffer view {vi}"), v.buffer.value(), buffers, "buffer")?;
    }
    for (ni, n) in j.nodes.iter().enumerate() {
        if let Some(m) = &n.mesh {
            within(format!("node {ni}"), m.value(), j.meshes.len(), "mesh")?;
        }
        for c in n.children.iter().flatten() {
            within(format!("node {ni}'s children"), c.value(), j.nodes.len(), "node")?;
        }
    }
    for (si, sc) in j.scenes.iter().enumerate() {
        for n in &sc.nodes {
            within(format!("scene {si}"), n.value(), j.nodes.len(), "node")?;
        }
    }
    for (ti, t) in j.textures.iter().enumerate() {
        within(format!("texture {ti}"), t.source.value(), j.images.len(), "image")?;
    }
    super::gltf_rig::check_indices(j, within)
}

/// The node graph is a forest: no node is its own descendant (the walk below would
/// never end) and none has two parents.
fn check_nodes(doc: &gltf::Document) -> std::result::Result<(), String> {
    let n = doc.nodes().count();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for c in node.children() {
            if let Some(p) = parent[c.index()] {
                return Err(format!("node {} has two parents ({p} and {})", c.index(), node.index()));
            }
            parent[c.index()] = Some(node.index());
        }
    }
    for start in 0..n {
        let (mut at, mut steps) = (start, 0);
        while let Some(p) = parent[at] {
            (at, steps) = (p, steps + 1);
            if steps > n {
                return Err(format!(
                    "node {start} is its own descendant: the node hierarchy has a cycle"
                ));
            }
        }
    }
    Ok(())
}

/// Every external buffer file exists (named when missing) and is a regular file within
/// the model bound, before the `gltf` crate reads it.
fn check_buffer_files(doc: &gltf::Document, base: &Path) -> Result<()> {
    for buffer in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let file = base.join(uri);
            // A missing, special or huge file is named before the crate reads it.
            crate::error::open_bounded(&file, "glTF buffer", crate::error::bounds::MODEL)?;
        }
    }
    Ok(())
}

/// Every primitive's accessors are of the types read here and lie within their buffer
/// views and buffers: POSITION and NORMAL are float VEC3, texture coordinates VEC2
/// (float, or normalized unsigned bytes or shorts), indices unsigned SCALAR; a view's
/// stride is at least its element.
fn check_accessors(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> std::result::Result<(), String> {
    use gltf::accessor::{DataType as D, Dimensions as Dim};
    use gltf::Semantic as S;
    for mesh in doc.meshes() {
        for (p, prim) in mesh.primitives().enumerate() {
            let at = |what: &str| format!("mesh {} primitive {p} {what}", mesh.index());
            let mut list: Vec<(String, gltf::Accessor<'_>, &[Dim], &[D])> = Vec::new();
            for (semantic, acc) in prim.attributes() {
                let (dims, types): (&[Dim], &[D]) = match semantic {
                    S::Positions | S::Normals => (&[Dim::Vec3], &[D::F32]),
                    S::TexCoords(_) => (&[Dim::Vec2], &[D::F32, D::U8, D::U16]),
                    _ => continue,
                };
                list.push((at(&format!("{semantic:?}")), acc, dims, types));
            }
            if let Some(acc) = prim.indices() {
                list.push((at("indices"), acc, &[Dim::Scalar], &[D::U8, D::U16, D::U32]));
            }
            for (what, acc, dims, types) in list {
                if !dims.contains(&acc.dimensions()) || !types.contains(&acc.data_type()) {
                    return Err(format!(
                        "{what}: accessor {} is {:?} {:?}, not {dims:?} of {types:?}",
                        acc.index(),
                        acc.dimensions(),
                        acc.data_type()
                    ));
                }
                let Some(view) = acc.view() else { continue };
                let element = acc.size();
                let stride = view.stride().unwrap_or(element);
                if stride < element {
                    return Err(format!(
                        "{what}: buffer view {} has byteStride {stride}, smaller than its {element}-byte elements",
                        view.index()
                    ));
                }
                let need = match acc.count() {
                    0 => 0,
                    n => acc.offset() + stride * (n - 1) + element,
                };
                if need > view.length() {
                    return Err(format!(
                        "{what}: accessor {} needs {need} bytes of buffer view {}, which has {}",
                        acc.index(),
                        view.index(),
                        view.length()
                    ));
                }
                let have = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
                if view.offset() + view.length() > have {
                    return Err(format!(
                        "{what}: buffer view {} ends at byte {}, past its buffer's {have}",
                        view.index(),
                        view.offset() + view.length()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// An image in a file of its own is a regular file within the image bound (the `gltf`
/// crate would read it whole, whatever it is).
fn check_image_file(img: &gltf::Image<'_>, base: &Path) -> std::result::Result<(), String> {
    match img.source() {
        gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
            crate::error::open_bounded(&base.join(uri), "glTF image", crate::error::bounds::IMAGE)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }
        _ => Ok(()),
    }
}

/// The checked document's default scene as a Speculum scene.
fn walk(path: &Path, doc: &gltf::Document, buffers: &[gltf::buffer::Data], base: &Path) -> Result<Scene> {
    let mut warnings = Vec::new();
    let images = decode_images(path, doc, buffers, base, &mut warnings);
    let mut w = Walk {
        path,
        buffers,
        images,
        b: SceneBuilder::new(&path.display().to_string()),
        ids: Vec::new(),
        textures: Vec::new(),
        warnings,
    };
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| w.bad("no scene".into()))?;
    let rig = super::gltf_rig::read(doc, buffers, &mut w.warnings).map_err(|e| w.bad(e))?;
    let moved = rig.as_ref().map(Rig::moved).unwrap_or_default();
    let rest = rig.as_ref().map(|r| r.world(None, 0.0)).unwrap_or_default();
    // With an animation, what it moves is dynamic (`Animated`); without, skins stand
    // posed at rest.
    let mut animated = rig.clone().filter(|r| !r.animations.is_empty()).map(Animated::new);
    let too_many = || format!("its animated meshes need more than {MAX_JOINTS} joints");
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        stack.extend(node.children().map(|c| (c, m)));
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            let Some((tri, id, source)) = w.primitive(&mesh, &prim)? else {
                continue;
            };
            match (node.skin(), animated.as_mut(), &rig) {
                (Some(skin), Some(a), _) => {
                    let base = a.skin_joints(skin.index()).ok_or_else(|| w.bad(too_many()))?;
                    a.push(&tri, id, &w.influences(&prim, &source, base));
                }
                (Some(skin), None, Some(rig)) => {
                    let matrices = rig.joint_matrices(&rig.skins[skin.index()], &rest, Mat4::IDENTITY);
                    let posed = super::animation::skin_mesh(&tri, &w.influences(&prim, &source, 0), &matrices);
                    w.b.mesh(posed, Mat4::IDENTITY, id);
                }
                (None, Some(a), _) if moved[node.index()] => {
                    let joint = a.node_joint(node.index()).ok_or_else(|| w.bad(too_many()))?;
                    let one = GpuInfluence::new([joint, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]);
                    a.push(&tri, id, &vec![one; tri.positions.len()]);
                }
                _ => {
                    w.b.mesh(tri, m, id);
                }
            }
        }
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "gltf".into());
    w.b.scene.animated = animated.filter(|a| !a.indices.is_empty());
    let mut scene = match &w.b.scene.animated {
        // All of it moves: no static triangles until a floor or a scene file's other
        // instances join it (which validate the whole).
        Some(a) if w.b.scene.indices.is_empty() => {
            a.check().map_err(|e| w.bad(format!("its animated meshes: {e}")))?;
            w.b.scene
        }
        _ => w.b.build()?,
    };
    let (lo, hi) = scene.bounds();
    scene.camera = Camera::framing(lo, hi);
    scene.name = name;
    scene.warnings = w.warnings;
    Ok(scene)
}

/// Every image decoded; one that cannot be read or decoded is a warning, its materials
/// untextured (as a missing OBJ texture).
fn decode_images(
    path: &Path,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    base: &Path,
    warnings: &mut Vec<String>,
) -> Vec<Option<gltf::image::Data>> {
    doc.images()
        .map(|img| {
            let decoded = check_image_file(&img, base).and_then(|_| {
                gltf::image::Data::from_source(img.source(), Some(base), buffers).map_err(|e| e.to_string())
            });
            decoded
                .inspect_err(|e| {
                    warnings.push(format!(
                        "'{}' image {}: {e}: the materials that use it take their base colour factor alone",
                        path.display(),
                        img.index()
                    ))
                })
                .ok()
        })
        .collect()
}

/// A glTF scene being walked into a scene builder.
struct Walk<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    images: Vec<Option<gltf::image::Data>>,
    b: SceneBuilder,
    /// glTF material index (None: the default material) → scene material and the
    /// texture coordinate set its base colour texture uses.
    ids: Vec<(Option<usize>, u32, u32)>,
    /// glTF image index → scene texture (None: not usable, warned about once).
    /// (glTF image, as linear data (`texture::data_texture`), scene texture).
    textures: Vec<(usize, bool, Option<u32>)>,
    warnings: Vec<String>,
}

impl Walk<'_> {
    fn bad(&self, detail: String) -> Error {
        Error::BadAsset {
            what: "glTF file",
            path: self.path.into(),
            detail,
        }
    }

    /// The scene material of glTF material `m` (made on first use) and the texture
    /// coordinate set of its base colour texture.
    fn material(&mut self, m: gltf::Material<'_>) -> (u32, u32) {
        if let Some(&(_, id, set)) = self.ids.iter().find(|(i, _, _)| *i == m.index()) {
            return (id, set);
        }
        let pbr = m.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        let name = m.name().map(str::to_string).unwrap_or_else(|| match m.index() {
            Some(i) => format!("material {i}"),
            None => "default".into(),
        });
        let roughness = pbr.roughness_factor();
        let mut material = Material::new(&name, [f[0], f[1], f[2]], roughness, 1.0).metal(pbr.metallic_factor());
        let mut set = 0;
        if let Some(info) = pbr.base_color_texture() {
            material.texture = self.texture(info.texture().source().index(), false, &name);
            set = info.tex_coord();
        }
        if let Some(info) = pbr.metallic_roughness_texture() {
            if pbr
                .base_color_texture()
                .is_some_and(|b| b.tex_coord() != info.tex_coord())
            {
                self.warnings.push(format!(
                    "material '{name}': its metallic-roughness texture uses another texture coordinate set than its \
                     base colour; it is read with the base colour's"
                ));
            }
            material.roughness_texture = self.texture(info.texture().source().index(), true, &name);
            if pbr.base_color_texture().is_none() {
                set = info.tex_coord();
            }
        }
        let id = self.b.material(material);
        self.ids.push((m.index(), id, set));
        (id, set)
    }

    /// The scene texture of glTF image `image` (made on first use), as colour or as
    /// linear `data` (a metallic-roughness map), for material `name`.
    fn texture(&mut self, image: usize, data: bool, name: &str) -> Option<u32> {
        if let Some(&(_, _, t)) = self.textures.iter().find(|(i, d, _)| *i == image && *d == data) {
            return t;
        }
        let decoded = self.images.get(image).and_then(|d| d.as_ref());
        let t = match decoded.map(image_rgba8) {
            // Unreadable: already warned about when decoded.
            None => None,
            Some(Some(img)) => {
                let t = Texture {
                    name: format!("{} image {image}", self.path.display()),
                    image: img,
                    data,
                };
                Some(self.b.texture(t))
            }
            Some(None) => {
                self.warnings.push(format!(
                    "image {image}: not 8- or 16-bit; material '{name}' uses its base colour factor alone"
                ));
                None
            }
        };
        self.textures.push((image, data, t));
        t
    }

    /// One primitive of `mesh` in its own space, its material, and the file's vertex
    /// each of its vertices came from: triangles only (others are skipped with a
    /// warning), indices and texture coordinates checked, the file's normals or smooth
    /// ones (which weld vertices at equal positions: each takes the first's).
    fn primitive(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        prim: &gltf::Primitive<'_>,
    ) -> Result<Option<(TriMesh, u32, Vec<u32>)>> {
        let mesh_name = mesh.name().unwrap_or("(unnamed)");
        if prim.mode() != gltf::mesh::Mode::Triangles {
            self.warnings.push(format!(
                "mesh '{mesh_name}': a {:?} primitive is skipped (triangles only)",
                prim.mode()
            ));
            return Ok(None);
        }
        let buffers = self.buffers;
        let reader = prim.reader(|buf| buffers.get(buf.index()).map(|d| &d.0[..]));
        let Some(positions) = reader.read_positions() else {
            return Err(self.bad(format!("mesh '{mesh_name}' has no positions")));
        };
        let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(self.bad(format!("an index {i} is past the {} positions", positions.len())));
        }
        let (id, set) = self.material(prim.material());
        let uvs: Vec<Vec2> = match reader.read_tex_coords(set) {
            Some(t) => t.into_f32().map(Vec2::from).collect(),
            None => Vec::new(),
        };
        if uvs.len() != positions.len() && !uvs.is_empty() {
            return Err(self.bad(format!(
                "mesh '{mesh_name}' has {} texture coordinates for {} positions",
                uvs.len(),
                positions.len()
            )));
        }
        let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
        let source: Vec<u32>;
        let tri = match normals {
            Some(normals) if normals.len() == positions.len() => {
                source = (0..positions.len() as u32).collect();
                TriMesh {
                    positions,
                    normals: normals.into_iter().map(|n| n.normalize_or(Vec3::Y)).collect(),
                    uvs,
                    indices,
                }
            }
            _ => {
                let tri = smooth_normals(&positions, &uvs, &indices, CREASE_ANGLE_DEG);
                let key = |p: &Vec3| (*p + Vec3::ZERO).to_array().map(f32::to_bits);
                let mut first = std::collections::HashMap::new();
                for (i, p) in positions.iter().enumerate().rev() {
                    first.insert(key(p), i as u32);
                }
                source = tri.positions.iter().map(|p| first[&key(p)]).collect();
                tri
            }
        };
        Ok(Some((tri, id, source)))
    }

    /// The influences of `prim`'s vertices (`source`: each one's vertex in the file),
    /// their joints moved by `base` into the model's palette. Checked already
    /// (`gltf_rig`): one set of four, as many as the positions, within the skin.
    fn influences(&self, prim: &gltf::Primitive<'_>, source: &[u32], base: u16) -> Vec<GpuInfluence> {
        let buffers = self.buffers;
        let reader = prim.reader(|buf| buffers.get(buf.index()).map(|d| &d.0[..]));
        let joints: Vec<[u16; 4]> = reader
            .read_joints(0)
            .map(|j| j.into_u16().collect())
            .unwrap_or_default();
        let weights: Vec<[f32; 4]> = reader
            .read_weights(0)
            .map(|w| w.into_f32().collect())
            .unwrap_or_default();
        source
            .iter()
            .map(|&i| GpuInfluence::new(joints[i as usize].map(|j| j + base), weights[i as usize]))
            .collect()
    }
}
