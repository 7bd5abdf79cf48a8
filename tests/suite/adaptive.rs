//! The adaptive hybrid (`hybrid_policy = adaptive`, issue 42): tiles whose SSR answers
//! less than the exchange rate go straight to the ray tracer, the rest march first;
//! with a GPU-like rate the frame keeps SSR where it answers; with a fixed rate it is
//! deterministic; a measured rate comes from the frame's own timings; with it the
//! frame's paths (marching, or not at all) are priced and the cheapest taken; the
//! report says how the tiles split.

use crate::common;

use speculum::cpu_ref::ssr::tile_hysteresis;
use speculum::settings::{HybridPolicy, Mode, Visibility};
use speculum::shader_defines::{FAIL_SKIPPED, TILE_KNOWN, TILE_RAYS_ONLY, TILE_SUCCESS, TILE_WORDS};
use speculum::{Renderer, Settings};

const W: u32 = 320;
const H: u32 = 176;

fn settings(policy: HybridPolicy, exchange_rate: f32) -> Settings {
    Settings {
        width: W,
        height: H,
        mode: Mode::Hybrid,
        hybrid_policy: policy,
        exchange_rate,
        visibility: Visibility::Raster,
        ..Default::default()
    }
}

/// `spheres` in the adaptive hybrid at `exchange_rate` and in the `rt` mode.
fn adaptive_and_rt(ctx: &std::sync::Arc<speculum::vk::Context>, exchange_rate: f32) -> (Renderer, Renderer) {
    let scene = speculum::scene::builtin::spheres().unwrap();
    let r = Renderer::new(ctx, &scene, &settings(HybridPolicy::Adaptive, exchange_rate)).unwrap();
    (r, Renderer::new(ctx, &scene, &rt_settings()).unwrap())
}

/// The `rt` mode at the tests' size.
fn rt_settings() -> Settings {
    Settings {
        mode: Mode::Rt,
        ..settings(HybridPolicy::SsrFirst, 0.0)
    }
}

/// The adaptive hybrid with a measured rate and glossy off (a still view renders the
/// same image again where the tiles keep their class) on `scene`, through `tracer`.
fn glossy_off(
    ctx: &std::sync::Arc<speculum::vk::Context>,
    scene: &speculum::scene::Scene,
    tracer: speculum::settings::Tracer,
) -> Renderer {
    let st = Settings {
        glossy: false,
        tracer,
        ..settings(HybridPolicy::Adaptive, 0.0)
    };
    Renderer::new(ctx, scene, &st).unwrap()
}

/// The tiles' state words after the last frame.
fn tile_states(r: &Renderer) -> Vec<u32> {
    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.tiles_written().read().unwrap());
    words.into_iter().step_by(TILE_WORDS as usize).collect()
}

/// Each tile's share of marched pixels SSR answered in an SSR-first frame's fail mask
/// (`None`: nothing marched there), from the mask and the reflective pixels.
fn ssr_answered(r: &Renderer) -> Vec<Option<f64>> {
    let maps = r.reflection_maps().unwrap();
    let tiles_x = W.div_ceil(8) as usize;
    let mut counts = vec![(0u32, 0u32); tiles_x * H.div_ceil(8) as usize];
    for (i, (&m, &reflective)) in maps.mask.iter().zip(&maps.reflective).enumerate() {
        let marched = reflective && m & (speculum::shader_defines::FAIL_LOW_CONFIDENCE | FAIL_SKIPPED) == 0;
        if marched {
            let t = (i / W as usize / 8) * tiles_x + (i % W as usize) / 8;
            counts[t].0 += 1;
            counts[t].1 += (m == 0) as u32;
        }
    }
    counts
        .into_iter()
        .map(|(m, a)| (m > 0).then(|| a as f64 / m as f64))
        .collect()
}

