//! The built-in scenes: scene files in `assets/scenes/` (the format of `scene::file`),
//! compiled into the binary so that `--scene room` works from any folder.

use super::file::{Instance, SceneFile};
use super::Scene;
use crate::error::{Error, Result};
use std::path::Path;

/// (name, scene file text) of every built-in scene; the first is the default.
const SCENES: [(&str, &str); 8] = [
    ("room", include_str!("../../assets/scenes/room.toml")),
    ("offscreen", include_str!("../../assets/scenes/offscreen.toml")),
    ("mirrors", include_str!("../../assets/scenes/mirrors.toml")),
    ("spheres", include_str!("../../assets/scenes/spheres.toml")),
    ("drop", include_str!("../../assets/scenes/drop.toml")),
    ("stress", include_str!("../../assets/scenes/stress.toml")),
    ("cloth", include_str!("../../assets/scenes/cloth.toml")),
    ("glossy", include_str!("../../assets/scenes/glossy.toml")),
];

/// Names accepted by `--scene`: the scene files, then `gallery` (generated; `gallery:N`
/// for about N triangles).
pub const NAMES: [&str; 9] = [
    SCENES[0].0,
    SCENES[1].0,
    SCENES[2].0,
    SCENES[3].0,
    SCENES[4].0,
    SCENES[5].0,
    SCENES[6].0,
    SCENES[7].0,
    GALLERY,
];

/// The generated scene family: a mirror-floored hall of sculptures whose triangle count
/// `gallery:N` sets, so the tracer's cost can be measured against scene size while
/// everything on screen stays the same.
pub const GALLERY: &str = "gallery";
/// `gallery`'s triangle count when none is given.
pub const GALLERY_DEFAULT_TRIANGLES: u32 = 100_000;
/// The range `gallery:N` takes.
pub const GALLERY_TRIANGLES: std::ops::RangeInclusive<u32> = 10_000..=8_000_000;

/// The parsed scene file of the built-in scene `name`, if there is one.
pub fn file(name: &str) -> Option<Result<SceneFile>> {
    let path = Path::new("assets/scenes").join(format!("{name}.toml"));
    if let Some(detail) = gallery_triangles(name) {
        return Some(detail.and_then(|n| gallery(&path, name, n)));
    }
    SCENES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| SceneFile::parse(&path, text))
}

/// The triangle count `name` asks of the gallery (`gallery`, `gallery:N`, N with an
/// optional `k` or `M`), or `None` when it names another scene.
fn gallery_triangles(name: &str) -> Option<Result<u32>> {
    let detail = match name.strip_prefix(GALLERY)? {
        "" => return Some(Ok(GALLERY_DEFAULT_TRIANGLES)),
        rest => rest.strip_prefix(':')?,
    };
    let (digits, unit) = match detail.as_bytes().last() {
        Some(b'k' | b'K') => (&detail[..detail.len() - 1], 1_000),
        Some(b'm' | b'M') => (&detail[..detail.len() - 1], 1_000_000),
        _ => (detail, 1),
    };
    let n = digits.parse::<u64>().ok().and_then(|d| d.checked_mul(unit));
    Some(match n {
        Some(n) if n >= *GALLERY_TRIANGLES.start() as u64 && n <= *GALLERY_TRIANGLES.end() as u64 => Ok(n as u32),
        _ => Err(Error::Input(format!(
            "scene '{name}': gallery:N takes a triangle count N in {}..={} (e.g. gallery:1M)",
            GALLERY_TRIANGLES.start(),
            GALLERY_TRIANGLES.end()
        ))),
    })
}

/// The sculptures of the gallery: (x, z, radius, material) on pedestals in two rows.
const SCULPTURES: [(f32, f32, f32, &str); 8] = [
    (-2.6, -6.0, 0.75, "terracotta"),
    (2.6, -6.0, 0.75, "jade"),
    (-2.6, -2.0, 0.7, "marble"),
    (2.6, -2.0, 0.7, "bronze"),
    (-2.6, 2.0, 0.65, "jade"),
    (2.6, 2.0, 0.65, "terracotta"),
    (-2.6, 6.0, 0.6, "bronze"),
    (2.6, 6.0, 0.6, "marble"),
];

