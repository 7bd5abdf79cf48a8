//! The built-in scenes: scene files in `assets/scenes/` (the format of `scene::file`),
//! compiled into the binary so that `--scene room` works from any folder.

use super::file::SceneFile;
use super::Scene;
use crate::error::Result;
use std::path::Path;

/// (name, scene file text) of every built-in scene; the first is the default.
const SCENES: [(&str, &str); 7] = [
    ("room", include_str!("../../assets/scenes/room.toml")),
    ("offscreen", include_str!("../../assets/scenes/offscreen.toml")),
    ("mirrors", include_str!("../../assets/scenes/mirrors.toml")),
    ("spheres", include_str!("../../assets/scenes/spheres.toml")),
    ("drop", include_str!("../../assets/scenes/drop.toml")),
    ("stress", include_str!("../../assets/scenes/stress.toml")),
    ("cloth", include_str!("../../assets/scenes/cloth.toml")),
];

/// Names accepted by `--scene`.
pub const NAMES: [&str; 7] = [
    SCENES[0].0,
    SCENES[1].0,
    SCENES[2].0,
    SCENES[3].0,
    SCENES[4].0,
    SCENES[5].0,
    SCENES[6].0,
];

/// The parsed scene file of the built-in scene `name`, if there is one.
pub fn file(name: &str) -> Option<Result<SceneFile>> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(n, text)| {
        let path = Path::new("assets/scenes").join(format!("{n}.toml"));
        SceneFile::parse(&path, text)
    })
}

/// The built-in scene called `name`, if there is one.
pub fn by_name(name: &str) -> Option<Result<Scene>> {
    file(name).map(|f| {
        let path = Path::new("assets/scenes").join(format!("{name}.toml"));
        f?.build(&path, Path::new("assets/scenes"))
    })
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
