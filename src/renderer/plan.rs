//! The frame's decisions, made once before anything is recorded (`FramePlan`): from
//! the settings, the mode, the adaptive hybrid's path and measured rate, and the
//! scene's kinds of motion, which rows of the frame table run and with what — the
//! classification, the tile rate, the blur, which step keeps the previous vertices.
//! `Renderer::record_frame` reads it as a table; nothing here touches the GPU, so
//! every decision is unit-tested on the CPU.

use super::exchange::{FramePath, Path};
use super::table::Row;
use crate::passes::compose::ComposeMode;
use crate::passes::reflect_merge::BlurParams;
use crate::passes::ssr_trace::Classify;
use crate::settings::{Hybrid, Mode, Settings, Shadows, SsrParams, Visibility};

/// What moves in the scene, as the frame steps it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Motion {
    /// The scene has dynamic geometry (rigid bodies, cloth or an animated model).
    pub dynamic: bool,
    /// Rigid bodies with triangles (`sim.transform` poses them).
    pub rigid: bool,
    pub cloth: bool,
    /// An animated model (`sim.skin`).
    pub skin: bool,
    /// The frame steps the simulation (not paused, or a single step asked for).
    pub advance: bool,
    /// The vendor tracer: its structures (`as.*`) move with the scene, not the BVH's.
    pub vendor: bool,
}

/// Who copies the dynamic vertices to their previous-frame buffer (the motion vectors'
/// origin) before they change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Previous {
    /// Nothing moves (a static scene).
    None,
    /// A paused frame: the copy alone, so the motion is zero.
    Held,
    /// The first step that writes the vertices, inside its row.
    By(Row),
}

/// The frame's decisions (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePlan {
    pub motion: Motion,
    pub previous: Previous,
    pub hybrid: Hybrid,
    /// The adaptive hybrid's path this frame (`Path::March` for every other frame), and
    /// the path its image is (`shows`: another only on a probe frame while idle, which
    /// marches to measure and ends every marched pixel as on the idle path).
    pub path: Path,
    pub shows: Path,
    /// The adaptive hybrid's recheck: the idle path the frame also runs, to price it,
    /// before its own (`recheck_plan`; `Row::ReflectRecheck`).
    pub recheck: Option<Path>,
    /// SSR marches this frame.
    pub marches: bool,
    /// The classification of the pixels a march could answer (`None`: no reflections).
    pub classify: Option<Classify>,
    /// The tiles' exchange rate for the classification (0: every tile SSR-first).
    pub tile_rate: u32,
    /// The march's and the rays' counts are recorded to price a march in rays.
    pub counts: bool,
    pub blur: BlurParams,
    pub denoise: bool,
    pub compose: ComposeMode,
    /// How the G-buffer is made this frame.
    pub visibility: Visibility,
    /// Where this frame's shadows come from (never `Adaptive`: its way).
    pub shadows: Shadows,
    shadow_map: bool,
    shadow_rays: bool,
    hiz: bool,
    traces: bool,
}

/// The ways the adaptive stages chose for a frame: the hybrid's path and the one it
/// shows (read where
/// `Hybrid::of(st)` is adaptive), the G-buffer's (read where `visibility` is adaptive;
/// raster or rays) and the shadows' (read where `shadows` is adaptive; one of
/// `Shadows::ADAPTIVE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ways {
    pub path: FramePath,
    pub visibility: Visibility,
    pub shadows: Shadows,
}

