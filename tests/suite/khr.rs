//! The vendor tracer (`tracer = khr`) against the CPU: the driver's acceleration
//! structures and a ray-tracing pipeline find the hits brute force finds (the same
//! triangle, t within 1e-4 relative; ties counted), closest and any hit, over scenes of
//! 1, 2 and thousands of triangles; a device without the extensions is told so.

use crate::common;
use crate::trace::{compare_within, random_rays};

use glam::Vec3;
use speculum::cpu_ref::lbvh::triangle;
use speculum::cpu_ref::trace::{brute_force, intersect};
use speculum::gpu_types::{GpuVertex, Hit, Ray};
use speculum::passes::rt_trace::TracePass;
use speculum::scene::soup::{default_size, random_soup};
use speculum::shader_defines::BVH_INVALID;
use speculum::tracers::khr::{KhrScene, StaticInput, StaticOrder};
use speculum::tracers::lbvh::UploadedTriangles;
use speculum::tracers::Khr;
use speculum::vk::ContextDesc;

/// Relative t tolerance between the driver's intersection test and the CPU's
/// Moller-Trumbore (both single precision, computed differently).
const T_REL: f32 = 1e-4;

/// The vendor tracer's hits against brute force's: the same triangle with t within
/// `T_REL` (barycentrics within 1e-3), or a counted tie.
fn compare(gpu: &[Hit], cpu: &[Hit], rays: &[Ray], tri_of: impl Fn(u32) -> [Vec3; 3]) -> usize {
    compare_within(gpu, cpu, rays, tri_of, (T_REL, 1e-3))
}

fn traced(v: &[GpuVertex], i: &[u32], rays: &[Ray], any_hit: bool) -> Vec<Hit> {
    let ctx = common::context();
    assert!(
        ctx.ray_tracing.is_some() || ctx.driver_name != "llvmpipe",
        "lavapipe 25 has the vendor tracer's extensions: {:?}",
        ctx.ray_tracing_missing
    );
    if ctx.ray_tracing.is_none() {
        eprintln!("skipped: {} lacks {:?}", ctx.device_name, ctx.ray_tracing_missing);
        return rays.iter().map(|r| brute_force(r, v, i)).collect();
    }
    let tris = UploadedTriangles::new(&ctx, "khr", v, i).unwrap();
    let pass = TracePass::<Khr>::new(&ctx).unwrap();
    let mut out = Vec::new();
    // Either order of the triangles traces the same hits (ids mapped back).
    for order in [StaticOrder::File, StaticOrder::Morton] {
        let input = StaticInput::new(tris.geometry(), v, i, order);
        let scene = KhrScene::new_static(&ctx, &input).unwrap();
        let (hits, _) = pass.trace(rays, scene.trace(tris.geometry(), None), any_hit).unwrap();
        out.push(hits);
    }
    assert_eq!(ctx.validation_messages(), 0);
    let morton = out.pop().unwrap();
    let file = out.pop().unwrap();
    let ids = |h: &[Hit]| h.iter().map(|h| h.prim).collect::<Vec<_>>();
    if !any_hit {
        // (An any-hit ray may stop at another triangle in another tree.)
        assert_eq!(ids(&file), ids(&morton), "file and Morton order hit the same triangles");
    }
    morton
}

/// 4,000 random rays against a 3,000-triangle soup: every closest hit is brute force's
/// (ties excepted, counted, rare); every any-hit agrees on whether something is hit,
/// and what it reports is a real hit of that ray.
#[test]
fn khr_hits_equal_brute_force() {
    let n = 3000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 31);
    let rays = random_rays(4000, &v, &i, 1.0, 32);
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    let hits = cpu.iter().filter(|h| h.prim != BVH_INVALID).count();
    assert!(hits > 2000 && hits < 3900, "a mix of hits and misses: {hits}");
    let gpu = traced(&v, &i, &rays, false);
    let ties = compare(&gpu, &cpu, &rays, |p| triangle(&v, &i, p as usize));
    assert!(ties <= rays.len() / 1000, "{ties} ties");
    let any = traced(&v, &i, &rays, true);
    for (k, ((a, c), r)) in any.iter().zip(&cpu).zip(&rays).enumerate() {
        assert_eq!(
            a.prim == BVH_INVALID,
            c.prim == BVH_INVALID,
            "ray {k}: any {a:?} closest {c:?}"
        );
        if a.prim != BVH_INVALID {
            let t = intersect(r, &triangle(&v, &i, a.prim as usize)).map(|h| h.0);
            assert!(
                t.is_some_and(|t| (t - a.t).abs() <= T_REL * t.max(1.0)),
                "ray {k}: {a:?}"
            );
        }
    }
}