/// With the exchange rate of a GPU (0.1: a march costs a tenth of a ray), `room` keeps
/// at least 90% of the tiles where SSR answers at least 90% of the marched pixels
/// SSR-first, and its image equals the SSR-first hybrid's within SSIM 0.999 (issue 42's
/// floor). With the rate of a march costing 0.9 of a ray, the tiles where SSR mostly
/// fails go rays-only and their pixels are traced (`FAIL_SKIPPED`) while the floor
/// marches on, at the rt reference's quality.
#[test]
fn tiles_follow_the_exchange_rate() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let mut first = Renderer::new(&ctx, &scene, &settings(HybridPolicy::SsrFirst, 0.0)).unwrap();
    let mut gpu = Renderer::new(&ctx, &scene, &settings(HybridPolicy::Adaptive, 0.1)).unwrap();
    let mut dear = Renderer::new(&ctx, &scene, &settings(HybridPolicy::Adaptive, 0.9)).unwrap();
    let mut rt = Renderer::new(&ctx, &scene, &rt_settings()).unwrap();
    for _ in 0..12 {
        for r in [&mut first, &mut gpu, &mut dear, &mut rt] {
            r.render_frame().unwrap();
        }
    }
    let answered = ssr_answered(&first);
    let states = tile_states(&gpu);
    let good: Vec<usize> = (0..answered.len())
        .filter(|&t| answered[t].is_some_and(|a| a >= 0.9))
        .collect();
    let kept = good.iter().filter(|&&t| states[t] & TILE_RAYS_ONLY == 0).count();
    assert!(
        good.len() > 100 && kept * 10 >= good.len() * 9,
        "{kept} of {} tiles SSR-first",
        good.len()
    );
    let image = |r: &Renderer| r.read_output().unwrap();
    let c = speculum::metrics::compare_rgba8(&image(&gpu), &image(&first), W, H).unwrap();
    assert!(c.ssim >= 0.999, "{c:?}");
    let states = tile_states(&dear);
    let rays_only = states.iter().filter(|&&s| s & TILE_RAYS_ONLY != 0).count();
    let known = states.iter().filter(|&&s| s & TILE_KNOWN != 0).count();
    assert!(
        rays_only * 5 > known && rays_only < known && known > 100,
        "{rays_only} of {known} known tiles rays-only"
    );
    let maps = dear.reflection_maps().unwrap();
    let skipped = maps.mask.iter().filter(|&&m| m & FAIL_SKIPPED != 0).count();
    assert!(skipped > 5000, "{skipped} pixels skipped");
    let vs_rt = speculum::metrics::compare_rgba8(&image(&dear), &image(&rt), W, H).unwrap();
    let first_vs_rt = speculum::metrics::compare_rgba8(&image(&first), &image(&rt), W, H).unwrap();
    assert!(
        vs_rt.ssim >= first_vs_rt.ssim - 0.002,
        "{vs_rt:?} against SSR-first's {first_vs_rt:?}"
    );
    assert_eq!(ctx.validation_messages(), 0);
}

