//! Dynamic scenes end to end: `drop`'s rigid bodies and `cloth`'s sheet move every
//! frame, deterministically, and the hybrid frame matches the fully ray-traced one at
//! every frame of the animation (moving bodies reflected in the floor and the metals,
//! one of them behind the camera, seen only in the reflections; the cloth in the floor
//! and the chrome sphere).

use crate::common;

use speculum::headless::{self, FramePlan};
use speculum::settings::{Mode, Visibility};
use speculum::shader_defines::{SOURCE_RT, SOURCE_SSR};
use speculum::{Renderer, Settings};

/// 320x180: SSIM's 11x11 window spans a body's reflection, not the whole body (at
/// 192x108 one worst frame scores 0.969, at 384x216 0.986).
fn small(mode: Mode) -> Settings {
    Settings {
        width: 320,
        height: 180,
        mode,
        ..Default::default()
    }
}

/// `drop` (rigid bodies), `cloth` (the GPU cloth, its BVH refit) and the walking
/// figure (a skinned glTF on a mirror floor, its BVH refit).
fn dynamic_scenes() -> [speculum::scene::Scene; 3] {
    [
        speculum::scene::builtin::drop().unwrap(),
        speculum::scene::builtin::cloth().unwrap(),
        speculum::scene::load(crate::animation::FIGURE).unwrap(),
    ]
}

/// Frame k of a run is the same image in another run, and with a different warm-up
/// (warm-up frames are followed by a reset); and things do move (frame 12 differs
/// from frame 1). The adaptive hybrid at a fixed exchange rate and the G-buffer
/// rasterized: measured ones follow each run's timings.
#[test]
fn dynamic_frames_are_deterministic_whatever_the_warmup() {
    let ctx = common::context();
    for scene in dynamic_scenes() {
        let settings = Settings {
            exchange_rate: 0.5,
            visibility: Visibility::Raster,
            ..small(Mode::Hybrid)
        };
        let run = |warmup, frames| {
            let plan = FramePlan {
                warmup: speculum::steady::WarmUp::Frames(warmup),
                frames,
                reference: false,
                spp: 1,
            };
            headless::render(&ctx, &scene, &settings, plan, &mut || {})
                .unwrap()
                .rgba
        };
        let name = &scene.name;
        let a = run(0, 12);
        assert!(a == run(0, 12), "{name}: two runs differ at frame 12");
        assert!(a == run(3, 12), "{name}: the warm-up changed frame 12");
        let first = run(0, 1);
        let moved = a.iter().zip(&first).filter(|(x, y)| x != y).count();
        assert!(
            moved > 1000,
            "{name}: only {moved} bytes changed between frames 1 and 12"
        );
    }
}

/// Hybrid against rt on every frame of a 60-frame run of `drop` and of `cloth`: SSIM
/// at least 0.97, and every reflective pixel has a reflection.
#[test]
fn dynamic_hybrid_matches_rt_on_every_frame() {
    let ctx = common::context();
    for scene in dynamic_scenes() {
        let name = &scene.name;
        let mut hybrid = Renderer::new(&ctx, &scene, &small(Mode::Hybrid)).unwrap();
        let mut rt = Renderer::new(&ctx, &scene, &small(Mode::Rt)).unwrap();
        assert_eq!(hybrid.dynamic_triangles() as usize, scene.dynamic_triangle_count());
        let mut worst = (1.0f64, 0);
        for k in 0..60 {
            hybrid.render_frame().unwrap();
            rt.render_frame().unwrap();
            assert_eq!(hybrid.sim_steps(), k + 1);
            let (a, b) = (hybrid.read_output().unwrap(), rt.read_output().unwrap());
            let c = speculum::metrics::compare_rgba8(&a, &b, 320, 180).unwrap();
            if c.ssim < worst.0 {
                worst = (c.ssim, k);
            }
            let stats = hybrid.reflection_stats().unwrap();
            assert!(stats.reflective_pixels > 1000, "{name} frame {k}");
            let merged: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(
                &hybrid
                    .reflections
                    .merge
                    .out
                    .read(ash::vk::ImageLayout::GENERAL)
                    .unwrap(),
            );
            let reflective = hybrid.reflection_maps().unwrap().reflective;
            let holes = (0..merged.len())
                .filter(|&i| reflective[i] && ![SOURCE_SSR, SOURCE_RT].contains(&(merged[i][3] as u32)))
                .count();
            assert_eq!(holes, 0, "{name} frame {k}: reflective pixels without a reflection");
        }
        assert!(
            worst.0 >= 0.97,
            "{name} frame {}: hybrid vs rt SSIM {}",
            worst.1,
            worst.0
        );
    }
}

