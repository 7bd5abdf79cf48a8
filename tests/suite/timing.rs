//! Timings that can be trusted: every scope of a real frame marks its place in the
//! command stream, so the scopes nest, follow each other and fill the frame
//! (`vk::timing::check_spans`). Without the barrier after each timestamp, lavapipe
//! resolved `ssr.trace`'s first stamp after its own dispatch: the scope read ~0.1 ms and
//! ~60 ms of work fell in the gap before it, which these tests catch.

use crate::common;

use speculum::vk::timing::{GAP_MARGIN_MS, GAP_MARGIN_REL};
use speculum::vk::GpuTimer;
use speculum::{Renderer, Settings};

/// Records, submits and waits for one frame through the window's path (no wall
/// clock: only the scopes' own agreement is checked, whatever the machine's load).
fn frame_readout(r: &mut Renderer, ctx: &speculum::vk::Context) -> speculum::vk::TimerReadout {
    let cmd = ctx.allocate_command_buffer().unwrap();
    ctx.rerecord(cmd, |cmd| r.record_frame(cmd, 0)).unwrap();
    ctx.submit_and_wait(cmd).unwrap();
    ctx.free_command_buffer(cmd);
    r.frame_finished(0).unwrap()
}

/// Frames tried for each one that must pass its self-check.
const ATTEMPTS: usize = 4;

/// The next frame whose timings pass their self-check, within `ATTEMPTS` frames: a
/// lavapipe thread preempted between two stamps (by another process, or by this
/// virtual machine's host) opens a gap in that one frame, which the check rightly
/// refuses, while a stamp that does not mark its place fails every frame (the bug
/// these tests catch put ~60 ms in the gap of each one). Every refused frame is printed.
fn checked_frame(r: &mut Renderer, ctx: &speculum::vk::Context, what: &str) -> speculum::vk::TimerReadout {
    let mut refused = Vec::new();
    for _ in 0..ATTEMPTS {
        let t = frame_readout(r, ctx);
        match t.problem {
            None => return t,
            Some(p) => {
                eprintln!("{what}: a frame refused by its self-check: {p}");
                refused.push((p, t.scopes));
            }
        }
    }
    panic!("{what}: none of {ATTEMPTS} frames passed its self-check: {refused:#?}");
}

/// Every scope of `room` (SSR's indirect march included) and of `drop` (the sim and
/// dynamic BVH scopes too) passes the self-check (`checked_frame`), in every
/// reflecting mode, and the
/// scopes the frame's work is in read what it costs, by bounds that hold on any device:
/// - the inner scopes cover the frame to within the self-check's own margin
///   (`GAP_MARGIN_MS` + `GAP_MARGIN_REL` of the frame: the stamps' and barriers' cost,
///   absolute for a GPU's sub-millisecond frame, relative for lavapipe's long one; it
///   was "more than half the frame", which a GPU frame of 0.3 ms with 0.2 ms of stamps
///   could miss and lavapipe's misplaced stamp, ~60 ms of ~100, passed);
/// - `ssr.trace` reads at least a tenth of `ssr.classify`: per reflective pixel the
///   march reads the pixel's G-buffer as the classification does and then steps the
///   pyramid at least once, so on any device it does more memory work than the pass
///   that only classifies (the misplaced stamp read 0.1 ms against ~20).
#[test]
fn frame_scopes_nest_and_fill_the_frame() {
    let _one = common::alone();
    let ctx = common::context();
    for name in ["room", "drop"] {
        let scene = speculum::scene::load(name).unwrap();
        for mode in [speculum::settings::Mode::Hybrid, speculum::settings::Mode::Rt] {
            // The SSR-first hybrid: the adaptive one may not march.
            let settings = Settings {
                width: 320,
                height: 180,
                mode,
                hybrid_policy: speculum::settings::HybridPolicy::SsrFirst,
                ..Settings::default()
            };
            let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
            for k in 0..3 {
                let t = checked_frame(&mut r, &ctx, &format!("{name} {mode:?} frame {k}"));
                let frame = t.get(speculum::renderer::FRAME).unwrap();
                let inner: f64 = t
                    .iter()
                    .filter(|(n, _)| *n != speculum::renderer::FRAME && *n != "sim.rigid")
                    .map(|s| s.1)
                    .sum();
                let margin = GAP_MARGIN_MS + GAP_MARGIN_REL * frame;
                assert!(
                    inner <= frame * 1.001 + 0.01 && frame - inner <= margin,
                    "{name}: {inner} of {frame} ms (margin {margin} ms)"
                );
                if mode == speculum::settings::Mode::Hybrid {
                    let (classify, trace) = (t.get("ssr.classify").unwrap(), t.get("ssr.trace").unwrap());
                    assert!(
                        trace > 0.1 * classify,
                        "{name}: ssr.trace {trace} ms, ssr.classify {classify} ms"
                    );
                }
            }
        }
    }
}

