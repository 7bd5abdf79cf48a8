//! Built-in scenes, made from code so that tests and the README need no assets.

use super::{Camera, Light, Material, Scene, SceneBuilder, TriMesh};
use crate::error::Result;
use glam::{Mat4, Quat, Vec3};

/// Names accepted by `--scene`.
pub const NAMES: &[&str] = &["room", "offscreen", "mirrors", "spheres"];

/// The built-in scene called `name`, if there is one.
pub fn by_name(name: &str) -> Option<Result<Scene>> {
    match name {
        "room" => Some(room()),
        "offscreen" => Some(offscreen()),
        "mirrors" => Some(mirrors()),
        "spheres" => Some(spheres()),
        _ => None,
    }
}

/// A wall facing +z (towards the default cameras) of the given size, centred at `c`.
fn wall(width: f32, height: f32, c: Vec3) -> (TriMesh, Mat4) {
    (
        TriMesh::quad(width, height),
        Mat4::from_translation(c) * Mat4::from_rotation_x(90f32.to_radians()),
    )
}

/// SSR's blind spots: a large mirror in front of the camera shows a red sphere that is
/// behind the camera (off screen) and a green box hidden from the camera behind a
/// panel. Screen space holds neither; the ray tracer must supply both.
pub fn offscreen() -> Result<Scene> {
    let mut b = SceneBuilder::new("offscreen");
    let floor = b.material(Material::new("floor", [0.55, 0.55, 0.5], 0.9, 0.0));
    let mirror = b.material(Material::new("mirror", [0.9, 0.9, 0.9], 0.0, 0.95));
    let red = b.material(Material::new("red", [0.85, 0.08, 0.06], 0.5, 0.0));
    let green = b.material(Material::new("green", [0.1, 0.75, 0.15], 0.5, 0.0));
    let grey = b.material(Material::new("panel", [0.45, 0.45, 0.5], 0.7, 0.0));
    let frame_mat = b.material(Material::new("frame", [0.25, 0.18, 0.12], 0.7, 0.0));
    b.mesh(TriMesh::quad(16.0, 20.0), Mat4::IDENTITY, floor);
    let (m, t) = wall(10.0, 4.5, Vec3::new(0.0, 2.35, -4.0));
    b.mesh(m, t, mirror);
    b.mesh(
        TriMesh::cuboid(Vec3::new(10.4, 0.1, 0.2)),
        Mat4::from_translation(Vec3::new(0.0, 0.05, -4.05)),
        frame_mat,
    );
    // Behind the camera (at z = 3), so off screen.
    b.mesh(
        TriMesh::sphere(0.8, 48, 24),
        Mat4::from_translation(Vec3::new(-1.0, 1.4, 5.0)),
        red,
    );
    // Hidden from the camera by the panel in front of it.
    b.mesh(
        TriMesh::cuboid(Vec3::new(0.9, 1.4, 0.9)),
        Mat4::from_translation(Vec3::new(1.5, 0.7, -1.5)),
        green,
    );
    b.mesh(
        TriMesh::cuboid(Vec3::new(1.8, 2.4, 0.1)),
        Mat4::from_translation(Vec3::new(1.5, 1.2, 0.0)),
        grey,
    );
    b.camera(Camera {
        position: Vec3::new(0.0, 1.6, 3.0),
        target: Vec3::new(0.0, 1.5, -4.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        near: 0.1,
        far: 60.0,
    });
    b.light(Light {
        direction: Vec3::new(-0.3, 0.8, 0.5),
        color: Vec3::new(1.0, 0.97, 0.92),
        intensity: 2.4,
    });
    b.build()
}

/// Two facing mirrors with objects between them: each mirror shows the other, so
/// recursive bounces are visible (one more reflection per bounce).
pub fn mirrors() -> Result<Scene> {
    let mut b = SceneBuilder::new("mirrors");
    let floor = b.material(Material::new("floor", [0.6, 0.55, 0.45], 0.8, 0.0));
    let mirror = b.material(Material::new("mirror", [0.92, 0.92, 0.95], 0.0, 0.9));
    let blue = b.material(Material::new("blue", [0.1, 0.25, 0.85], 0.4, 0.1));
    let orange = b.material(Material::new("orange", [0.95, 0.45, 0.08], 0.5, 0.0));
    let back = b.material(Material::new("back wall", [0.7, 0.7, 0.72], 0.9, 0.0));
    b.mesh(TriMesh::quad(8.0, 12.0), Mat4::IDENTITY, floor);
    let side = TriMesh::quad(12.0, 3.5);
    // Left mirror at x = -2.5 facing +x, right mirror at x = 2.5 facing -x.
    b.mesh(
        side.clone(),
        Mat4::from_translation(Vec3::new(-2.5, 1.75, 0.0))
            * Mat4::from_rotation_z(-90f32.to_radians())
            * Mat4::from_rotation_y(90f32.to_radians()),
        mirror,
    );
    b.mesh(
        side,
        Mat4::from_translation(Vec3::new(2.5, 1.75, 0.0))
            * Mat4::from_rotation_z(90f32.to_radians())
            * Mat4::from_rotation_y(90f32.to_radians()),
        mirror,
    );
    let (m, t) = wall(5.0, 3.5, Vec3::new(0.0, 1.75, -6.0));
    b.mesh(m, t, back);
    b.mesh(
        TriMesh::sphere(0.6, 48, 24),
        Mat4::from_translation(Vec3::new(-0.8, 0.6, -1.5)),
        blue,
    );
    b.mesh(
        TriMesh::cuboid(Vec3::new(0.8, 1.4, 0.8)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(25f32.to_radians()), Vec3::new(0.9, 0.7, -3.0)),
        orange,
    );
    b.camera(Camera {
        position: Vec3::new(-1.2, 1.6, 5.0),
        target: Vec3::new(1.5, 1.0, -2.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        near: 0.1,
        far: 60.0,
    });
    b.light(Light {
        direction: Vec3::new(0.2, 0.9, 0.35),
        color: Vec3::new(1.0, 0.97, 0.92),
        intensity: 2.4,
    });
    b.build()
}

/// Many curved reflectors: a 5 x 4 grid of spheres of varied reflectivity and colour on
/// a checkerboard floor.
pub fn spheres() -> Result<Scene> {
    let mut b = SceneBuilder::new("spheres");
    let dark = b.material(Material::new("dark tile", [0.12, 0.12, 0.14], 0.6, 0.0));
    let light = b.material(Material::new("light tile", [0.8, 0.8, 0.78], 0.6, 0.0));
    for j in 0..10 {
        for i in 0..10 {
            let c = Vec3::new(-9.0 + 2.0 * i as f32, 0.0, -13.0 + 2.0 * j as f32);
            b.mesh(
                TriMesh::quad(2.0, 2.0),
                Mat4::from_translation(c),
                if (i + j) % 2 == 0 { dark } else { light },
            );
        }
    }
    let palette = [
        [0.95, 0.95, 0.95],
        [0.95, 0.7, 0.25],
        [0.85, 0.15, 0.15],
        [0.2, 0.45, 0.9],
        [0.3, 0.8, 0.35],
    ];
    for j in 0..4 {
        for i in 0..5 {
            let k = (i + 2 * j) % 5;
            let refl = [0.95, 0.7, 0.4, 0.25, 0.6][(i + j) % 5];
            let m = b.material(Material::new(&format!("sphere {i},{j}"), palette[k], 0.1, refl));
            let c = Vec3::new(-4.0 + 2.0 * i as f32, 0.7, -7.0 + 2.2 * j as f32);
            b.mesh(TriMesh::sphere(0.7, 48, 24), Mat4::from_translation(c), m);
        }
    }
    b.camera(Camera {
        position: Vec3::new(0.0, 3.2, 5.5),
        target: Vec3::new(0.0, 0.5, -3.5),
        up: Vec3::Y,
        fov_y_deg: 55.0,
        near: 0.1,
        far: 80.0,
    });
    b.light(Light {
        direction: Vec3::new(-0.4, 0.75, 0.35),
        color: Vec3::new(1.0, 0.96, 0.9),
        intensity: 3.0,
    });
    b.build()
}

/// The default scene: an open-topped box room with a mirror-like floor, a glossy back
/// wall, coloured side walls, three spheres and two boxes, lit by a low sun so that
/// every object casts a visible shadow. Planar and curved reflectors, saturated
/// colours: reflections are easy to see.
pub fn room() -> Result<Scene> {
    let mut b = SceneBuilder::new("room");
    let floor = b.material(Material::new("mirror floor", [0.32, 0.32, 0.36], 0.04, 0.7));
    let back = b.material(Material::new("glossy back wall", [0.78, 0.72, 0.62], 0.25, 0.15));
    let red = b.material(Material::new("red wall", [0.72, 0.14, 0.12], 0.8, 0.0));
    let green = b.material(Material::new("green wall", [0.14, 0.58, 0.2], 0.8, 0.0));
    let chrome = b.material(Material::new("chrome", [0.9, 0.9, 0.92], 0.02, 0.9));
    let blue = b.material(Material::new("blue plastic", [0.08, 0.22, 0.8], 0.3, 0.2));
    let gold = b.material(Material::new("gold", [0.95, 0.66, 0.2], 0.1, 0.6));
    let orange = b.material(Material::new("orange box", [0.95, 0.42, 0.08], 0.6, 0.0));
    let purple = b.material(Material::new("purple box", [0.5, 0.16, 0.7], 0.5, 0.0));

    let (half, height) = (5.0f32, 6.0f32);
    b.mesh(TriMesh::quad(2.0 * half, 2.0 * half), Mat4::IDENTITY, floor);
    let wall = TriMesh::quad(2.0 * half, height);
    b.mesh(
        wall.clone(),
        Mat4::from_translation(Vec3::new(0.0, 0.5 * height, -half)) * Mat4::from_rotation_x(90f32.to_radians()),
        back,
    );
    b.mesh(
        wall.clone(),
        Mat4::from_translation(Vec3::new(-half, 0.5 * height, 0.0))
            * Mat4::from_rotation_z(-90f32.to_radians())
            * Mat4::from_rotation_y(90f32.to_radians()),
        red,
    );
    b.mesh(
        wall,
        Mat4::from_translation(Vec3::new(half, 0.5 * height, 0.0))
            * Mat4::from_rotation_z(90f32.to_radians())
            * Mat4::from_rotation_y(90f32.to_radians()),
        green,
    );
    b.mesh(
        TriMesh::sphere(1.0, 64, 32),
        Mat4::from_translation(Vec3::new(-1.5, 1.0, -1.6)),
        chrome,
    );
    b.mesh(
        TriMesh::sphere(0.7, 48, 24),
        Mat4::from_translation(Vec3::new(1.7, 0.7, 0.4)),
        blue,
    );
    b.mesh(
        TriMesh::sphere(0.45, 40, 20),
        Mat4::from_translation(Vec3::new(-0.1, 0.45, 1.6)),
        gold,
    );
    b.mesh(
        TriMesh::cuboid(Vec3::splat(1.5)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(30f32.to_radians()), Vec3::new(2.3, 0.75, -2.6)),
        orange,
    );
    b.mesh(
        TriMesh::cuboid(Vec3::new(1.0, 1.6, 1.0)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(-20f32.to_radians()), Vec3::new(-3.3, 0.8, 1.2)),
        purple,
    );
    b.camera(Camera {
        position: Vec3::new(0.0, 2.8, 7.8),
        target: Vec3::new(0.0, 1.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 55.0,
        near: 0.1,
        far: 50.0,
    });
    b.light(Light {
        direction: Vec3::new(-0.3, 0.85, 0.45),
        color: Vec3::new(1.0, 0.95, 0.88),
        intensity: 3.2,
    });
    b.build()
}