/// With a fixed rate the adaptive hybrid is deterministic: two runs give the same
/// bytes at every frame, and a frame measured again (a failed timer readout) reads the
/// same tiles; the first frame, with no history, is the SSR-first frame. Provenance
/// paints the rays-only tiles' traced pixels orange.
#[test]
fn a_fixed_rate_is_deterministic_and_the_first_frame_is_ssr_first() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let run = |policy, frames| {
        let mut r = Renderer::new(&ctx, &scene, &settings(policy, 0.9)).unwrap();
        (0..frames)
            .map(|_| {
                r.render_frame().unwrap();
                r.read_output().unwrap()
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(HybridPolicy::Adaptive, 8), run(HybridPolicy::Adaptive, 8));
    assert!(a == b, "two runs differ");
    let first = run(HybridPolicy::SsrFirst, 1);
    assert!(a[0] == first[0], "the first frame is not the SSR-first frame");
    assert!(a[7] != first[0], "the tiles changed nothing");
    // Measured again: the same frame.
    let mut r = Renderer::new(&ctx, &scene, &settings(HybridPolicy::Adaptive, 0.9)).unwrap();
    for _ in 0..5 {
        r.render_frame_measured().unwrap();
    }
    let seq = r.reflections.ssr.tile_sequence();
    r.render_frame().unwrap();
    let once = tile_states(&r);
    r.reflections.ssr.restore_tiles(seq);
    r.render_frame().unwrap();
    assert_eq!(tile_states(&r), once, "the frame again read other tiles");
    let mut p = Renderer::new(
        &ctx,
        &scene,
        &Settings {
            mode: Mode::Provenance,
            ..settings(HybridPolicy::Adaptive, 0.9)
        },
    )
    .unwrap();
    for _ in 0..8 {
        p.render_frame().unwrap();
    }
    let img = p.read_output().unwrap();
    let orange = img
        .chunks_exact(4)
        .filter(|c| c[0] > 150 && c[1] > 60 && c[1] < 160 && c[2] < 60)
        .count();
    assert!(orange > 2000, "{orange} orange pixels");
    assert_eq!(ctx.validation_messages(), 0);
}

/// Which pixels a frame probes does not show: with a fixed rate, glossy off and a
/// still view, two frames on one split of the tiles are byte-identical, though each
/// probes other pixels of its rays-only tiles (a rotating sixteenth: a probe ends as
/// the tile's other pixels, traced or left untraced for its 2x2 block). Before, a
/// weak reflector's probe off its block's traced corner was traced, where its
/// neighbours took the corner's colour: `room`'s blue sphere sparkled, up to 154 of
/// 255 a channel, one frame to the next.
#[test]
fn probes_do_not_show_in_the_frame() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let st = Settings {
        glossy: false,
        ..settings(HybridPolicy::Adaptive, 0.9)
    };
    let mut r = Renderer::new(&ctx, &scene, &st).unwrap();
    let class = |r: &Renderer| -> Vec<u32> { tile_states(r).iter().map(|s| s & TILE_RAYS_ONLY).collect() };
    let mut frames = Vec::new();
    for _ in 0..10 {
        r.render_frame().unwrap();
        frames.push((r.read_output().unwrap(), class(&r)));
    }
    // A frame's classification writes the classes it runs on: where frames k - 1 and k
    // ran on one split, with rays-only tiles in it, they are the same image.
    let mut same_split = 0;
    for k in 1..frames.len() {
        if frames[k].1 != frames[k - 1].1 {
            continue;
        }
        let rays_only = frames[k].1.iter().filter(|&&c| c != 0).count();
        assert!(rays_only > 100, "frame {k}: {rays_only} rays-only tiles");
        assert!(frames[k].0 == frames[k - 1].0, "frame {k} differs from frame {}", k - 1);
        same_split += 1;
    }
    assert!(same_split >= 5, "{same_split} pairs of frames on one split");
    assert_eq!(ctx.validation_messages(), 0);
}

/// While the frames take an idle path, a probe frame marches with the tiles to measure
/// them and ends every marched pixel as the idle path does (traced, or on `SkipMarch`
/// left untraced for its block): with glossy off on a still view it is the idle frame
/// before it, byte for byte, on both idle paths, though SSR-first tiles marched in it.
/// Before, it showed SSR's answers there: a pulse at every probe frame (`room` at
/// 960x540, about 100,000 pixels changed, 105 of them by 32 of 255 or more).
#[test]
fn a_probe_frame_while_idle_shows_the_idle_path() {
    use speculum::renderer::exchange::Path;
    use speculum::renderer::PROBE_EVERY;
    // The paths are priced by frames whose timings pass their self-check: alone.
    let _alone = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let mut r = glossy_off(&ctx, &scene, speculum::settings::Tracer::Lbvh);
    // Each frame: the path it shows (the paths' next before it), whether it marched,
    // its image, and the SSR-first tiles after it.
    let mut frames = Vec::new();
    for _ in 0..=2 * PROBE_EVERY {
        let shows = r.hybrid_paths().next;
        // Measured as `render` measures (a busy machine's frame rendered again).
        let marched = r.render_frame_measured().unwrap().0.get("ssr.trace").is_some();
        frames.push((
            shows,
            marched,
            r.read_output().unwrap(),
            r.tile_census().unwrap().ssr_first,
        ));
    }
    let mut compared = Vec::new();
    for k in 2..frames.len() {
        let ((before, marched_before, a, _), (shows, marched, b, ssr_first)) = (&frames[k - 1], &frames[k]);
        if *marched && !*marched_before && shows == before && *shows != Path::March {
            assert!(
                a == b,
                "frame {k}, a probe frame showing {shows:?}, differs from frame {}",
                k - 1
            );
            compared.push((*shows, *ssr_first));
        }
    }
    // Both idle paths, and SSR-first tiles marching in a probe frame (in one run beside
    // other tests, one probe frame had none: the tiles follow a rate measured on a
    // loaded machine).
    let shown = |q| compared.iter().any(|c| c.0 == q);
    assert!(
        shown(Path::TraceAll) && shown(Path::SkipMarch) && compared.iter().any(|c| c.1 > 0),
        "probe frames compared (path, SSR-first tiles): {compared:?}, rate {:?}",
        r.exchange_rate()
    );
    let p = r.hybrid_paths();
    assert!(
        p.probes >= 2 && p.frames.iter().sum::<u64>() == frames.len() as u64,
        "{p:?}"
    );
    assert_eq!(ctx.validation_messages(), 0);
}