/// The frame's wall clock from submit to fence bounds its `frame` scope from above on
/// every device (`render_frame`'s check); a lone traversal dispatch (`rt.trace`, the
/// scope that read 0.1 ms on lavapipe) and an LBVH build with its stages pass too.
#[test]
fn one_shot_scopes_pass_their_self_check() {
    let _one = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::load("room").unwrap();
    let mut r = Renderer::new(
        &ctx,
        &scene,
        &Settings {
            width: 160,
            height: 90,
            ..Settings::default()
        },
    )
    .unwrap();
    for _ in 0..2 {
        // Re-measured while a readout fails (a preempted lavapipe thread opens a gap);
        // the CPU device's lower bound depends on the machine's load, the upper one not.
        let (t, _) = r.render_frame_measured().unwrap();
        if let Some(p) = &t.problem {
            assert!(p.contains("on a CPU device"), "{p}");
        }
    }
    let (v, i) = speculum::scene::soup::random_soup(20_000, 1.0, 10.0, 5);
    let triangles = speculum::tracers::lbvh::UploadedTriangles::new(&ctx, "t", &v, &i).unwrap();
    let geometry = triangles.geometry();
    let builder = speculum::tracers::lbvh::LbvhBuilder::new(&ctx).unwrap();
    let bvh =
        speculum::tracers::lbvh::Bvh::new_static(&ctx, 20_000, speculum::tracers::lbvh::MortonBits::Bits30).unwrap();
    let mut timer = GpuTimer::new(&ctx, 8).unwrap();
    // As for frames (`checked_frame`): a build refused by its self-check may be a
    // lavapipe thread preempted between two stamps (`remeasure_readout` tries again); one that
    // never passes is a bug.
    let (build, discarded) =
        speculum::vk::remeasure_readout(|| speculum::bench::lbvh::timed_build(&mut timer, &builder, geometry, &bvh))
            .unwrap();
    assert_eq!(
        build.problem, None,
        "no build passed its self-check ({discarded} refused before): {:?}",
        build.scopes
    );
    assert_eq!(build.len(), 5, "the build and its four stages: {:?}", build.scopes);
    // Timed whole (`outermost_only`): the build's scope alone, then its stages again.
    timer.outermost_only(true);
    let (whole, _) =
        speculum::vk::remeasure_readout(|| speculum::bench::lbvh::timed_build(&mut timer, &builder, geometry, &bvh))
            .unwrap();
    timer.outermost_only(false);
    assert_eq!(whole.problem, None, "{:?}", whole.scopes);
    let names: Vec<&str> = whole.scopes.iter().map(|s| s.0).collect();
    assert_eq!(names, [speculum::bench::lbvh::BUILD], "{:?}", whole.scopes);
    let (staged, _) =
        speculum::vk::remeasure_readout(|| speculum::bench::lbvh::timed_build(&mut timer, &builder, geometry, &bvh))
            .unwrap();
    assert_eq!(staged.len(), 5, "stamped again: {:?}", staged.scopes);
    let (lo, hi) = (glam::Vec3::splat(-5.0), glam::Vec3::splat(5.0));
    let rays = speculum::bench::lbvh::incoherent_rays(lo, hi, 50_000, 3);
    timer
        .one_shot(|cmd, timer| builder.record_compact(cmd, timer, &bvh))
        .unwrap();
    let tracer = speculum::passes::rt_trace::TracePass::<speculum::tracers::Lbvh>::new(&ctx).unwrap();
    let scene = speculum::tracers::TraceScene {
        static_bvh: Some(speculum::tracers::Traceable { bvh: &bvh, geometry }),
        dynamic_bvh: None,
    };
    let (_, t) = tracer.trace(&rays, scene, false).unwrap();
    assert_eq!(t.problem, None);
    assert!(t.get("rt.trace").unwrap() > 0.0, "{:?}", t.scopes);
}
