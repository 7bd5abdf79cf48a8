//! SSR works at any scene scale: the same scene at 1/100 and 100 times its size (the
//! camera scaled with it) gives the same fail mask, pixel for pixel up to rounding.

use crate::common;

use speculum::scene::Scene;
use speculum::{Renderer, Settings};

/// `scene` with every length multiplied by `s`: vertices, camera and clip planes.
fn scaled(scene: &Scene, s: f32) -> Scene {
    let mut out = scene.clone();
    for v in &mut out.vertices {
        v.position = v.position.map(|c| c * s);
    }
    let c = &mut out.camera;
    c.position *= s;
    c.target *= s;
    c.near *= s;
    c.far *= s;
    out
}

/// Resolution of both tests' frames.
const SIZE: (u32, u32) = (192, 108);

/// A renderer of `scene` at `SIZE` (default settings) after one frame.
fn one_frame(ctx: &std::sync::Arc<speculum::vk::Context>, scene: &Scene) -> Renderer {
    let settings = Settings {
        width: SIZE.0,
        height: SIZE.1,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, scene, &settings).unwrap();
    r.render_frame().unwrap();
    r
}

#[test]
fn fail_masks_do_not_depend_on_the_scene_scale() {
    let ctx = common::context();
    let room = speculum::scene::builtin::room().unwrap();
    let mask = |scene: &Scene| one_frame(&ctx, scene).reflection_maps().unwrap();
    let base = mask(&room);
    let reflective = base.reflective.iter().filter(|r| **r).count();
    assert!(reflective > 1000);
    for s in [0.01f32, 100.0] {
        let other = mask(&scaled(&room, s));
        let same = base.mask.iter().zip(&other.mask).filter(|(a, b)| a == b).count();
        let share = same as f64 / base.mask.len() as f64;
        println!(
            "scale {s}: {same} of {} pixels have the same fail mask ({share:.4})",
            base.mask.len()
        );
        assert!(share >= 0.99, "scale {s}: only {share:.4} of the fail mask is the same");
    }
}

/// A scene far from the origin renders as it does at the origin: the renderer works
/// relative to the scene's centre, so neither depth nor shadows lose precision.
#[test]
fn far_from_the_origin_renders_the_same() {
    let ctx = common::context();
    let room = speculum::scene::builtin::room().unwrap();
    let render = |scene: &Scene| one_frame(&ctx, scene).read_output().unwrap();
    let base = render(&room);
    let offset = glam::Vec3::new(1e4, -3e3, 2e4);
    let mut far = room.clone();
    for v in &mut far.vertices {
        v.position = (glam::Vec3::from(v.position) + offset).to_array();
    }
    far.camera.position += offset;
    far.camera.target += offset;
    let c = speculum::metrics::compare_rgba8(&base, &render(&far), SIZE.0, SIZE.1).unwrap();
    println!("translated by {offset}: SSIM {:.4}, RMSE {:.4}", c.ssim, c.rmse);
    assert!(c.ssim >= 0.99, "SSIM {:.4}", c.ssim);
}

/// Dynamic scenes far from the origin too: `drop` (its bodies) and `cloth` (its sheet,
/// colliders and floor) moved by the same offset render frame 20 as at the origin:
/// both are simulated relative to the renderer's origin (at 2e4 units f32 steps of
/// ~2 mm made the bodies' paths diverge: SSIM 0.988, and the cloth was not moved at all).
#[test]
fn far_dynamic_scenes_render_the_same() {
    let ctx = common::context();
    let offset = glam::Vec3::new(1e4, -3e3, 2e4);
    let frame20 = |scene: &Scene| {
        // A fixed exchange rate and G-buffer: measured ones follow each run's timings.
        let settings = Settings {
            width: SIZE.0,
            height: SIZE.1,
            exchange_rate: 0.5,
            visibility: speculum::settings::Visibility::Raster,
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, scene, &settings).unwrap();
        for _ in 0..20 {
            r.render_frame().unwrap();
        }
        r.read_output().unwrap()
    };
    for scene in [
        speculum::scene::builtin::drop().unwrap(),
        speculum::scene::builtin::cloth().unwrap(),
    ] {
        let mut far = scene.clone();
        for v in &mut far.vertices {
            v.position = (glam::Vec3::from(v.position) + offset).to_array();
        }
        far.camera.position += offset;
        far.camera.target += offset;
        for b in &mut far.bodies {
            b.position += offset;
        }
        for c in &mut far.cloths {
            c.center += offset;
            c.floor_y += offset.y;
            for s in &mut c.spheres {
                *s += offset.extend(0.0);
            }
        }
        let c = speculum::metrics::compare_rgba8(&frame20(&scene), &frame20(&far), SIZE.0, SIZE.1).unwrap();
        println!("{} translated by {offset}: SSIM {:.4}", scene.name, c.ssim);
        assert!(c.ssim >= 0.99, "{}: SSIM {:.4}", scene.name, c.ssim);
    }
}