impl FramePlan {
    /// The plan of a frame of `st` with the scene's `motion`, the adaptive stages'
    /// `ways`, the exchange rate the frames have measured (`applied`, `TILE_ONE`
    /// units), and whether the fail mask is shown instead of the reflections.
    pub fn new(st: &Settings, motion: Motion, ways: Ways, applied: u32, fail_mask_view: bool) -> Self {
        let mode = st.mode;
        let path = ways.path;
        let visibility = match st.visibility {
            Visibility::Adaptive => ways.visibility,
            fixed => fixed,
        };
        assert_ne!(
            visibility,
            Visibility::Adaptive,
            "an adaptive frame's way is raster or rays"
        );
        let shadows = match st.shadows {
            Shadows::Adaptive => ways.shadows,
            fixed => fixed,
        };
        assert!(
            shadows != Shadows::Adaptive,
            "an adaptive frame's shadows are one source"
        );
        let hybrid = Hybrid::of(st);
        let FramePath {
            runs: path,
            shows,
            rechecks,
        } = if hybrid.adaptive() {
            path
        } else {
            FramePath::plain(Path::March)
        };
        let idle = path != Path::March;
        let marches = mode.marches() && !idle;
        let classify = mode.reflects().then_some(match (marches, path) {
            (true, _) => Classify::Tiles,
            (false, Path::SkipMarch) => Classify::SkipAll,
            (false, _) => Classify::MaskOnly,
        });
        let tile_rate = match hybrid {
            Hybrid::None => 0,
            Hybrid::Fixed(rate) => rate,
            Hybrid::Measured => applied,
        };
        let previous = match motion {
            Motion { dynamic: false, .. } => Previous::None,
            Motion { advance: false, .. } => Previous::Held,
            Motion { rigid: true, .. } => Previous::By(Row::SimTransform),
            Motion { cloth: true, .. } => Previous::By(Row::SimCloth),
            Motion { skin: true, .. } => Previous::By(Row::SimSkin),
            // Bodies without triangles (colliders alone): nothing to copy.
            _ => Previous::None,
        };
        Self {
            motion,
            previous,
            hybrid,
            path,
            shows,
            recheck: rechecks.filter(|_| mode.traces()),
            marches,
            classify,
            tile_rate,
            counts: marches && mode.traces(),
            // Seams exist only where both sources do (not on the adaptive hybrid's idle
            // paths, nor on a probe frame that shows one: SSR answers nothing there).
            blur: BlurParams {
                radius: if mode.has_seams() && shows == Path::March {
                    st.blur_radius
                } else {
                    0
                },
                band: st.blur_band,
            },
            denoise: mode.reflects() && st.glossy && (st.denoise_radius > 0 || st.denoise_history > 1),
            compose: match mode {
                Mode::Raster => ComposeMode::Plain,
                _ if fail_mask_view => ComposeMode::FailMask,
                Mode::Provenance => ComposeMode::Provenance,
                Mode::Ssr | Mode::Hybrid | Mode::Rt => ComposeMode::Reflect,
            },
            visibility,
            shadows,
            shadow_map: shadows.uses_map(),
            shadow_rays: shadows.traces(),
            hiz: marches && st.ssr_hiz,
            traces: mode.traces(),
        }
    }

    /// The adaptive hybrid's path as the frame runs, shows and rechecks it.
    pub fn frame_path(&self) -> FramePath {
        FramePath {
            runs: self.path,
            shows: self.shows,
            rechecks: self.recheck,
        }
    }

    /// A probe frame while idle: it marches with the tiles to measure them and ends
    /// every marched pixel as the idle path `shows` does.
    pub fn measures_only(&self) -> bool {
        self.path != self.shows
    }

    /// The plan of the frame's recheck (`None`: no recheck): the idle path's
    /// classification, rays and merge, as an idle frame records them (no pyramid, no
    /// march, no seams), whose outputs the frame's own path then writes again.
    pub fn recheck_plan(&self) -> Option<FramePlan> {
        let idle = self.recheck?;
        Some(FramePlan {
            path: idle,
            shows: idle,
            recheck: None,
            marches: false,
            hiz: false,
            counts: false,
            classify: Some(match idle {
                Path::SkipMarch => Classify::SkipAll,
                _ => Classify::MaskOnly,
            }),
            blur: BlurParams { radius: 0, ..self.blur },
            ..*self
        })
    }

    /// The frame's SSR parameters: the settings', the tiles' rate, and on a probe frame
    /// that only measures, its end of every marched pixel (`trace_min_weight` 0 where
    /// it shows the `rt` mode's path, which traces every reflective pixel).
    pub fn ssr_params(&self, st: &Settings) -> SsrParams {
        let from_settings = SsrParams::from_settings(st);
        let all_traced = self.measures_only() && self.shows == Path::TraceAll;
        SsrParams {
            tile_rate: self.tile_rate,
            measure_only: self.measures_only(),
            trace_min_weight: if all_traced {
                0.0
            } else {
                from_settings.trace_min_weight
            },
            ..from_settings
        }
    }