/// While the frames march, the frame in `RECHECK_EVERY` that prices an idle path (each
/// in turn) runs it under `reflect.recheck` before the marching path, and shows the
/// marching path: byte for byte the marching frame before it on a still view with
/// glossy off, wherever the tiles kept their class. Before, it showed the idle path
/// (every pixel traced where SSR answered the frames around it): a pulse one frame in
/// 64 (11,180 of the 56,320 pixels here, with the idle path shown). Through either
/// tracer (the driver's runs its ray-tracing pipeline twice in the recheck frame).
#[test]
fn a_recheck_prices_an_idle_path_and_shows_the_march() {
    // A recheck prices its path where its timings pass their self-check: alone.
    let _alone = common::alone();
    let ctx = common::context();
    use speculum::settings::Tracer;
    // Lavapipe 25 has the driver's ray tracing; a GPU without it runs the LBVH alone.
    assert!(ctx.ray_tracing.is_some() || ctx.driver_name != "llvmpipe");
    let khr = ctx.ray_tracing.is_some().then_some(Tracer::Khr);
    for tracer in std::iter::once(Tracer::Lbvh).chain(khr) {
        // A rate measured on a loaded machine can turn every tile rays-only (a march
        // dearer than a ray): the frames then rightly stop marching and the run shows
        // nothing of the rechecks; it is run again, at most `TRIES` runs.
        const TRIES: usize = 3;
        let mut idled = Vec::new();
        while let Err(why) = recheck_while_marching(&ctx, tracer) {
            idled.push(why);
            assert!(idled.len() < TRIES, "{tracer:?}: every run went idle: {idled:?}");
        }
    }
}

/// `Err`: the frames went idle because no SSR-first tile marched (what the measured
/// rate and the frame say), not for any price; every other failure panics.
fn recheck_while_marching(
    ctx: &std::sync::Arc<speculum::vk::Context>,
    tracer: speculum::settings::Tracer,
) -> Result<(), String> {
    use speculum::renderer::exchange::{Path, Paths, RECHECK_EVERY};
    let scene = speculum::scene::builtin::room().unwrap();
    let mut r = glossy_off(ctx, &scene, tracer);
    // Marching priced far below the idle paths: the frames march, rechecks aside.
    let far = 1e9;
    r.set_hybrid_paths(Paths {
        ms: [Some(1.0), Some(far), Some(far)],
        ..Paths::default()
    });
    let mut checked = Vec::new();
    let mut before = None;
    for k in 0..2 * RECHECK_EVERY {
        // Measured as `render` measures: a frame whose timings fail their self-check
        // (a busy machine) is rendered again as the same frame, so a recheck prices.
        let (times, _) = r.render_frame_measured().unwrap();
        let recheck = k % RECHECK_EVERY == RECHECK_EVERY - 1;
        assert_eq!(times.get("reflect.recheck").is_some(), recheck, "{tracer:?} frame {k}");
        if times.get("ssr.trace").is_none() {
            let p = r.hybrid_paths();
            // Marching is priced below both idle paths (real prices against `far`'s
            // mean), so only a frame with no SSR-first tile marching turns the frames
            // idle (`Paths::marched`).
            let march = p.price(Path::March).unwrap();
            assert!(
                p.next != Path::March
                    && [Path::SkipMarch, Path::TraceAll]
                        .iter()
                        .all(|&i| p.price(i).unwrap() > march),
                "{tracer:?} frame {k} does not march: {p:?}"
            );
            return Err(format!(
                "frame {k}: rate {:?}, {:?}",
                r.exchange_rate(),
                r.tile_census().unwrap()
            ));
        }
        if recheck || (k + 1) % RECHECK_EVERY == RECHECK_EVERY - 1 {
            let frame = (r.read_output().unwrap(), tile_classes(&r));
            if recheck {
                let p = r.hybrid_paths();
                let idle = [Path::SkipMarch, Path::TraceAll][(k / RECHECK_EVERY) as usize];
                let price = p.price(idle).unwrap();
                assert!(
                    price < far && price > 0.0,
                    "{tracer:?} frame {k}: {idle:?} priced {price}"
                );
                let (compared, differ) = equal_where_tiles_held(before.as_ref().unwrap(), &frame);
                assert!(
                    differ == 0 && 2 * compared >= (W * H) as usize,
                    "{tracer:?} frame {k}, a recheck of {idle:?}: {differ} of {compared} pixels differ from the marching frame before it"
                );
                checked.push(idle);
            }
            before = Some(frame);
        }
    }
    assert_eq!(checked, [Path::SkipMarch, Path::TraceAll], "{tracer:?}");
    let p = r.hybrid_paths();
    assert_eq!((p.next, p.frames[0]), (Path::March, 2 * RECHECK_EVERY as u64), "{p:?}");
    assert_eq!(ctx.validation_messages(), 0, "{tracer:?}");
    Ok(())
}