/// The gallery's scene file with about `triangles` triangles: the hall
/// (`assets/gallery_hall.toml`: mirror floor, glossy far wall, matte side walls, a few
/// hundred triangles) with a pedestal and a sculpture at each of `SCULPTURES` (UV
/// spheres of `2r` segments and `r` rings, 4r^2 triangles each), which hold nearly all
/// the triangles.
fn gallery(path: &Path, name: &str, triangles: u32) -> Result<SceneFile> {
    let per = triangles as f64 / SCULPTURES.len() as f64;
    let rings = ((per / 4.0).sqrt().round() as u32).clamp(4, 512);
    let mut file = SceneFile::parse(path, include_str!("../../assets/gallery_hall.toml"))?;
    file.name = Some(name.into());
    for (x, z, r, material) in SCULPTURES {
        file.instances.push(Instance {
            cuboid: Some([1.2, 1.0, 1.2]),
            material: Some("pedestal".into()),
            translate: Some([x, 0.5, z]),
            ..Default::default()
        });
        file.instances.push(Instance {
            sphere: Some(r),
            segments: Some(2 * rings),
            rings: Some(rings),
            material: Some(material.into()),
            translate: Some([x, 1.0 + r, z]),
            ..Default::default()
        });
    }
    Ok(file)
}

/// The built-in scene called `name`, if there is one.
pub fn by_name(name: &str) -> Option<Result<Scene>> {
    file(name).map(|f| {
        let path = Path::new("assets/scenes").join(format!("{name}.toml"));
        let mut scene = f?.build(&path, Path::new("assets/scenes"))?;
        if name == "glossy" {
            roughness_ramp(&mut scene, RAMP_MATERIAL);
        }
        Ok(scene)
    })
}

/// The material of `glossy` whose roughness `roughness_ramp` ramps.
const RAMP_MATERIAL: &str = "floor ramp";

/// Gives material `name` a generated roughness texture (a scene file's textures are
/// files beside it, which a built-in scene has not): green runs from 0 at u = 0 to 1 at
/// u = 1, so the roughness runs from a mirror to the material's factor across it.
fn roughness_ramp(scene: &mut Scene, name: &str) {
    let image = image::RgbaImage::from_fn(256, 4, |x, _| {
        // Blue 1: the G-buffer reads it as glTF's layout (blue x metallic).
        image::Rgba([x as u8, x as u8, 255, 255])
    });
    let layer = scene.textures.len() as u32;
    scene.textures.push(super::Texture {
        name: format!("{name}: roughness ramp"),
        image,
        data: true,
    });
    let m = scene
        .materials
        .iter_mut()
        .find(|m| m.name == name)
        .expect("the ramp's material");
    m.roughness_texture = Some(layer);
}

fn named(name: &str) -> Result<Scene> {
    by_name(name).expect("a built-in scene")
}

/// The default scene: an open-topped box room with a mirror-like floor, a glossy back
/// wall, coloured side walls, three spheres and two boxes, lit by a low sun.
pub fn room() -> Result<Scene> {
    named("room")
}

/// SSR's blind spots: a mirror showing a sphere behind the camera and a box hidden
/// behind a panel.
pub fn offscreen() -> Result<Scene> {
    named("offscreen")
}

/// Two facing mirrors: each bounce adds a reflection.
pub fn mirrors() -> Result<Scene> {
    named("mirrors")
}

/// Twenty curved reflectors on a checkerboard.
pub fn spheres() -> Result<Scene> {
    named("spheres")
}

/// Rigid bodies falling into `room`'s room, a chrome sphere rolling across its floor.
pub fn drop() -> Result<Scene> {
    named("drop")
}

/// A cloth draping over a sphere above a polished floor, beside a chrome sphere.
pub fn cloth() -> Result<Scene> {
    named("cloth")
}

/// A grid of many bodies (100 unless `set_spawn_count`) falling onto a polished floor.
pub fn stress() -> Result<Scene> {
    named("stress")
}

/// The triangle counts `skinned_tube` takes.
pub const TUBE_TRIANGLES: std::ops::RangeInclusive<u32> = 1_000..=4_000_000;