    /// Whether the frame records `row`.
    pub fn runs(&self, row: Row) -> bool {
        let m = self.motion;
        let steps = m.dynamic && m.advance;
        match row {
            Row::Uniforms | Row::LightDirect | Row::Compose => true,
            Row::GBuffer => self.visibility == Visibility::Raster,
            Row::GBufferTrace => self.visibility == Visibility::Rays,
            Row::SimRigid => steps,
            Row::SimTransform => steps && m.rigid,
            Row::SimCloth => steps && m.cloth,
            Row::SimSkin => steps && m.skin,
            Row::DynamicBvh => steps && !m.vendor,
            Row::DynamicAccel => steps && m.vendor,
            Row::ShadowMap => self.shadow_map,
            Row::ShadowClassify | Row::ShadowCompact | Row::ShadowTrace => self.shadow_rays,
            Row::ReflectRecheck => self.recheck.is_some(),
            Row::SsrHiz => self.hiz,
            Row::SsrClassify | Row::ReflectMerge => self.classify.is_some(),
            Row::SsrTrace => self.marches,
            Row::SsrCompact | Row::RtReflect => self.traces,
            Row::ReflectDenoise => self.denoise,
        }
    }

    /// The rows the frame records, in table order.
    pub fn rows(&self) -> Vec<Row> {
        Row::ALL.iter().copied().filter(|&r| self.runs(r)).collect()
    }

    /// Whether the shadow rays trace (`light.direct` reads their visibility).
    pub fn shadow_rays(&self) -> bool {
        self.shadow_rays
    }