/// `render --sequence DIR --contact-sheet F --reference` on `drop`: one PNG and one
/// JSON line per measured frame, each line with its timings (the dynamic scopes
/// included), its dynamic triangles and its SSIM against rt; a sheet six frames wide.
#[test]
fn sequences_write_every_frame_and_their_lines() {
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("seq");
    let sheet = dir.path().join("sheet.png");
    let out = common::speculum([
        "render", "--scene", "drop", "--frames", "7", "--warmup", "1", "--width", "64", "--height", "48",
    ])
    .args(["--reference", "--quiet", "--sequence"])
    .arg(&seq)
    .arg("--contact-sheet")
    .arg(&sheet)
    .arg("--out")
    .arg(dir.path().join("last.png"))
    .run();
    assert!(out.ok(), "{}", out.stderr);
    let text = std::fs::read_to_string(seq.join("frames.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 7);
    let triangles = speculum::scene::builtin::drop().unwrap().dynamic_triangle_count() as u64;
    for (k, l) in lines.iter().enumerate() {
        assert_eq!(l["frame"], k as u64);
        assert!(seq.join(format!("frame_{k:04}.png")).is_file());
        assert_eq!(l["dynamic_triangles"], triangles);
        assert!(l["sim_ms"].as_f64().unwrap() >= 0.0 && l["frame_ms"].as_f64().unwrap() > 0.0);
        for scope in ["sim.transform", "lbvh.sort", "lbvh.fit", "rt.reflect"] {
            assert!(l["passes_ms"][scope].as_f64().unwrap() > 0.0, "frame {k}: {scope}");
        }
        assert!(l["passes_ms"].get("frame").is_none() && l["passes_ms"].get("sim.rigid").is_none());
        let ssim = l["ssim"].as_f64().unwrap();
        assert!(ssim > 0.5 && ssim <= 1.0, "frame {k}: {ssim}");
        // The ways the frame took, as its rows show them.
        let ran = |scope: &str| l["passes_ms"][scope].is_number();
        assert_eq!(l["visibility"] == "rays", ran("gbuffer.trace"), "frame {k}: {l}");
        assert_eq!(l["shadows"] != "rays", ran("shadow.map"), "frame {k}: {l}");
        assert_eq!(l["path"]["runs"] == "march", ran("ssr.trace"), "frame {k}: {l}");
        let idle = ["skip_march", "trace_all"];
        assert!(l["path"]["runs"] == l["path"]["shows"] || idle.iter().any(|p| l["path"]["shows"] == *p));
    }
    assert_eq!(lines[0]["path"], serde_json::json!({"runs": "march", "shows": "march"}));
    // The last sequence frame is the --out frame.
    assert_eq!(
        std::fs::read(seq.join("frame_0006.png")).unwrap(),
        std::fs::read(dir.path().join("last.png")).unwrap()
    );
    let img = image::open(&sheet).unwrap();
    assert_eq!((img.width(), img.height()), (6 * 64, 48));
}

/// Moving bodies above the top of the screen show in the floor: `drop` at frame 3 seen
/// from low down, looking at the floor, its bodies still high in the air. The pixels
/// where the rt frame changes when the bodies are taken out but the raster frame does
/// not (their shadows change both) hold only their reflections; hybrid must match rt
/// there, and `ssr`, which cannot see them, must not.
#[test]
fn bodies_above_the_screen_appear_in_hybrid_where_rt_puts_them() {
    let ctx = common::context();
    let mut scene = speculum::scene::builtin::drop().unwrap();
    scene.camera.position = glam::Vec3::new(0.0, 1.2, 4.5);
    scene.camera.target = glam::Vec3::new(0.0, 0.0, 0.0);
    scene.camera.fov_y_deg = 40.0;
    let mut without = scene.clone();
    without.bodies.clear();
    let at_frame = |scene: &speculum::scene::Scene, mode| {
        let mut r = Renderer::new(&ctx, scene, &small(mode)).unwrap();
        for _ in 0..3 {
            r.render_frame().unwrap();
        }
        r.read_output().unwrap()
    };
    let (rt, rt_without) = (at_frame(&scene, Mode::Rt), at_frame(&without, Mode::Rt));
    let (raster, raster_without) = (at_frame(&scene, Mode::Raster), at_frame(&without, Mode::Raster));
    let (hybrid, ssr) = (at_frame(&scene, Mode::Hybrid), at_frame(&scene, Mode::Ssr));
    let near = |a: &[u8], b: &[u8], i: usize, tol: i32| {
        (0..3).all(|c| (a[4 * i + c] as i32 - b[4 * i + c] as i32).abs() <= tol)
    };
    let shown: Vec<usize> = (0..rt.len() / 4)
        .filter(|&i| !near(&rt, &rt_without, i, 16) && near(&raster, &raster_without, i, 1))
        .collect();
    assert!(
        shown.len() > 200,
        "the bodies' reflections cover {} pixels",
        shown.len()
    );
    let in_hybrid = shown.iter().filter(|&&i| near(&hybrid, &rt, i, 8)).count();
    let in_ssr = shown.iter().filter(|&&i| near(&ssr, &rt, i, 8)).count();
    assert!(
        in_hybrid * 100 >= 95 * shown.len(),
        "hybrid shows them on {in_hybrid} of {}",
        shown.len()
    );
    assert!(
        in_ssr * 4 <= shown.len(),
        "ssr alone shows them on {in_ssr} of {}",
        shown.len()
    );
}

/// The G-buffer's motion takes each surface point back to where it was the frame
/// before: on `drop` (rigid bodies) and `cloth` (the GPU cloth) at 160x120, for pixels
/// where it is not zero, it equals the displacement a CPU ray cast through the pixel
/// finds on the moving triangle it hits (its vertices' last-frame positions minus this
/// frame's, interpolated at the hit), within half-float rounding; it is zero on the
/// static geometry, and everywhere in the first frame (of a renderer, and after a
/// restart: no frame before it) and once the scene is paused.
#[test]
fn motion_takes_each_point_back_to_where_it_was() {
    use glam::{IVec2, Vec3};
    use speculum::cpu_ref::trace::CpuBvh;
    let ctx = common::context();
    for scene in dynamic_scenes() {
        let (w, h) = (160usize, 120usize);
        let settings = Settings {
            width: w as u32,
            height: h as u32,
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
        let motionless = |r: &Renderer| {
            let m = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&r.lighting.gbuffer.out.motion).unwrap());
            m.iter().all(|m| m[..3] == [0.0; 3])
        };
        // The first frame has no frame before it, nor the first after a restart.
        r.render_frame().unwrap();
        assert!(motionless(&r), "{}: motion in the first frame", scene.name);
        r.render_frame().unwrap();
        r.reset_simulation().unwrap();
        r.render_frame().unwrap();
        assert!(
            motionless(&r),
            "{}: motion in the first frame after a reset",
            scene.name
        );
        for _ in 0..11 {
            r.render_frame().unwrap();
        }
        let before = r.read_dynamic_vertices().unwrap().unwrap();
        r.render_frame().unwrap();
        let now = r.read_dynamic_vertices().unwrap().unwrap();
        let frame = *r.uniforms();
        let g = &r.lighting.gbuffer.out;
        let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&g.depth).unwrap());
        let motion = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&g.motion).unwrap());
        let material: Vec<u32> = bytemuck::pod_collect_to_vec(&r.read_target(&g.material).unwrap());
        let indices = scene.dynamic_meshes().indices;
        let bvh = CpuBvh::build(&now, &indices);
        let camera = frame.camera_pos.truncate();
        let (mut moving, mut checked) = (0usize, 0usize);
        for i in 0..w * h {
            let m = Vec3::new(motion[i][0], motion[i][1], motion[i][2]);
            if material[i] == speculum::shader_defines::MATERIAL_NONE || m == Vec3::ZERO {
                continue;
            }
            moving += 1;
            if moving % 7 != 0 {
                continue; // a sample of them: the CPU cast is slow
            }
            let p = IVec2::new((i % w) as i32, (i / w) as i32);
            let x = speculum::cpu_ref::shading::world_from_depth(&frame, p, depth[i]);
            let ray = speculum::gpu_types::Ray {
                origin: camera.into(),
                tmin: 0.0,
                dir: (x - camera).normalize().into(),
                tmax: 3.0e38,
            };
            let hit = bvh.trace(&ray, &now, &indices);
            assert_ne!(
                hit.prim,
                speculum::shader_defines::BVH_INVALID,
                "pixel {p}: moves but hits nothing moving"
            );
            assert!(
                (hit.t - (x - camera).length()).abs() < 0.01,
                "pixel {p}: not the visible surface"
            );
            let t = hit.prim as usize;
            let weights = [1.0 - hit.u - hit.v, hit.u, hit.v];
            let want: Vec3 = (0..3)
                .map(|k| {
                    let v = indices[3 * t + k] as usize;
                    weights[k] * (Vec3::from(before[v].position) - Vec3::from(now[v].position))
                })
                .sum();
            // Half floats (1/1024 relative), and the pixel centre vs the hit's rounding.
            let tolerance = 2e-3 * want.length() + 2e-4;
            assert!(
                (m - want).length() <= tolerance,
                "pixel {p}: motion {m}, the cast finds {want}"
            );
            checked += 1;
        }
        assert!(checked > 50, "{}: only {checked} moving pixels checked", scene.name);
        // The static geometry (the floor, the walls) does not move.
        let still = (0..w * h)
            .filter(|&i| material[i] != speculum::shader_defines::MATERIAL_NONE && motion[i][..3] == [0.0; 3])
            .count();
        assert!(still > w * h / 4, "{}: {still} still pixels", scene.name);
        r.set_paused(true);
        r.render_frame().unwrap();
        assert!(motionless(&r), "{}: paused, yet moving", scene.name);
    }
    assert_eq!(ctx.validation_messages(), 0);
}
