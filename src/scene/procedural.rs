//! Built-in scenes, made from code so that tests and the README need no assets.

use super::{Camera, Light, Material, Scene, SceneBuilder, TriMesh};
use crate::error::Result;
use glam::{Mat4, Quat, Vec3};

/// Names accepted by `--scene`.
pub const NAMES: &[&str] = &["room"];

/// The built-in scene called `name`, if there is one.
pub fn by_name(name: &str) -> Option<Result<Scene>> {
    match name {
        "room" => Some(room()),
        _ => None,
    }
}

/// The default scene: an open-topped box room with a mirror-like floor, a glossy back
/// wall, coloured side walls, three spheres and two boxes, lit by a low sun so that
/// every object casts a visible shadow. Planar and curved reflectors, saturated
/// colours: reflections are easy to see.
pub fn room() -> Result<Scene> {
    let mut b = SceneBuilder::new("room");
    let floor = b.material(Material::new("mirror floor", [0.32, 0.32, 0.36], 0.04, 0.7));
    let back = b.material(Material::new("glossy back wall", [0.78, 0.72, 0.62], 0.25, 0.35));
    let red = b.material(Material::new("red wall", [0.72, 0.14, 0.12], 0.8, 0.0));
    let green = b.material(Material::new("green wall", [0.14, 0.58, 0.2], 0.8, 0.0));
    let chrome = b.material(Material::new("chrome", [0.9, 0.9, 0.92], 0.02, 0.9));
    let blue = b.material(Material::new("blue plastic", [0.08, 0.22, 0.8], 0.3, 0.2));
    let gold = b.material(Material::new("gold", [0.95, 0.66, 0.2], 0.1, 0.6));
    let orange = b.material(Material::new("orange box", [0.95, 0.42, 0.08], 0.6, 0.0));
    let purple = b.material(Material::new("purple box", [0.5, 0.16, 0.7], 0.5, 0.0));

    let (half, height) = (5.0f32, 4.0f32);
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