    /// Whether `row` is the step that keeps the previous vertices.
    pub fn keeps_previous(&self, row: Row) -> bool {
        self.previous == Previous::By(row)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::HybridPolicy;
    use crate::shader_defines::TILE_ONE;
    use Row::*;

    /// Ways no fixed setting reads.
    fn ways(path: Path) -> Ways {
        Ways {
            path: FramePath::plain(path),
            visibility: Visibility::Raster,
            shadows: Shadows::Hybrid,
        }
    }

    fn plan(st: &Settings, motion: Motion, path: Path) -> FramePlan {
        FramePlan::new(st, motion, ways(path), 37, false)
    }

    fn settings(mode: Mode) -> Settings {
        Settings {
            mode,
            ..Default::default()
        }
    }

    const STILL: Motion = Motion {
        dynamic: false,
        rigid: false,
        cloth: false,
        skin: false,
        advance: true,
        vendor: false,
    };

    /// Each mode's rows on a static scene with the default (map) shadows.
    #[test]
    fn each_mode_runs_its_rows() {
        let base = [Uniforms, ShadowMap, GBuffer, LightDirect];
        let want: [(Mode, &[Row]); 5] = [
            (Mode::Raster, &[]),
            (Mode::Ssr, &[SsrHiz, SsrClassify, SsrTrace, ReflectMerge]),
            (
                Mode::Hybrid,
                &[SsrHiz, SsrClassify, SsrTrace, SsrCompact, RtReflect, ReflectMerge],
            ),
            (Mode::Rt, &[SsrClassify, SsrCompact, RtReflect, ReflectMerge]),
            (
                Mode::Provenance,
                &[SsrHiz, SsrClassify, SsrTrace, SsrCompact, RtReflect, ReflectMerge],
            ),
        ];
        for (mode, rows) in want {
            let st = Settings {
                glossy: false,
                shadows: Shadows::Map,
                ..settings(mode)
            };
            let mut all: Vec<Row> = base.iter().chain(rows).copied().collect();
            all.push(Compose);
            all.sort_by_key(|&r| r as usize);
            assert_eq!(plan(&st, STILL, Path::March).rows(), all, "{mode:?}");
        }
    }

    /// The adaptive hybrid's paths: marching classifies tiles; skipping the march
    /// classifies every pixel as skipped and blurs nothing; tracing all masks every
    /// pixel. The rate is the measured one, or the fixed one, and 0 where nothing adapts.
    #[test]
    fn the_hybrids_paths_and_rates() {
        let st = settings(Mode::Hybrid);
        assert_eq!(Hybrid::of(&st), Hybrid::Measured);
        let march = plan(&st, STILL, Path::March);
        assert_eq!(
            (march.classify, march.tile_rate, march.counts),
            (Some(Classify::Tiles), 37, true)
        );
        assert_eq!(march.blur.radius, st.blur_radius);
        let params = march.ssr_params(&st);
        assert!(!params.measure_only && params.trace_min_weight == st.trace_min_weight && params.tile_rate == 37);
        let skip = plan(&st, STILL, Path::SkipMarch);
        assert_eq!(
            (skip.classify, skip.marches, skip.counts),
            (Some(Classify::SkipAll), false, false)
        );
        assert_eq!(skip.blur.radius, 0, "no seams on an idle path");
        assert!(!skip.runs(SsrHiz) && !skip.runs(SsrTrace) && skip.runs(RtReflect));
        let all = plan(&st, STILL, Path::TraceAll);
        assert_eq!(all.classify, Some(Classify::MaskOnly));
        // A probe frame while idle: the marching path's rows and counts, no seams.
        for idle in [Path::SkipMarch, Path::TraceAll] {
            let runs = FramePath::probe(idle);
            let probe = FramePlan::new(
                &st,
                STILL,
                Ways {
                    path: runs,
                    ..ways(idle)
                },
                37,
                false,
            );
            assert_eq!(probe.rows(), march.rows(), "{idle:?}");
            assert_eq!(
                (probe.classify, probe.counts, probe.shows),
                (march.classify, true, idle)
            );
            assert!(probe.measures_only() && !march.measures_only());
            assert_eq!(probe.blur.radius, 0, "{idle:?}: no seams shown");
            let params = probe.ssr_params(&st);
            let weight = if idle == Path::TraceAll {
                0.0
            } else {
                st.trace_min_weight
            };
            assert_eq!(
                (params.measure_only, params.trace_min_weight, params.tile_rate),
                (true, weight, 37)
            );
        }
        // A recheck: the frame's own rows after `reflect.recheck`, whose plan is the
        // idle path's (its classification, no march, no seams, no counts).
        for (runs, idle) in [(Path::March, Path::SkipMarch), (Path::SkipMarch, Path::TraceAll)] {
            let ways = Ways {
                path: FramePath::recheck(runs, idle),
                ..ways(runs)
            };
            let frame = FramePlan::new(&st, STILL, ways, 37, false);
            let own = plan(&st, STILL, runs);
            let mut rows = own.rows();
            rows.insert(
                rows.iter().position(|&r| r == SsrHiz || r == SsrClassify).unwrap(),
                ReflectRecheck,
            );
            assert_eq!(frame.rows(), rows, "{runs:?} rechecking {idle:?}");
            assert_eq!(frame.frame_path(), FramePath::recheck(runs, idle));
            let r = frame.recheck_plan().unwrap();
            let want = plan(&st, STILL, idle);
            assert_eq!(
                (r.classify, r.marches, r.counts, r.blur.radius, r.rows()),
                (want.classify, false, false, 0, want.rows())
            );
            assert_eq!(own.recheck_plan(), None);
        }
        let fixed = Settings {
            exchange_rate: 0.5,
            ..st.clone()
        };
        assert_eq!(Hybrid::of(&fixed), Hybrid::Fixed(TILE_ONE / 2));
        assert_eq!(plan(&fixed, STILL, Path::March).tile_rate, TILE_ONE / 2);
        let first = Settings {
            hybrid_policy: HybridPolicy::SsrFirst,
            ..st.clone()
        };
        // Not adaptive: the path asked for is ignored, every tile marches first.
        let p = plan(&first, STILL, Path::SkipMarch);
        assert_eq!(
            (p.path, p.tile_rate, p.classify),
            (Path::March, 0, Some(Classify::Tiles))
        );
        for mode in [Mode::Ssr, Mode::Rt, Mode::Raster] {
            assert_eq!(Hybrid::of(&settings(mode)), Hybrid::None, "{mode:?}");
            assert_eq!(plan(&settings(mode), STILL, Path::TraceAll).tile_rate, 0);
        }
        assert_eq!(Hybrid::of_policy(&settings(Mode::Rt)), Hybrid::Measured);
    }

    /// The first step that writes the vertices keeps the previous ones; a paused frame
    /// only copies them; the tracer decides which structure moves.
    #[test]
    fn motion_rows_and_who_keeps_the_previous_vertices() {
        let st = settings(Mode::Hybrid);
        let moving = Motion {
            dynamic: true,
            rigid: true,
            cloth: true,
            skin: true,
            ..STILL
        };
        let p = plan(&st, moving, Path::March);
        assert_eq!(p.previous, Previous::By(SimTransform));
        assert!(p.keeps_previous(SimTransform) && !p.keeps_previous(SimCloth));
        let steps: Vec<Row> = p
            .rows()
            .into_iter()
            .filter(|r| (*r as usize) < ShadowMap as usize)
            .collect();
        assert_eq!(steps, [Uniforms, SimRigid, SimTransform, SimCloth, SimSkin, DynamicBvh]);
        let cloth_skin = Motion { rigid: false, ..moving };
        assert_eq!(plan(&st, cloth_skin, Path::March).previous, Previous::By(SimCloth));
        let skin = Motion {
            cloth: false,
            ..cloth_skin
        };
        assert_eq!(plan(&st, skin, Path::March).previous, Previous::By(SimSkin));
        let colliders = Motion { skin: false, ..skin };
        assert_eq!(plan(&st, colliders, Path::March).previous, Previous::None);
        let vendor = plan(&st, Motion { vendor: true, ..moving }, Path::March);
        assert!(vendor.runs(DynamicAccel) && !vendor.runs(DynamicBvh));
        let paused = plan(
            &st,
            Motion {
                advance: false,
                ..moving
            },
            Path::March,
        );
        assert_eq!(paused.previous, Previous::Held);
        assert!(!paused.runs(SimRigid) && !paused.runs(SimTransform) && !paused.runs(DynamicBvh));
        assert_eq!(plan(&st, STILL, Path::March).previous, Previous::None);
    }

    /// Visibility by rays swaps the raster G-buffer's row for the traced one in every
    /// mode and on a moving scene; every other row stays as it was.
    #[test]
    fn visibility_swaps_one_row() {
        let moving = Motion {
            dynamic: true,
            cloth: true,
            ..STILL
        };
        for mode in Mode::ALL {
            for motion in [STILL, moving] {
                let raster = plan(&settings(mode), motion, Path::March).rows();
                let st = Settings {
                    visibility: Visibility::Rays,
                    ..settings(mode)
                };
                let rays = plan(&st, motion, Path::March).rows();
                let swapped: Vec<Row> = raster
                    .iter()
                    .map(|&r| if r == GBuffer { GBufferTrace } else { r })
                    .collect();
                assert!(raster.contains(&GBuffer) && !raster.contains(&GBufferTrace), "{mode:?}");
                assert_eq!(rays, swapped, "{mode:?}");
                // Adaptive: the frame's way; a fixed setting ignores it.
                let ways = Ways {
                    visibility: Visibility::Rays,
                    ..ways(Path::March)
                };
                let adaptive = FramePlan::new(&settings(mode), motion, ways, 37, false);
                assert_eq!(settings(mode).visibility, Visibility::Adaptive);
                assert_eq!(adaptive.rows(), swapped, "{mode:?}");
                let fixed = Settings {
                    visibility: Visibility::Raster,
                    ..settings(mode)
                };
                assert_eq!(FramePlan::new(&fixed, motion, ways, 37, false).rows(), raster);
            }
        }
    }

    /// Shadows by rays add their three rows; the glossy filter runs with a radius or a
    /// history; the fail-mask view replaces the reflections in the composite.
    #[test]
    fn shadows_denoise_and_compose() {
        let rays = Settings {
            shadows: Shadows::Rays,
            ..settings(Mode::Rt)
        };
        let p = plan(&rays, STILL, Path::March);
        assert!(p.shadow_rays() && !p.runs(ShadowMap));
        assert!(p.runs(ShadowClassify) && p.runs(ShadowCompact) && p.runs(ShadowTrace));
        // Adaptive shadows: the frame's way, its rows, and the kernels' value.
        let adaptive = Settings {
            shadows: Shadows::Adaptive,
            ..settings(Mode::Rt)
        };
        for way in Shadows::ADAPTIVE {
            let fixed = Settings {
                shadows: way,
                ..settings(Mode::Rt)
            };
            let p = FramePlan::new(
                &adaptive,
                STILL,
                Ways {
                    shadows: way,
                    ..ways(Path::March)
                },
                37,
                false,
            );
            assert_eq!(p.rows(), plan(&fixed, STILL, Path::March).rows(), "{way:?}");
            assert_eq!((p.shadows, p.runs(ShadowMap)), (way, way == Shadows::Hybrid));
        }
        assert_eq!(p.shadows, Shadows::Rays, "a fixed source ignores the way");
        let glossy = Settings {
            glossy: true,
            denoise_radius: 0,
            denoise_history: 1,
            ..settings(Mode::Hybrid)
        };
        assert!(!plan(&glossy, STILL, Path::March).denoise);
        let history = Settings {
            denoise_history: 4,
            ..glossy.clone()
        };
        assert!(plan(&history, STILL, Path::March).runs(ReflectDenoise));
        assert!(!plan(&settings(Mode::Raster), STILL, Path::March).denoise);
        assert_eq!(
            plan(&settings(Mode::Raster), STILL, Path::March).compose,
            ComposeMode::Plain
        );
        let view = FramePlan::new(&settings(Mode::Hybrid), STILL, ways(Path::March), 0, true);
        assert_eq!(view.compose, ComposeMode::FailMask);
        assert_eq!(
            plan(&settings(Mode::Provenance), STILL, Path::March).compose,
            ComposeMode::Provenance
        );
    }
}