/// Each tile's class after the last frame (known, rays-only), the rest of its state
/// (success, flips) cleared.
fn tile_classes(r: &Renderer) -> Vec<u32> {
    tile_states(r)
        .into_iter()
        .map(|s| s & (TILE_KNOWN | TILE_RAYS_ONLY))
        .collect()
}

/// Two frames' images compared where their tiles kept their class (a marching frame
/// with a measured rate may turn a tile whose success lies near it; that tile and the
/// tiles around it, which its seams' blur reaches, are left out): the pixels compared
/// and those of them that differ.
fn equal_where_tiles_held((a, ta): &(Vec<u8>, Vec<u32>), (b, tb): &(Vec<u8>, Vec<u32>)) -> (usize, usize) {
    let tiles_x = W.div_ceil(8) as i64;
    let tiles_y = H.div_ceil(8) as i64;
    let turned = |tx: i64, ty: i64| {
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let (x, y) = (tx + dx, ty + dy);
                let t = (y * tiles_x + x) as usize;
                (0..tiles_x).contains(&x) && (0..tiles_y).contains(&y) && ta[t] != tb[t]
            })
        })
    };
    let (mut compared, mut differ) = (0, 0);
    for (i, (pa, pb)) in a.chunks(4).zip(b.chunks(4)).enumerate() {
        let (x, y) = ((i % W as usize) as i64, (i / W as usize) as i64);
        if !turned(x / 8, y / 8) {
            compared += 1;
            differ += (pa != pb) as usize;
        }
    }
    (compared, differ)
}

/// While the frames take an idle path, the frame in `RECHECK_EVERY` prices the other
/// idle path under `reflect.recheck` before its own, and shows its own: byte for byte
/// the idle frame before it. Before, the idle path not taken kept the price of its
/// trial (the first frames) however the view changed.
#[test]
fn an_idle_frame_rechecks_the_other_idle_path() {
    use speculum::renderer::exchange::{Path, Paths, RECHECK_EVERY};
    // A recheck prices its path where its timings pass their self-check: alone.
    let _alone = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::builtin::spheres().unwrap();
    let mut r = glossy_off(&ctx, &scene, speculum::settings::Tracer::Lbvh);
    // `trace_all` priced far below the others, and no probe frame (they could choose
    // anew): the frames stay on `trace_all`.
    let far = 1e9;
    r.set_hybrid_paths(Paths {
        next: Path::TraceAll,
        ms: [Some(far), Some(far), Some(1.0)],
        probe_every: u32::MAX,
        ..Paths::default()
    });
    let mut frames = Vec::new();
    for k in 0..RECHECK_EVERY {
        // Measured as `render` measures (a busy machine's frame rendered again).
        let (times, _) = r.render_frame_measured().unwrap();
        let plan = r.last_plan().unwrap();
        assert_eq!(
            times.get("reflect.recheck").is_some(),
            plan.recheck.is_some(),
            "frame {k}"
        );
        assert!(times.get("ssr.trace").is_none(), "frame {k} does not march");
        if k >= RECHECK_EVERY - 2 {
            frames.push((plan, r.read_output().unwrap()));
        }
    }
    let [(before, a), (recheck, b)] = <[_; 2]>::try_from(frames).unwrap();
    assert_eq!((before.shows, before.recheck), (Path::TraceAll, None), "{before:?}");
    assert_eq!(
        (recheck.path, recheck.shows, recheck.recheck),
        (Path::TraceAll, Path::TraceAll, Some(Path::SkipMarch)),
        "{recheck:?}"
    );
    assert!(a == b, "the recheck frame differs from the idle frame before it");
    let price = r.hybrid_paths().price(Path::SkipMarch).unwrap();
    assert!(price < far && price > 0.0, "skip_march priced {price}");
    assert_eq!(ctx.validation_messages(), 0);
}