/// Builds of one and of two triangles trace as brute force says (the smallest trees).
#[test]
fn khr_traces_one_and_two_triangles() {
    for n in [1, 2] {
        let (v, i) = random_soup(n, 1.0, default_size(n), 40 + n as u64);
        let rays = random_rays(200, &v, &i, 1.0, 50 + n as u64);
        let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
        assert!(cpu.iter().any(|h| h.prim != BVH_INVALID), "{n}: some rays hit");
        let gpu = traced(&v, &i, &rays, false);
        let ties = compare(&gpu, &cpu, &rays, |p| triangle(&v, &i, p as usize));
        assert_eq!(ties, 0, "{n} triangles");
    }
}

/// A device whose ray-tracing extensions are hidden has no vendor tracer, and says what
/// it lacks in one line.
#[test]
fn hidden_ray_tracing_is_missing() {
    let ctx = common::context_with(ContextDesc {
        no_ray_tracing: true,
        ..Default::default()
    });
    assert!(ctx.ray_tracing.is_none());
    let why = ctx.ray_tracing_missing.clone().expect("a reason");
    assert!(!why.contains('\n') && why.contains("ray-tracing"), "{why}");
}

/// Every static built-in scene renders the same image through either tracer, in
/// `hybrid` and `rt`, with map and ray shadows: SSIM >= 0.999 (the driver's intersection
/// test differs from the walk's in the last bits of t; here the images are in fact
/// byte-identical). The vendor tracer's frame passes validation.
#[test]
fn khr_renders_what_lbvh_renders() {
    use speculum::settings::{Mode, Shadows, Tracer};
    use speculum::{headless, Settings};
    let ctx = common::context();
    if ctx.ray_tracing.is_none() {
        assert_ne!(ctx.driver_name, "llvmpipe", "lavapipe 25 has the vendor tracer");
        return;
    }
    let plan = headless::FramePlan {
        warmup: speculum::steady::WarmUp::Frames(0),
        frames: 1,
        reference: false,
        spp: 1,
    };
    for name in ["room", "mirrors", "spheres", "offscreen", "gallery"] {
        let scene = speculum::scene::builtin::by_name(name).unwrap().unwrap();
        for (mode, shadows) in [
            (Mode::Hybrid, Shadows::Map),
            (Mode::Rt, Shadows::Rays),
            (Mode::Hybrid, Shadows::Hybrid),
        ] {
            let image = |tracer| {
                let settings = Settings {
                    width: 160,
                    height: 90,
                    mode,
                    shadows,
                    tracer,
                    ..Default::default()
                };
                headless::render(&ctx, &scene, &settings, plan, &mut || {})
                    .unwrap()
                    .rgba
            };
            let (lbvh, khr) = (image(Tracer::Lbvh), image(Tracer::Khr));
            let c = speculum::metrics::compare_rgba8(&lbvh, &khr, 160, 90).unwrap();
            assert!(c.ssim >= 0.999, "{name} {mode:?} {shadows:?}: {c:?}");
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// `tracer = khr` is refused in one line before any GPU work on a device without the
/// extensions (hidden here), naming what is missing. Switching a renderer's tracer in
/// place renders what a fresh renderer of that tracer renders.
#[test]
fn khr_refusals_and_switching() {
    use speculum::settings::Tracer;
    use speculum::{Renderer, Settings};
    let khr = Settings {
        width: 64,
        height: 40,
        tracer: Tracer::Khr,
        ..Default::default()
    };
    let room = speculum::scene::builtin::room().unwrap();
    let hidden = common::context_with(ContextDesc {
        no_ray_tracing: true,
        ..Default::default()
    });
    let e = Renderer::new(&hidden, &room, &khr).err().expect("refused").to_string();
    assert!(
        e.contains("tracer khr needs ray tracing") && e.contains("lacks") && !e.contains('\n'),
        "{e}"
    );
    let ctx = common::context();
    if ctx.ray_tracing.is_none() {
        return;
    }
    let lbvh = Settings {
        tracer: Tracer::Lbvh,
        ..khr.clone()
    };
    let frame = |r: &mut Renderer| {
        r.render_frame().unwrap();
        r.read_output().unwrap()
    };
    let mut fresh = Renderer::new(&ctx, &room, &khr).unwrap();
    let want = frame(&mut fresh);
    let mut switched = Renderer::new(&ctx, &room, &lbvh).unwrap();
    frame(&mut switched);
    switched.set_settings(khr.clone()).unwrap();
    // The glossy sequence and history restarted, as a fresh renderer's are.
    switched.reset_simulation().unwrap();
    assert_eq!(frame(&mut switched), want, "switched to khr in place");
    // A moving scene switched with two frames in flight (the demo's): the second
    // slot's frame has its own instances.
    let drop = speculum::scene::builtin::by_name("drop").unwrap().unwrap();
    let mut r = Renderer::new(&ctx, &drop, &lbvh).unwrap();
    r.set_frames_in_flight(2).unwrap();
    r.set_settings(khr.clone()).unwrap();
    for slot in [0, 1, 0, 1] {
        let cmd = ctx.allocate_command_buffer().unwrap();
        ctx.rerecord(cmd, |cmd| r.record_frame(cmd, slot)).unwrap();
        ctx.submit_and_wait(cmd).unwrap();
        ctx.free_command_buffer(cmd);
        r.frame_finished(slot).unwrap();
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// Frames of a renderer with `settings` on `scene`, one image per frame.
fn frames(scene: &speculum::scene::Scene, settings: &speculum::Settings, n: usize) -> Vec<Vec<u8>> {
    let ctx = common::context();
    let mut r = speculum::Renderer::new(&ctx, scene, settings).unwrap();
    let out = (0..n)
        .map(|_| {
            r.render_frame().unwrap();
            r.read_output().unwrap()
        })
        .collect();
    assert_eq!(ctx.validation_messages(), 0);
    out
}

/// Every frame of `drop` (rigid bodies: instances of their shapes' bottom levels, the
/// top level rebuilt from the poses), of `cloth` and of the walking figure (their
/// deformable bottom level updated every frame) through the vendor tracer matches the LBVH's, 60 frames each, hybrid with
/// ray shadows (the adaptive hybrid at a fixed exchange rate and the G-buffer
/// rasterized: measured ones would follow each run's timings); and the cloth updated 29 times in 30 frames renders as
/// the cloth rebuilt every frame.
#[test]
fn khr_moving_scenes_render_what_lbvh_renders() {
    use speculum::settings::{Mode, Shadows, Tracer, Visibility};
    use speculum::Settings;
    if common::context().ray_tracing.is_none() {
        return;
    }
    let (w, h) = (128, 72);
    for name in ["drop", "cloth", "assets/models/figure.glb"] {
        let scene = speculum::scene::load(name).unwrap();
        let settings = |tracer| Settings {
            width: w,
            height: h,
            mode: Mode::Hybrid,
            shadows: Shadows::Rays,
            tracer,
            exchange_rate: 0.5,
            visibility: Visibility::Raster,
            ..Default::default()
        };
        let lbvh = frames(&scene, &settings(Tracer::Lbvh), 60);
        let khr = frames(&scene, &settings(Tracer::Khr), 60);
        for (k, (a, b)) in lbvh.iter().zip(&khr).enumerate() {
            let c = speculum::metrics::compare_rgba8(a, b, w, h).unwrap();
            assert!(c.ssim >= 0.999, "{name} frame {k}: {c:?}");
        }
        // The frames differ from each other: the scene moves.
        assert_ne!(khr[0], khr[59], "{name} moves");
    }
    let cloth = speculum::scene::builtin::by_name("cloth").unwrap().unwrap();
    let updated = Settings {
        width: w,
        height: h,
        tracer: Tracer::Khr,
        refit_rebuild_every: 30,
        exchange_rate: 0.5,
        visibility: Visibility::Raster,
        ..Default::default()
    };
    let rebuilt = Settings {
        cloth_rebuild: true,
        ..updated.clone()
    };
    let (a, b) = (frames(&cloth, &updated, 30), frames(&cloth, &rebuilt, 30));
    let c = speculum::metrics::compare_rgba8(&a[29], &b[29], w, h).unwrap();
    assert!(c.ssim >= 0.999, "cloth updated vs rebuilt: {c:?}");
}

/// A vendor-traced renderer resized renders what a fresh one renders at the new size.
#[test]
fn khr_resize_renders_what_a_fresh_renderer_renders() {
    use speculum::settings::{Mode, Tracer};
    use speculum::{Renderer, Settings};
    let ctx = common::context();
    if ctx.ray_tracing.is_none() {
        return;
    }
    let scene = speculum::scene::builtin::room().unwrap();
    let at = |width, height| Settings {
        width,
        height,
        mode: Mode::Rt,
        tracer: Tracer::Khr,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &at(64, 40)).unwrap();
    r.render_frame().unwrap();
    r.resize(90, 50).unwrap();
    r.render_frame().unwrap();
    let mut fresh = Renderer::new(&ctx, &scene, &at(90, 50)).unwrap();
    fresh.render_frame().unwrap();
    assert_eq!(r.read_output().unwrap(), fresh.read_output().unwrap());
    assert_eq!(ctx.validation_messages(), 0);
}

/// A build of 100,000 triangles traces as brute force says (a few hundred rays: lavapipe
/// traces a soup in file order slowly, see docs/tracers.md).
#[test]
fn khr_traces_100k_triangles() {
    let n = 100_000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 61);
    let rays = random_rays(300, &v, &i, 1.0, 62);
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    let gpu = traced(&v, &i, &rays, false);
    let ties = compare(&gpu, &cpu, &rays, |p| triangle(&v, &i, p as usize));
    assert!(ties <= 1, "{ties} ties");
}

/// Moving geometry with nothing in it (no bodies, no cloth) leaves the static
/// instance alone in the top level, which traces as brute force says; a moving
/// bottom level whose first triangle is beyond an instance's 23-bit custom index is
/// refused in one line before anything is built.
#[test]
fn khr_empty_dynamic_set_and_the_index_limit() {
    use speculum::tracers::khr::{BodyRange, DynamicLayout};
    let ctx = common::context();
    if ctx.ray_tracing.is_none() {
        return;
    }
    let (v, i) = random_soup(500, 1.0, default_size(500), 71);
    let tris = UploadedTriangles::new(&ctx, "khr", &v, &i).unwrap();
    let input = StaticInput::new(tris.geometry(), &v, &i, StaticOrder::Morton);
    let empty = DynamicLayout {
        objects: tris.geometry().vertices,
        object_vertices: v.len() as u32,
        world: tris.geometry(),
        bodies: Vec::new(),
        cloth: None,
        rebuild_every: 60,
    };
    let scene = KhrScene::new(&ctx, &input, Some(&empty), &[]).unwrap();
    let rays = random_rays(400, &v, &i, 1.0, 72);
    let pass = TracePass::<Khr>::new(&ctx).unwrap();
    let (hits, _) = pass.trace(&rays, scene.trace(tris.geometry(), None), false).unwrap();
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    assert_eq!(compare(&hits, &cpu, &rays, |p| triangle(&v, &i, p as usize)), 0);
    let beyond = DynamicLayout {
        bodies: vec![BodyRange {
            first_tri: 9_000_000,
            tris: 1,
            shape_of: 0,
        }],
        ..empty
    };
    let e = KhrScene::new(&ctx, &input, Some(&beyond), &[glam::Mat4::IDENTITY])
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("custom index") && e.contains("9000000") && !e.contains('\n'),
        "{e}"
    );
    assert_eq!(ctx.validation_messages(), 0);
}
