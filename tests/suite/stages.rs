//! The frame's adaptive stages (`renderer::stages`) on a renderer: `visibility` and
//! `shadows = adaptive` try each of their ways over their first frames, each frame
//! records its way's rows and no other, and once every way is priced the frames take
//! the cheapest (within `HOLD` of the one in use). The pricing itself, frame by frame
//! against made-up times: the unit tests in `src/renderer/stages.rs`.

use crate::common;

use speculum::renderer::stages::{Stage, HOLD, SAMPLES};
use speculum::settings::{Mode, Shadows, Visibility};
use speculum::{Renderer, Settings};

/// The cheapest way is the one taken, or the one in use is within `HOLD` of it.
fn takes_the_cheapest<const N: usize>(stage: &Stage<N>, what: &str) {
    let prices: Vec<f64> = (0..N).map(|w| stage.price(w).expect("priced")).collect();
    let cheapest = prices.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        prices[stage.chosen] * (1.0 - HOLD) <= cheapest,
        "{what}: {prices:?}, chosen {}",
        stage.chosen
    );
}

#[test]
fn adaptive_stages_try_each_way_then_take_the_cheapest() {
    // A stage is priced by frames whose timings pass their self-check: alone, and
    // frames large enough for lavapipe's timestamps (small traced frames leave more
    // time between their scopes than the check allows: docs/experiments.md).
    let _alone = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    let settings = Settings {
        width: 640,
        height: 360,
        mode: Mode::Hybrid,
        visibility: Visibility::Adaptive,
        shadows: Shadows::Adaptive,
        exchange_rate: 0.5,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
    let mut frames = 0;
    while !(r.stages().visibility.priced() && r.stages().shadows.priced()) {
        assert!(frames < 40, "not priced in 40 frames: {:?}", r.stages());
        let before = r.stages();
        let visibility = Visibility::FIXED[before.visibility.frame_way(r.frame_index())];
        let shadows = Shadows::ADAPTIVE[before.shadows.frame_way(r.frame_index())];
        let times = r.render_frame().unwrap();
        frames += 1;
        // The frame's rows are its ways'.
        let ran = |scope: &str| times.get(scope).is_some();
        assert_eq!(
            (ran("gbuffer"), ran("gbuffer.trace")),
            (visibility == Visibility::Raster, visibility == Visibility::Rays),
            "frame {frames}"
        );
        assert_eq!(ran("shadow.map"), shadows == Shadows::Hybrid, "frame {frames}");
        assert!(ran("shadow.trace"), "both ways trace");
        let stats = r.shadow_maps().unwrap().stats();
        assert!(stats.lit_pixels > 1000, "{stats:?}");
        match shadows {
            Shadows::Rays => assert_eq!(stats.traced_pixels, stats.lit_pixels, "frame {frames}"),
            _ => assert!(stats.traced_pixels < stats.lit_pixels, "frame {frames}: {stats:?}"),
        }
    }
    let stages = r.stages();
    for (what, frames) in [
        ("visibility", stages.visibility.frames),
        ("shadows", stages.shadows.frames),
    ] {
        assert!(frames.iter().all(|&n| n >= SAMPLES as u64), "{what}: {frames:?}");
    }
    takes_the_cheapest(&stages.visibility, "visibility");
    takes_the_cheapest(&stages.shadows, "shadows");
    // A change of settings prices anew; a fixed setting counts nothing.
    r.set_settings(Settings {
        visibility: Visibility::Rays,
        ..settings
    })
    .unwrap();
    r.render_frame().unwrap();
    let after = r.stages();
    assert_eq!(after.visibility.frames, [0, 0]);
    assert_eq!(after.shadows.frames.iter().sum::<u64>(), 1);
    assert_eq!(ctx.validation_messages(), 0);
}

/// A steady warm-up prices the adaptive stages again once the clocks have settled (the
/// first frames priced them cold): every way's frames counted afresh, every stage
/// priced before the measured frames. A fixed count renders exactly its frames, and a
/// renderer without an adaptive stage prices nothing.
#[test]
fn a_steady_warm_up_prices_the_stages_at_settled_clocks() {
    use speculum::steady::WarmUp;
    let _alone = common::alone();
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    // Large enough for lavapipe's timestamps to pass their self-check (above).
    let settings = |visibility| Settings {
        width: 640,
        height: 360,
        visibility,
        exchange_rate: 0.5,
        ..Default::default()
    };
    let mut adaptive = Renderer::new(&ctx, &scene, &settings(Visibility::Adaptive)).unwrap();
    let mut fixed = Renderer::new(&ctx, &scene, &settings(Visibility::Raster)).unwrap();
    let report =
        speculum::headless::warm_up(&mut [&mut adaptive, &mut fixed], WarmUp::from_arg(None), &mut || {}).unwrap();
    let frames = adaptive.stages().visibility.frames;
    assert!(adaptive.stages_priced(), "{report:?}");
    assert_eq!(
        frames.iter().sum::<u64>(),
        report.pricing_rounds as u64,
        "the ways' frames are the pricing rounds' (counted afresh): {report:?}"
    );
    assert!(frames.iter().all(|&n| n >= SAMPLES as u64), "{frames:?}");
    let alone = speculum::headless::warm_up(&mut [&mut fixed], WarmUp::from_arg(None), &mut || {}).unwrap();
    assert_eq!(alone.pricing_rounds, 0);
    let counted = speculum::headless::warm_up(&mut [&mut adaptive], WarmUp::Frames(2), &mut || {}).unwrap();
    assert_eq!((counted.frames, counted.pricing_rounds), (2, 0));
    assert_eq!(ctx.validation_messages(), 0);
}