/// `exchange_rate = 0`: the renderer prices a march in rays from its hybrid frames'
/// timings and counts, and its tiles follow that price; `render`'s report gives the
/// split.
#[test]
fn the_rate_is_measured_and_reported() {
    // The rate is measured from frames whose timings pass their self-check: alone.
    let _alone = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let mut r = Renderer::new(&ctx, &scene, &settings(HybridPolicy::Adaptive, 0.0)).unwrap();
    assert_eq!(r.exchange_rate().applied, 0, "nothing measured yet: SSR-first");
    for _ in 0..4 {
        r.render_frame().unwrap();
    }
    let rate = r.exchange_rate();
    let e = rate.estimate.expect("measured");
    assert!(e > 0.01 && e < 100.0 && rate.applied > 0, "{rate:?}");
    // The frames use it: every known tile whose success lies more than the hysteresis
    // below the rate the last frame used is rays-only, and there are such tiles.
    for _ in 0..6 {
        r.render_frame().unwrap();
    }
    // The next marching frame (a probe frame at the latest: the others may take an
    // idle path, which leaves the tiles) updates them with the rate in use before it.
    let mut used = None;
    for _ in 0..speculum::renderer::exchange::PROBE_EVERY_MAX {
        let rate = r.exchange_rate().applied;
        if r.render_frame().unwrap().get("ssr.trace").is_some() {
            used = Some(rate);
            break;
        }
    }
    let used = used.expect("a probe frame marches");
    let below: Vec<u32> = (tile_states(&r).into_iter())
        .filter(|&s| s & TILE_KNOWN != 0 && (s & TILE_SUCCESS) + tile_hysteresis(used) < used)
        .collect();
    assert!(below.len() > 20, "{} tiles below the rate {used}", below.len());
    assert!(below.iter().all(|&s| s & TILE_RAYS_ONLY != 0));
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("t.json");
    std::fs::write(dir.path().join("s.json"), r#"{"hybrid_policy": "adaptive"}"#).unwrap();
    let out = common::speculum([
        "render", "--width", "96", "--height", "56", "--frames", "3", "--warmup", "1", "--quiet",
    ])
    .arg("--settings")
    .arg(dir.path().join("s.json"))
    .arg("--timings")
    .arg(&json)
    .arg("--out")
    .arg(dir.path().join("f.png"))
    .run();
    assert!(out.ok(), "{}", out.stderr);
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let h = &report["hybrid"];
    assert_eq!(h["policy"], "adaptive");
    let tiles: u64 = ["ssr_first_tiles", "rays_only_tiles", "unknown_tiles"]
        .iter()
        .map(|k| h[k].as_u64().unwrap())
        .sum();
    assert_eq!(tiles, 12 * 7);
    assert!(h["exchange_rate_measured"].as_f64().is_some_and(|m| m > 0.0), "{h}");
    assert_eq!(ctx.validation_messages(), 0);
}

/// A march dearer than any answer pays for (rate 1.5): once every tile is known
/// rays-only, the frames between probe frames (each `PROBE_EVERY` frames after the
/// last that marched) skip the pyramid
/// and the march (`Path::SkipMarch`): every reflective pixel is skipped or fails on its
/// heading, none answered by SSR, at the quality of the `rt` mode; probe frames march
/// again, so the tiles can come back.
#[test]
fn with_no_ssr_first_tile_the_march_stops_between_probe_frames() {
    use speculum::renderer::PROBE_EVERY;
    let ctx = common::context();
    let (mut r, mut rt) = adaptive_and_rt(&ctx, 1.5);
    let (mut idle, mut probes, mut last_marched) = (0, 0, 0);
    for k in 0..2 * PROBE_EVERY + 3 {
        let times = r.render_frame().unwrap();
        rt.render_frame().unwrap();
        let marched = times.get("ssr.trace").is_some();
        assert_eq!(marched, times.get("ssr.hiz").is_some(), "frame {k}");
        if k >= 2 && !marched {
            idle += 1;
            let (a, b) = (r.read_output().unwrap(), rt.read_output().unwrap());
            let c = speculum::metrics::compare_rgba8(&a, &b, W, H).unwrap();
            assert!(c.ssim >= 0.995, "frame {k}: {c:?}");
            let maps = r.reflection_maps().unwrap();
            let skipped = FAIL_SKIPPED | speculum::shader_defines::FAIL_LOW_CONFIDENCE;
            let (reflective, unmarched) = maps
                .reflective
                .iter()
                .zip(&maps.mask)
                .fold((0, 0), |(n, u), (&rf, &m)| {
                    (n + rf as usize, u + (rf && m & skipped != 0) as usize)
                });
            assert!(
                reflective > 1000 && unmarched == reflective,
                "frame {k}: {unmarched} of {reflective}"
            );
        }
        if k >= 2 {
            let due = k - last_marched == PROBE_EVERY;
            assert_eq!(
                marched, due,
                "frame {k}: a probe frame comes {PROBE_EVERY} frames after the last that marched ({last_marched})"
            );
            probes += due as usize;
        }
        if marched {
            last_marched = k;
        }
    }
    assert!(
        idle >= 2 * PROBE_EVERY as usize - 2 && probes == 2,
        "{idle} idle frames, {probes} probe frames"
    );
    assert_eq!(ctx.validation_messages(), 0);
}

/// With a measured rate the paths are priced: after the first frame the `rt` mode's
/// path (`TraceAll`, its image) is tried until the next probe frame, then `SkipMarch`
/// until the one after; every path then has a price, and the frames take the cheapest,
/// or keep `SkipMarch` while it undercuts that by no more than `PATH_HOLD`
/// (`Paths::marched`'s choice, here on the renderer's own timings).
#[test]
fn measured_paths_are_tried_and_the_cheapest_taken() {
    use speculum::renderer::exchange::{Path, PATH_HOLD};
    use speculum::renderer::PROBE_EVERY;
    // The paths are priced by frames whose timings pass their self-check: alone.
    let _alone = common::alone();
    let ctx = common::context();
    let (mut r, mut rt) = adaptive_and_rt(&ctx, 0.0);
    for k in 0..=2 * PROBE_EVERY {
        // Measured as `render` measures (a busy machine's frame rendered again).
        let (times, _) = r.render_frame_measured().unwrap();
        rt.render_frame().unwrap();
        let marched = times.get("ssr.trace").is_some();
        assert_eq!(
            marched,
            k % PROBE_EVERY == 0,
            "frame {k}: probe frames march, the others not"
        );
        if (2..PROBE_EVERY).contains(&k) {
            let (a, b) = (r.read_output().unwrap(), rt.read_output().unwrap());
            let c = speculum::metrics::compare_rgba8(&a, &b, W, H).unwrap();
            assert!(c.ssim >= 0.999, "frame {k}: TraceAll is the rt mode's path: {c:?}");
        }
    }
    let p = r.hybrid_paths();
    // Frame 0 marches; the probe frames 7 and 14 march to measure and show the idle
    // path of the frames before them.
    assert_eq!(
        (p.frames, p.probes),
        ([1, PROBE_EVERY as u64, PROBE_EVERY as u64], 2),
        "{p:?}"
    );
    let prices: Vec<f64> = Path::ALL.iter().map(|&q| p.price(q).expect("priced")).collect();
    // Marching is a choice only while an SSR-first tile marches.
    let marching = r.tile_census().unwrap().ssr_first > 0;
    let cheapest = Path::ALL
        .into_iter()
        .filter(|&q| marching || q != Path::March)
        .min_by(|&a, &b| prices[a as usize].total_cmp(&prices[b as usize]))
        .expect("idle paths");
    // The frames before the last probe frame tried `SkipMarch`.
    let held = prices[cheapest as usize] >= (1.0 - PATH_HOLD) * prices[Path::SkipMarch as usize];
    let chosen = if held { Path::SkipMarch } else { cheapest };
    assert_eq!(p.next, chosen, "{p:?}");
    assert_eq!(ctx.validation_messages(), 0);
}