/// A generated skinned tube (`animation::skinned_tube`: 256 around, 16 joints, its
/// one-second sway looping) of about `triangles` triangles (the next whole ring up) in
/// `TUBE_TRIANGLES`, in chrome on a mirror floor: the animated-geometry benchmark's
/// scene (`bench dynamic --skinned`).
pub fn skinned_tube(triangles: u32) -> Result<Scene> {
    use super::{animated::Animated, camera::Camera, Material, SceneBuilder, TriMesh};
    use glam::{Mat4, Vec3};
    if !TUBE_TRIANGLES.contains(&triangles) {
        return Err(Error::Input(format!(
            "a skinned tube takes {}..={} triangles, not {triangles}",
            TUBE_TRIANGLES.start(),
            TUBE_TRIANGLES.end()
        )));
    }
    let segments = 256;
    let (mesh, influences, rig) = super::animation::skinned_tube(segments, triangles.div_ceil(2 * segments), 16);
    let mut b = SceneBuilder::new(&format!("tube:{triangles}"));
    let floor = b.material(Material::new("floor (mirror)", [0.6, 0.6, 0.62], 0.03, 1.0).metal(1.0));
    let chrome = b.material(Material::new("chrome", [0.95, 0.93, 0.88], 0.15, 1.0).metal(1.0));
    b.mesh(TriMesh::quad(6.0, 6.0), Mat4::IDENTITY, floor);
    b.camera(Camera::framing(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 2.2, 1.0)));
    let mut a = Animated::new(rig);
    a.skin_joints(0).expect("16 joints");
    a.push(&mesh, chrome, &influences);
    b.scene.animated = Some(a);
    b.build()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every built-in scene file parses, builds, and round-trips through TOML.
    #[test]
    fn built_in_files_build_and_round_trip() {
        for name in NAMES {
            let f = file(name).unwrap().unwrap();
            let again = SceneFile::parse(Path::new("x.toml"), &f.to_toml()).unwrap();
            assert_eq!(f, again, "{name}");
            let s = by_name(name).unwrap().unwrap();
            assert_eq!(s.name, name);
            assert!(s.triangle_count() + s.dynamic_triangle_count() > 10);
        }
        assert!(by_name("nope").is_none());
    }

    /// `gallery:N` has about N triangles (within 5%, the hall's few hundred aside) for
    /// N across its range, `gallery` the default; a count outside the range or not a
    /// number is one error naming the scene; other names are not the gallery's.
    #[test]
    fn the_gallery_has_the_triangles_asked() {
        for (name, want) in [
            ("gallery", GALLERY_DEFAULT_TRIANGLES),
            ("gallery:10000", 10_000),
            ("gallery:250k", 250_000),
            ("gallery:1M", 1_000_000),
        ] {
            let s = by_name(name).unwrap().unwrap();
            let got = s.triangle_count() as f64;
            assert!((got / want as f64 - 1.0).abs() < 0.05, "{name}: {got} triangles");
            assert_eq!(s.name, name);
        }
        // The last would wrap a u64 times 10^6 into the range.
        for bad in [
            "gallery:",
            "gallery:9999",
            "gallery:9M",
            "gallery:lots",
            "gallery:-5",
            "gallery:18446744073710M",
        ] {
            let e = file(bad).unwrap().unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains("gallery:N"), "{bad}: {e}");
        }
        assert!(file("gallery2").is_none() && file("galleryx:5").is_none());
    }

    /// `stress` spawns its 100 bodies; `set_spawn_count` replaces them (and only them),
    /// the grid taller for more; every body starts above the floor, none overlapping.
    #[test]
    fn stress_spawns_and_respawns() {
        let mut s = stress().unwrap();
        assert_eq!(s.bodies.len(), 100);
        s.set_spawn_count(1000).unwrap();
        assert_eq!(s.bodies.len(), 1000);
        s.validate().unwrap();
        for (i, a) in s.bodies.iter().enumerate() {
            assert!(a.position.y - a.radius() > 0.0, "body {i} starts in the floor");
            for b in &s.bodies[..i] {
                assert!(
                    (a.position - b.position).length() > a.radius() + b.radius(),
                    "bodies overlap"
                );
            }
        }
        s.set_spawn_count(3).unwrap();
        assert_eq!(s.bodies.len(), 3);
        let mut room = room().unwrap();
        assert!(room.set_spawn_count(3).is_err());
    }
}
