//! ssr.classify against its CPU reference on a random G-buffer, ssr.trace's coverage of
//! the march list it dispatches over, and the march itself against
//! `cpu_ref::ssr::march` on a random G-buffer and on `room`; the Hi-Z pyramid
//! (`ssr.hiz`) against `cpu_ref::ssr::hiz`, exactly.
//!
//! Tolerances: the heading confidence goes through GPU `normalize` and matrix products
//! that are not correctly rounded, so a pixel whose confidence lies within 1e-4 of the
//! threshold may be classified either way; every other pixel must match exactly. The
//! march's fail mask must match exactly, its confidence within 1e-4 and its colour
//! within 1e-3 (relative), except where the CPU march grazed a decision — a depth test
//! or the secant's within 1e-4 relative, or a looked-up position within 2e-3 px of a
//! pixel boundary (a ray grazing a depth edge) — and such pixels must be at most 1%.

use crate::common;

use ash::vk;
use glam::IVec2;
use rand::Rng;
use speculum::cpu_ref::ssr::{self, Class};
use speculum::passes::ssr_hiz::{self, HiZPass};
use speculum::passes::ssr_trace::{Classify, MarchInputs, SsrPass};
use speculum::passes::GBuffer;
use speculum::settings::SsrParams;
use speculum::shader_defines::{
    FAIL_BACK_FACE, FAIL_BEHIND, FAIL_BLEND, FAIL_HIT_REFLECTIVE, FAIL_LEFT_SCREEN, FAIL_LOW_CONFIDENCE,
    FAIL_OUT_OF_STEPS, FAIL_SKIPPED, FAIL_UNTRACED, LIST_STRIPES, SSR_LIST_WG,
};
use speculum::vk::{barrier, Image};

const POISON_MASK: u32 = 0xdead_beef;
const POISON_COLOR: [f32; 4] = [-12345.0, -12345.0, -12345.0, 99.0];

/// A random G-buffer (reshaped by `shape`) and lit image on the GPU, with
/// the frame of `room` at w x h and an SSR pass to run over them.
struct Fixture {
    settings: speculum::Settings,
    frame: speculum::gpu_types::FrameUniforms,
    g: common::RandomGBuffer,
    gb: GBuffer,
    lit_texels: Vec<[f32; 4]>,
    lit: Image,
    ubo: speculum::vk::Buffer,
    pass: SsrPass,
    hiz: HiZPass,
    /// Random base colours (sRGB-encoded) and metallic per texel.
    albedo: Vec<u8>,
    metallic: Vec<f32>,
}

impl Fixture {
    fn new(
        ctx: &std::sync::Arc<speculum::vk::Context>,
        seed: u64,
        w: u32,
        h: u32,
        shape: impl FnOnce(&mut common::RandomGBuffer),
    ) -> Self {
        let mut rng = common::rng(seed);
        let scene = speculum::scene::builtin::room().unwrap();
        let settings = speculum::Settings {
            width: w,
            height: h,
            ..Default::default()
        };
        let frame = speculum::renderer::frame_uniforms(&scene, &settings);
        let n = (w * h) as usize;
        let extent = vk::Extent2D { width: w, height: h };
        let mut g = common::random_gbuffer(&mut rng, n);
        shape(&mut g);
        // The normals as the GPU will read them (rounded through RGBA16F).
        g.normal_bytes = speculum::cpu_ref::f32_to_rgba16f(&g.normal);
        g.normal = speculum::gpu_types::rgba16f_to_f32(&g.normal_bytes);
        let gb = GBuffer::new(ctx, extent).unwrap();
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        gb.depth.write(bytemuck::cast_slice(&g.depth), ro).unwrap();
        gb.normal.write(&g.normal_bytes, ro).unwrap();
        gb.material.write(bytemuck::cast_slice(&g.material), ro).unwrap();
        let albedo: Vec<u8> = (0..n * 4).map(|_| rng.random()).collect();
        gb.albedo.write(&albedo, ro).unwrap();
        let metallic = common::random_metallic(&mut rng, &gb, &g.material);
        let lit_texels: Vec<[f32; 4]> = (0..n)
            .map(|_| {
                [
                    rng.random_range(0.0..3.0),
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..0.5),
                    1.0,
                ]
            })
            .collect();
        let lit = Image::storage(ctx, "test.lit", extent, vk::Format::R32G32B32A32_SFLOAT).unwrap();
        lit.write(bytemuck::cast_slice(&lit_texels), vk::ImageLayout::GENERAL)
            .unwrap();
        Self {
            ubo: common::frame_ubo(ctx, &frame),
            pass: SsrPass::new(ctx, extent).unwrap(),
            hiz: HiZPass::new(ctx, extent).unwrap(),
            settings,
            frame,
            g,
            gb,
            lit_texels,
            lit,
            albedo,
            metallic,
        }
    }
}

impl Fixture {
    /// The same inputs with glossy reflections off: every reflective pixel a mirror.
    fn without_glossy(mut self, ctx: &std::sync::Arc<speculum::vk::Context>) -> Self {
        self.settings.glossy = false;
        self.frame = speculum::renderer::frame_uniforms(&speculum::scene::builtin::room().unwrap(), &self.settings);
        self.ubo = common::frame_ubo(ctx, &self.frame);
        self
    }

    /// Records the march over the classification's list (after the pyramid, when
    /// `params.hiz`), as the frame does.
    fn record_march(&self, cmd: vk::CommandBuffer, params: &SsrParams) {
        if params.hiz {
            self.hiz.record(cmd, &self.gb.depth);
        }
        let inputs = MarchInputs {
            frame: &self.ubo,
            gbuffer: &self.gb,
            lit: &self.lit,
            hiz: &self.hiz.out,
        };
        self.pass.trace(cmd, &inputs, params);
    }

    /// What the CPU march reads: this G-buffer, lit image and materials, and `pyramid`.
    fn inputs<'a>(&'a self, pyramid: &'a [Vec<f32>]) -> ssr::MarchInputs<'a> {
        ssr::MarchInputs {
            depth: &self.g.depth,
            normal: &self.g.normal,
            lit: &self.lit_texels,
            albedo: &self.albedo,
            material: &self.g.material,
            metallic: &self.metallic,
            pyramid,
        }
    }

    /// Poisons the outputs, classifies and marches (as the frame does) and reads back the
    /// fail mask and SSR colour.
    fn classify_and_march(&self, ctx: &speculum::vk::Context, params: &SsrParams) -> (Vec<u32>, Vec<[f32; 4]>) {
        let general = vk::ImageLayout::GENERAL;
        self.poison();
        ctx.one_shot(|cmd| {
            self.pass.classify(cmd, (&self.ubo, &self.gb), params, Classify::Tiles);
            self.record_march(cmd, params);
        })
        .unwrap();
        let out = &self.pass.out;
        (
            bytemuck::pod_collect_to_vec(&out.mask.read(general).unwrap()),
            bytemuck::pod_collect_to_vec(&out.color.read(general).unwrap()),
        )
    }

    /// Poisons the SSR colour and fail mask, so a pixel no kernel wrote shows.
    fn poison(&self) {
        let n = (self.settings.width * self.settings.height) as usize;
        let (out, general) = (&self.pass.out, vk::ImageLayout::GENERAL);
        out.mask
            .write(bytemuck::cast_slice(&vec![POISON_MASK; n]), general)
            .unwrap();
        out.color
            .write(bytemuck::cast_slice(&vec![POISON_COLOR; n]), general)
            .unwrap();
    }

    /// The pyramid the GPU march reads, from the CPU reference.
    fn pyramid(&self) -> Vec<Vec<f32>> {
        ssr::hiz(&self.g.depth, self.settings.width, self.settings.height)
    }
}

/// The GPU's classification of a pixel (listed to march, or its fail mask), and whether
/// it is the CPU's `want` (the SSR colour aside).
fn gpu_class(listed: bool, mask: u32, want: Class) -> (Class, bool) {
    let got = if listed {
        Class::March
    } else {
        Class::Done(mask, [0.0; 3])
    };
    let same = match (got, want) {
        (Class::Done(a, _), Class::Done(b, _)) => a == b,
        (a, b) => a == b,
    };
    (got, same)
}

/// The adaptive hybrid's tiles: from random last states and counts and a random
/// exchange rate, `ssr.classify` writes each tile's state as
/// `cpu_ref::ssr::tile_update` does (exactly), with its counts zeroed; in rays-only
/// tiles the pixels the CPU's classification marches are skipped (`FAIL_SKIPPED`, not
/// listed) but for the frame's probes (`tile_probe`), elsewhere listed as ever; then
/// `ssr.trace` counts each tile's marched pixels and those SSR answered as the fail
/// mask says, and ends each probe as the tile's other pixels (`FAIL_SKIPPED`: traced,
/// or untraced for its 2x2 block where its reflection weighs little, the sky kept), so
/// which pixels a frame probes does not show. Pixels on the heading and weight
/// thresholds as in the test below.
#[test]
fn adaptive_tiles_match_cpu() {
    use speculum::passes::ssr_trace::{tile_count, TileSequence};
    use speculum::shader_defines::{TILE_FLIPS_MAX, TILE_FLIPS_SHIFT, TILE_KNOWN, TILE_ONE};
    use speculum::shader_defines::{TILE_RAYS_ONLY, TILE_WORDS};
    let ctx = common::context();
    let mut f = Fixture::new(&ctx, 91, 157, 83, |_| {});
    // Probes at odd x and y (phase 3, 1), off their 2x2 blocks' traced corners.
    f.frame.frame_index = 7;
    f.ubo = common::frame_ubo(&ctx, &f.frame);
    let (w, h) = (f.settings.width as usize, f.settings.height as usize);
    let extent = vk::Extent2D {
        width: w as u32,
        height: h as u32,
    };
    let (tiles, tiles_x) = (tile_count(extent) as usize, w.div_ceil(8));
    let mut rng = common::rng(17);
    let last: Vec<u32> = (0..tiles)
        .flat_map(|_| {
            let state = rng.random_range(0..=TILE_ONE)
                | if rng.random_bool(0.8) { TILE_KNOWN } else { 0 }
                | if rng.random_bool(0.5) { TILE_RAYS_ONLY } else { 0 }
                // Flips so far, some at the counter's end (where it holds).
                | if rng.random_bool(0.2) { TILE_FLIPS_MAX } else { rng.random_range(0..1000) } << TILE_FLIPS_SHIFT;
            let marched = rng.random_range(0..=64u32);
            [state, marched, rng.random_range(0..=marched)]
        })
        .collect();
    let rate = rng.random_range(100..=160u32);
    let params = SsrParams {
        tile_rate: rate,
        ..SsrParams::from_settings(&f.settings)
    };
    let out = &f.pass.out;
    f.poison();
    out.tiles[0].write(bytemuck::cast_slice(&last)).unwrap();
    out.tiles[1].write(&vec![0xcdu8; out.tiles[1].size as usize]).unwrap();
    f.pass.restore_tiles(TileSequence { frames: 1, written: 0 });
    ctx.one_shot(|cmd| {
        f.pass.classify(cmd, (&f.ubo, &f.gb), &params, Classify::Tiles);
        f.record_march(cmd, &params);
        let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
        barrier::record(&ctx.device, cmd, &[b], &[]);
    })
    .unwrap();
    assert_eq!(f.pass.tile_sequence(), TileSequence { frames: 2, written: 1 });
    let got: Vec<u32> = bytemuck::pod_collect_to_vec(&out.tiles[1].read().unwrap());
    let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&out.mask.read(vk::ImageLayout::GENERAL).unwrap());
    let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_args.read().unwrap());
    let list: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_list.read().unwrap());
    let color: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&out.color.read(vk::ImageLayout::GENERAL).unwrap());
    let mut listed = vec![false; w * h];
    for &e in &list[..args[3] as usize] {
        listed[(e >> 16) as usize * w + (e & 0xffff) as usize] = true;
    }
    let words = TILE_WORDS as usize;
    let mut want_counts = vec![[0u32; 2]; tiles];
    let (mut skipped, mut probes, mut borderline, mut flipped, mut untraced) = (0, 0, 0, 0, 0);
    for t in 0..tiles {
        let want = ssr::tile_update(last[words * t], last[words * t + 1], last[words * t + 2], rate);
        assert_eq!(got[words * t], want, "tile {t}");
        flipped += ((got[words * t] ^ last[words * t]) & TILE_RAYS_ONLY != 0) as u32;
    }
    assert!(
        flipped > 10,
        "only {flipped} tiles changed class: the flip count is barely tested"
    );
    for i in 0..w * h {
        let p = IVec2::new((i % w) as i32, (i / w) as i32);
        let t = (i / w / 8) * tiles_x + (i % w) / 8;
        let texel = (
            f.g.depth[i],
            f.g.normal[i],
            f.g.material[i],
            f.albedo[4 * i + 3] as f32 / 255.0,
        );
        let rays_only = got[words * t] & TILE_RAYS_ONLY != 0;
        let probe = ssr::tile_probe(p, f.frame.frame_index);
        let surface = f.inputs(&[]).surface(i);
        let skip = rays_only && !probe;
        let (want, [heading, weight]) = ssr::classify_in_tile(&f.frame, p, texel, surface, &params, (false, skip));
        let (got_class, same) = gpu_class(listed[i], mask[i], want);
        if !same {
            let on_threshold =
                (heading - params.min_confidence).abs() < 1e-4 || (weight - params.trace_min_weight).abs() < 1e-4;
            assert!(
                on_threshold,
                "pixel {p}: GPU {got_class:?}, CPU {want:?}, rays-only {rays_only}, probe {probe}"
            );
            borderline += 1;
        }
        skipped += matches!(want, Class::Done(m, _) if m & FAIL_SKIPPED != 0) as usize;
        probes += (want == Class::March && rays_only) as usize;
        if listed[i] {
            want_counts[t][0] += 1;
            want_counts[t][1] += (mask[i] == 0) as u32;
            // A probe ends as its tile's other pixels do (the classification skipping
            // it): traced, or left untraced for its 2x2 block where its reflection
            // weighs little, so the tile has one source whichever pixels are probed.
            if rays_only {
                let (other, [_, weight]) = ssr::classify_in_tile(&f.frame, p, texel, surface, &params, (false, true));
                let Class::Done(m, sky) = other else {
                    panic!("probe {p}: a skipped pixel is not marched")
                };
                if mask[i] != m && (weight - params.trace_min_weight).abs() < 1e-4 {
                    borderline += 1;
                    continue;
                }
                assert_eq!(mask[i], m, "probe {p}: as its tile's other pixels");
                let close = (0..3).all(|k| (color[i][k] - sky[k]).abs() <= 1e-4 * (1.0 + sky[k].abs()));
                assert!(
                    close && color[i][3] == 0.0,
                    "probe {p}: SSR colour {:?}, want {sky:?}",
                    color[i]
                );
                untraced += (m & FAIL_UNTRACED != 0) as usize;
            }
        }
    }
    for (t, c) in want_counts.iter().enumerate() {
        let (marched, answered) = (got[words * t + 1], got[words * t + 2]);
        if got[words * t] & TILE_RAYS_ONLY != 0 {
            // The probes' own outcomes are not in the mask.
            assert!(
                marched == c[0] && answered <= marched,
                "tile {t}: {marched}, {answered} of {c:?}"
            );
        } else {
            assert_eq!([marched, answered], *c, "tile {t}: marched, answered");
        }
    }
    assert!(borderline <= w * h / 1000, "{borderline} pixels on the threshold");
    let rays_only = (0..tiles).filter(|t| got[words * t] & TILE_RAYS_ONLY != 0).count();
    assert!(
        rays_only > tiles / 5 && rays_only < tiles * 4 / 5,
        "{rays_only} of {tiles} tiles rays-only"
    );
    assert!(skipped > 1000 && probes > 50, "{skipped} skipped, {probes} probes");
    assert!(untraced > 5, "{untraced} probes left untraced for their blocks");
    assert_eq!(ctx.validation_messages(), 0);
}

/// Every pixel classifies as the CPU says: not reflective (mask 0), failed on its
/// heading (FAIL_LOW_CONFIDENCE) or listed for the march, each exactly once; listed
/// pixels are left to the march (their poison stays); the dispatch arguments cover the
/// list. The `rt` variant fails every reflective pixel and lists none; the idle path's
/// (`Classify::SkipAll`) skips every pixel the march would take (`FAIL_SKIPPED`, or
/// untraced as a failed pixel), lists none and leaves the tiles. Then the march
/// over the list writes every listed pixel, the list being long enough to span several
/// stripes of `list_entry` with a remainder (a chunk taken twice or never leaves
/// poison).
#[test]
fn classify_matches_cpu_and_the_march_covers_its_list() {
    let ctx = common::context();
    let f = Fixture::new(&ctx, 78, 157, 83, |_| {});
    let (frame, g, gb, ubo, pass, settings) = (&f.frame, &f.g, &f.gb, &f.ubo, &f.pass, &f.settings);
    let (w, h) = (settings.width as usize, settings.height as usize);
    let n = w * h;
    let general = vk::ImageLayout::GENERAL;
    // The last run also leaves pixels untraced (their own reflection weighing less
    // than 0.3): they keep the sky.
    for (kind, march, trace_min_weight) in [
        (Classify::Tiles, false, 0.0),
        (Classify::MaskOnly, false, 0.0),
        (Classify::Tiles, true, 0.0),
        (Classify::Tiles, false, 0.3),
        (Classify::SkipAll, false, 0.0),
        (Classify::SkipAll, false, 0.3),
    ] {
        let (mask_only, skip) = (kind == Classify::MaskOnly, kind == Classify::SkipAll);
        let tiles = pass.tile_sequence();
        let params = SsrParams {
            trace_min_weight,
            ..SsrParams::from_settings(settings)
        };
        let out = &pass.out;
        f.poison();
        out.march_list
            .write(&vec![0xcdu8; out.march_list.size as usize])
            .unwrap();
        out.march_args.write(&[0xcdu8; 16]).unwrap();
        ctx.one_shot(|cmd| {
            pass.classify(cmd, (ubo, gb), &params, kind);
            if march {
                f.record_march(cmd, &params);
            }
            // RAW: the readback copies see the shaders' writes.
            let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
            barrier::record(&ctx.device, cmd, &[b], &[]);
        })
        .unwrap();
        let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&out.mask.read(general).unwrap());
        let color: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&out.color.read(general).unwrap());
        let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_args.read().unwrap());
        let list_raw: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_list.read().unwrap());
        let len = args[3] as usize;
        assert!(len <= n, "list length {len}");
        let [x, y] = speculum::passes::list_groups(len.div_ceil(SSR_LIST_WG as usize) as u32);
        assert_eq!(args[..3], [x, y, 1], "dispatch arguments");
        let mut listed = vec![false; n];
        for &e in &list_raw[..len] {
            let (x, y) = ((e & 0xffff) as usize, (e >> 16) as usize);
            assert!(x < w && y < h, "list entry {e:#x}");
            assert!(!listed[y * w + x], "pixel ({x}, {y}) listed twice");
            listed[y * w + x] = true;
        }

        let (mut counts, mut borderline, mut untraced) = ([0usize; 3], 0, 0);
        for i in 0..n {
            let p = IVec2::new((i % w) as i32, (i / w) as i32);
            let texel = (
                g.depth[i],
                g.normal[i],
                g.material[i],
                f.albedo[4 * i + 3] as f32 / 255.0,
            );
            let own = f.inputs(&[]).surface(i);
            let (want, [heading, weight]) = ssr::classify_in_tile(frame, p, texel, own, &params, (mask_only, skip));
            let (got, same) = gpu_class(listed[i], mask[i], want);
            let on_threshold =
                (heading - params.min_confidence).abs() < 1e-4 || (weight - params.trace_min_weight).abs() < 1e-4;
            if !same && on_threshold {
                borderline += 1;
                continue;
            }
            assert!(same, "pixel {p} ({kind:?}): GPU {got:?}, CPU {want:?}");
            match want {
                Class::Done(0, _) => counts[0] += 1,
                Class::Done(m, _) => {
                    counts[1] += 1;
                    untraced += (m & FAIL_UNTRACED != 0) as usize;
                }
                Class::March => counts[2] += 1,
            }
            match (want, march) {
                (Class::Done(_, sky), _) => {
                    let close = (0..3).all(|k| (color[i][k] - sky[k]).abs() <= 1e-4 * (1.0 + sky[k].abs()));
                    assert!(
                        close && color[i][3] == 0.0,
                        "pixel {p}: SSR colour {:?}, want {sky:?}",
                        color[i]
                    );
                }
                // Listed: left to the march.
                (Class::March, false) => {
                    assert_eq!(mask[i], POISON_MASK, "pixel {p}");
                    assert_eq!(color[i], POISON_COLOR, "pixel {p}");
                }
                (Class::March, true) => {
                    assert_ne!(mask[i], POISON_MASK, "pixel {p}: listed but not marched");
                    let c = color[i];
                    assert!(
                        c.iter().all(|v| v.is_finite()) && (0.0..=1.0).contains(&c[3]),
                        "pixel {p}: {c:?}"
                    );
                }
            }
        }
        assert!(borderline <= n / 1000, "{borderline} pixels on the threshold");
        assert_eq!(untraced > n / 100, trace_min_weight > 0.0, "{untraced} untraced pixels");
        // Every class occurs (the rt variant lists none and fails every reflective
        // pixel), so each comparison above means something.
        if kind == Classify::Tiles {
            assert_eq!(pass.tile_sequence().frames, tiles.frames + 1);
        } else {
            assert_eq!(pass.tile_sequence(), tiles, "{kind:?} leaves the tiles");
        }
        if mask_only || skip {
            assert!(counts[0] > 0 && counts[1] > 0 && counts[2] == 0, "{counts:?}");
            assert_eq!(len, 0);
            let skipped = mask.iter().filter(|&&m| m & FAIL_SKIPPED != 0).count();
            assert_eq!(skipped > n / 50, skip, "{skipped} skipped");
        } else {
            assert!(counts.iter().all(|&c| c > n / 50), "{counts:?}");
            assert!(mask.contains(&FAIL_LOW_CONFIDENCE));
            // The march list spans every stripe of list_entry, and not evenly.
            let groups = len.div_ceil(SSR_LIST_WG as usize);
            assert!(
                groups > 2 * LIST_STRIPES as usize && !groups.is_multiple_of(LIST_STRIPES as usize),
                "{groups} workgroups"
            );
        }
    }
}

/// How the GPU march of the listed pixels compares with `cpu_ref::ssr::march`.
#[derive(Debug, Default)]
struct MarchComparison {
    listed: usize,
    /// Pixels whose mask or colour differ where the CPU march grazed a decision
    /// (margin below `GRAZE` or a looked-up position within `GRAZE_PX` of a pixel
    /// boundary): allowed, and counted.
    grazing: usize,
    /// Per fail value, how many listed pixels the CPU gave it.
    outcomes: std::collections::BTreeMap<u32, usize>,
}

impl MarchComparison {
    /// Each of these fail values was the outcome of more than 5 pixels, so each branch
    /// of the march was compared.
    fn assert_outcomes(&self, fails: &[u32]) {
        for reason in fails {
            assert!(
                self.outcomes.get(reason).is_some_and(|&k| k > 5),
                "outcome {reason:#x}: {self:?}"
            );
        }
    }
}

/// A decision within this relative margin may go either way on the GPU: its matrix
/// products, divisions and `normalize` are not correctly rounded (and may fuse into
/// FMAs), so values agree with the CPU's to ~1e-6 relative, and a margin 100x that is
/// taken as a tie.
const GRAZE: f32 = 1e-4;
/// A looked-up position this close (pixels) to a pixel boundary may fall on either side:
/// positions up to ~1000 px accumulate a few ulps (6e-5 px each) over a march.
const GRAZE_PX: f32 = 2e-3;

/// Compares the march of every listed pixel: mask exactly, confidence within 1e-4 and
/// colour within 1e-3 relative (bilinear weights from the sub-pixel hit position),
/// except for grazing pixels.
fn compare_march(
    frame: &speculum::gpu_types::FrameUniforms,
    inputs: &ssr::MarchInputs<'_>,
    params: &SsrParams,
    listed: &[IVec2],
    mask: &[u32],
    color: &[[f32; 4]],
) -> MarchComparison {
    let w = frame.resolution[0] as i32;
    let mut c = MarchComparison {
        listed: listed.len(),
        ..Default::default()
    };
    for &p in listed {
        let i = (p.y * w + p.x) as usize;
        let want = ssr::march(frame, p, inputs, params);
        *c.outcomes.entry(want.fail).or_default() += 1;
        let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()));
        // The colour interpolates the lit image at the hit position, which the GPU's
        // march finds within GRAZE_PX of the CPU's on each axis (else the pixel is
        // grazing): the colour may move by the texels' spread times that shift.
        let shifted = 2.0 * GRAZE_PX * want.lit_spread;
        let same = mask[i] == want.fail
            && close(color[i][3], want.color[3], 1e-4)
            && (0..3).all(|k| {
                (color[i][k] - want.color[k]).abs()
                    <= 1e-3 * (1.0 + color[i][k].abs().max(want.color[k].abs())) + shifted
            });
        if same {
            continue;
        }
        let grazing = want.margin < GRAZE || want.pixel_margin < GRAZE_PX;
        assert!(
            grazing,
            "pixel {p}: GPU mask {:#x} colour {:?}, CPU {want:?} (colour allowed {shifted} beyond 1e-3 relative)",
            mask[i], color[i]
        );
        c.grazing += 1;
    }
    c
}

/// The march of glossy pixels (random roughness: mirrors, glossy and rough pixels side
/// by side; two rays each) against the CPU's on the random G-buffer of
/// `march_matches_cpu_on_a_random_gbuffer`: the mask, colour and confidence as there,
/// and the hit distance of the pixels SSR answered within 1e-3 relative.
#[test]
fn glossy_march_matches_cpu_on_a_random_gbuffer() {
    let ctx = common::context();
    let (w, h) = (131usize, 77usize);
    let mut f = Fixture::new(&ctx, 92, w as u32, h as u32, |g| {
        for y in 0..h {
            for x in 0..w {
                let patch = ((x / 16) + 7 * (y / 16)) % 5;
                let d = 0.95 + 0.008 * patch as f32 + 0.0004 * ((x % 16) as f32 - (y % 16) as f32);
                g.depth[y * w + x] = if patch == 4 && x % 16 < 5 { 1.0 } else { d };
            }
        }
    });
    f.frame = speculum::gpu_types::FrameUniforms {
        glossy: 1,
        reflection_rays: 2,
        frame_index: 5,
        ..f.frame
    };
    f.ubo = common::frame_ubo(&ctx, &f.frame);
    let general = vk::ImageLayout::GENERAL;
    let pyramid = f.pyramid();
    let params = SsrParams {
        recursion_min: 0.6,
        max_steps: 9,
        ..SsrParams::from_settings(&f.settings)
    };
    let out = &f.pass.out;
    let (mask, color) = f.classify_and_march(&ctx, &params);
    let hit: Vec<f32> = bytemuck::pod_collect_to_vec(&out.hit_distance.read(general).unwrap());
    let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_args.read().unwrap());
    let list: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_list.read().unwrap());
    let listed = listed_pixels(&list, args[3] as usize);
    let inputs = f.inputs(&pyramid);
    let c = compare_march(&f.frame, &inputs, &params, &listed, &mask, &color);
    assert!(c.grazing * 100 <= c.listed, "{c:?}");
    c.assert_outcomes(&[0, FAIL_BEHIND, FAIL_LEFT_SCREEN, FAIL_OUT_OF_STEPS, FAIL_BACK_FACE]);
    let (mut glossy, mut answered) = (0usize, 0usize);
    for &p in &listed {
        let i = p.y as usize * w + p.x as usize;
        let roughness = f.albedo[4 * i + 3] as f32 / 255.0;
        glossy += speculum::cpu_ref::glossy::is_glossy(&f.frame, roughness) as usize;
        let want = ssr::march(&f.frame, p, &inputs, &params);
        if mask[i] == want.fail && want.fail == 0 && want.margin >= GRAZE && want.pixel_margin >= GRAZE_PX {
            answered += 1;
            assert!(
                (hit[i] - want.hit_distance).abs() <= 1e-3 * want.hit_distance,
                "pixel {p}: hit distance {} vs {}",
                hit[i],
                want.hit_distance
            );
        }
    }
    assert!(
        glossy > c.listed / 4 && answered > 100,
        "{glossy} glossy, {answered} answered of {c:?}"
    );
}

/// Unpacks the first `len` entries of a march list.
fn listed_pixels(raw: &[u32], len: usize) -> Vec<IVec2> {
    raw[..len]
        .iter()
        .map(|e| IVec2::new((e & 0xffff) as i32, (e >> 16) as i32))
        .collect()
}

/// The march against its CPU reference on a random G-buffer: the mask of every listed
/// pixel matches exactly, its colour and confidence within tolerance, except pixels
/// whose ray grazes a decision (at most 1%).
#[test]
fn march_matches_cpu_on_a_random_gbuffer() {
    let ctx = common::context();
    // Smooth depth in patches (with sky holes) so rays march some steps before they hit
    // or pass behind: per-pixel noise would end nearly every ray at its first step.
    let (w, h) = (131usize, 77usize);
    let f = Fixture::new(&ctx, 91, w as u32, h as u32, |g| {
        let depth = &mut g.depth;
        for y in 0..h {
            for x in 0..w {
                let patch = ((x / 16) + 7 * (y / 16)) % 5;
                let d = 0.95 + 0.008 * patch as f32 + 0.0004 * ((x % 16) as f32 - (y % 16) as f32);
                depth[y * w + x] = if patch == 4 && x % 16 < 5 { 1.0 } else { d };
            }
        }
    });
    let (frame, gb, ubo, pass, settings) = (&f.frame, &f.gb, &f.ubo, &f.pass, &f.settings);
    let general = vk::ImageLayout::GENERAL;
    let pyramid = f.pyramid();
    // Both marches. A short budget, so rays also run out of steps (a Hi-Z step may
    // cross many pixels, a DDA step crosses `stride`); a recursion threshold that lets
    // random reflectivities both pass and fail.
    // The last run leaves the failures of weak reflectors untraced (the sky kept).
    for (hiz, max_steps, trace_min_weight) in [(true, 9, 0.0), (false, 5, 0.0), (true, 9, 0.3)] {
        let params = SsrParams {
            hiz,
            trace_min_weight,
            recursion_min: 0.6,
            max_steps,
            ..SsrParams::from_settings(settings)
        };
        let out = &pass.out;
        f.poison();
        if hiz {
            f.hiz
                .out
                .buffer
                .write(&vec![0xcdu8; f.hiz.out.buffer.size as usize])
                .unwrap();
        }
        ctx.one_shot(|cmd| {
            pass.classify(cmd, (ubo, gb), &params, Classify::Tiles);
            f.record_march(cmd, &params);
        })
        .unwrap();
        let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&out.mask.read(general).unwrap());
        let color: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&out.color.read(general).unwrap());
        let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_args.read().unwrap());
        let list: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_list.read().unwrap());
        let inputs = f.inputs(&pyramid);
        let c = compare_march(
            frame,
            &inputs,
            &params,
            &listed_pixels(&list, args[3] as usize),
            &mask,
            &color,
        );
        println!("hiz {hiz}: {c:?}");
        assert!(c.grazing * 100 <= c.listed, "hiz {hiz}: {c:?}");
        // Hits kept, hits judged and misses all occur, so every branch was compared.
        let outcomes = [
            0,
            FAIL_BLEND,
            FAIL_BEHIND,
            FAIL_LEFT_SCREEN,
            FAIL_OUT_OF_STEPS,
            FAIL_BACK_FACE,
            FAIL_HIT_REFLECTIVE,
        ];
        c.assert_outcomes(&outcomes);
        let untraced: usize = c
            .outcomes
            .iter()
            .filter(|(m, _)| *m & FAIL_UNTRACED != 0)
            .map(|(_, k)| k)
            .sum();
        assert_eq!(untraced > 20, trace_min_weight > 0.0, "{untraced} untraced");
    }
}

/// Both marches against their CPU reference on `room`'s own G-buffer and lit image, as
/// the renderer leaves them after a hybrid frame.
#[test]
fn march_matches_cpu_on_room() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::room().unwrap();
    for hiz in [true, false] {
        let settings = speculum::Settings {
            width: 192,
            height: 108,
            ssr_hiz: hiz,
            ..Default::default()
        };
        let mut r = speculum::Renderer::new(&ctx, &scene, &settings).unwrap();
        r.render_frame().unwrap();
        let frame = *r.uniforms();
        let t = &r.lighting.gbuffer.out;
        let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.depth).unwrap());
        let normal = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.normal).unwrap());
        let lit = r.read_lit().unwrap();
        let general = vk::ImageLayout::GENERAL;
        let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.out.mask.read(general).unwrap());
        let color: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.out.color.read(general).unwrap());
        let args: Vec<u32> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.out.march_args.read().unwrap());
        let list: Vec<u32> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.out.march_list.read().unwrap());
        let albedo = r.read_target(&t.albedo).unwrap();
        let material: Vec<u32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.material).unwrap());
        let metallic: Vec<f32> = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.motion).unwrap())
            .iter()
            .map(|t| t[3])
            .collect();
        let inputs = ssr::MarchInputs {
            depth: &depth,
            normal: &normal,
            lit: &lit,
            albedo: &albedo,
            material: &material,
            metallic: &metallic,
            pyramid: &ssr::hiz(&depth, settings.width, settings.height),
        };
        let params = SsrParams::from_settings(&settings);
        let c = compare_march(
            &frame,
            &inputs,
            &params,
            &listed_pixels(&list, args[3] as usize),
            &mask,
            &color,
        );
        println!("hiz {hiz}: {c:?}");
        assert!(c.listed > 2000 && c.grazing * 100 <= c.listed, "hiz {hiz}: {c:?}");
        let outcomes = [
            0,
            FAIL_BLEND,
            FAIL_BEHIND,
            FAIL_LEFT_SCREEN,
            FAIL_BACK_FACE,
            FAIL_LOW_CONFIDENCE,
            FAIL_HIT_REFLECTIVE,
        ];
        c.assert_outcomes(&outcomes);
    }
}

/// A march list longer than `LIST_GROUPS_X` workgroups (every device's dispatch limit
/// along x) is dispatched over x and y, and every listed pixel is marched.
#[test]
fn a_march_list_beyond_one_row_of_workgroups_is_covered() {
    use speculum::shader_defines::LIST_GROUPS_X;
    let ctx = common::context();
    let (w, h) = (2200u32, 1920u32);
    // Every pixel a mirror-like floor (normal up, away-heading rays): nearly all listed.
    let f = Fixture::new(&ctx, 5, w, h, |g| {
        for (i, n) in g.normal.iter_mut().enumerate() {
            *n = [0.0, 1.0, 0.0, 0.9];
            g.material[i] = 0;
        }
    });
    let general = vk::ImageLayout::GENERAL;
    let out = &f.pass.out;
    f.poison();
    let params = SsrParams::from_settings(&f.settings);
    ctx.one_shot(|cmd| {
        f.pass.classify(cmd, (&f.ubo, &f.gb), &params, Classify::Tiles);
        f.record_march(cmd, &params);
    })
    .unwrap();
    let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_args.read().unwrap());
    let len = args[3] as usize;
    let groups = len.div_ceil(SSR_LIST_WG as usize);
    assert!(
        groups > LIST_GROUPS_X as usize,
        "{groups} workgroups: the list must need a second row"
    );
    assert_eq!(args[..3], [LIST_GROUPS_X, 2, 1]);
    let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&out.mask.read(general).unwrap());
    let list: Vec<u32> = bytemuck::pod_collect_to_vec(&out.march_list.read().unwrap());
    let unmarched = listed_pixels(&list, len)
        .iter()
        .filter(|p| mask[(p.y as u32 * w + p.x as u32) as usize] == POISON_MASK)
        .count();
    assert_eq!(unmarched, 0, "listed pixels the march never reached");
}

/// `ssr.hiz` against `cpu_ref::ssr::hiz`, bit for bit, on random depth with sky holes
/// at sizes odd and even, thin and 1x1, the pyramid poisoned first (0xcdcdcdcd is a
/// large negative float: a minimum that read a texel it should not would keep it).
#[test]
fn hiz_pyramid_matches_cpu_exactly() {
    let ctx = common::context();
    let mut rng = common::rng(77);
    for (w, h) in [(64u32, 48u32), (37, 23), (1, 19), (200, 1), (1, 1), (129, 65)] {
        let extent = vk::Extent2D { width: w, height: h };
        let gb = GBuffer::new(&ctx, extent).unwrap();
        let depth: Vec<f32> = (0..w * h)
            .map(|_| {
                if rng.random_bool(0.15) {
                    1.0
                } else {
                    rng.random_range(0.0..1.0f32)
                }
            })
            .collect();
        let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        gb.depth.write(bytemuck::cast_slice(&depth), ro).unwrap();
        let pass = HiZPass::new(&ctx, extent).unwrap();
        pass.out
            .buffer
            .write(&vec![0xcdu8; pass.out.buffer.size as usize])
            .unwrap();
        ctx.one_shot(|cmd| pass.record(cmd, &gb.depth)).unwrap();
        let gpu = pass.out.read().unwrap();
        let want = ssr::hiz(&depth, w, h);
        let sizes: Vec<usize> = ssr_hiz::levels(w, h)
            .iter()
            .map(|l| (l.size[0] * l.size[1]) as usize)
            .collect();
        assert_eq!(
            sizes,
            want.iter().map(Vec::len).collect::<Vec<_>>(),
            "{w}x{h}: level sizes"
        );
        assert_eq!(gpu.len(), want.len(), "{w}x{h}: levels");
        assert_eq!(want.last().map(Vec::len), Some(1), "{w}x{h}: the top is 1x1");
        for (k, (g, c)) in gpu.iter().zip(&want).enumerate() {
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(g), bits(c), "{w}x{h} level {k}");
        }
        // The top is the nearest depth of the whole image.
        let nearest = depth.iter().copied().fold(f32::INFINITY, f32::min);
        assert_eq!(want.last().unwrap()[0], nearest);
    }
}

/// A thin bar in front of a far wall, above a row of mirror pixels whose reflections
/// rise up the screen and pass behind the bar: the hierarchical march visits every
/// pixel on the way, so each ray stops behind the bar (`FAIL_BEHIND`, ray traced) and
/// none takes the wall's colour from beyond it; the linear DDA (8 px strides) steps
/// over the 2-px bar and reports false hits on the wall, a reflection seen through the
/// bar (the case this test keeps fixed).
#[test]
fn the_hiz_march_does_not_see_through_thin_geometry() {
    let ctx = common::context();
    let (w, h) = (131usize, 77usize);
    let bar = 30..32;
    let f = Fixture::new(&ctx, 13, w as u32, h as u32, |g| {
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (depth, normal) = match y {
                    // The wall, far (about 7 m), facing the camera, not reflective.
                    _ if y < bar.start => (0.985, [0.0, 0.0, 1.0, 0.0]),
                    // The bar, near (about 1 m).
                    _ if bar.contains(&y) => (0.90, [0.0, 0.0, 1.0, 0.0]),
                    // The mirror row (about 3 m), normal up: rays rise up the screen.
                    _ if y == h - 1 => (0.97, [0.0, 1.0, 0.0, 0.9]),
                    _ => (1.0, [0.0, 0.0, 1.0, 0.0]),
                };
                g.depth[i] = depth;
                g.normal[i] = normal;
                g.material[i] = 0;
            }
        }
    });
    // Lit colours that say where a hit came from: the wall blue, the bar red.
    let lit: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            if i / w < bar.start {
                [0.0, 0.0, 1.0, 1.0]
            } else {
                [1.0, 0.0, 0.0, 1.0]
            }
        })
        .collect();
    let general = vk::ImageLayout::GENERAL;
    f.lit.write(bytemuck::cast_slice(&lit), general).unwrap();
    let mut wall_hits = Vec::new();
    for hiz in [true, false] {
        // Every failure traced: the march's outcome alone.
        let params = SsrParams {
            hiz,
            trace_min_weight: 0.0,
            ..SsrParams::from_settings(&f.settings)
        };
        let (mask, color) = f.classify_and_march(&ctx, &params);
        let row = (h - 1) * w..h * w;
        let behind = row.clone().filter(|&i| mask[i] == FAIL_BEHIND).count();
        let wall = row
            .filter(|&i| (mask[i] == 0 || mask[i] == FAIL_BLEND) && color[i][2] > color[i][0])
            .count();
        println!("hiz {hiz}: {behind} of {w} behind the bar, {wall} false hits on the wall");
        if hiz {
            assert!(behind > w / 2, "hiz: {behind} of {w} rays stopped behind the bar");
        }
        wall_hits.push(wall);
    }
    assert_eq!(wall_hits[0], 0, "the Hi-Z march saw the wall through the bar");
    assert!(
        wall_hits[1] > 10,
        "the linear DDA no longer steps over the bar: {wall_hits:?}"
    );
}

/// Curtains: rays that run across the screen at a constant depth pass 1% of their
/// depth behind a vertical bar, well within `ssr_thickness` (3%) but far more than
/// the ray's depth changes over a pixel. Such a ray enters the bar's pixels from the
/// side, behind its surface: it passes behind the bar (or hits a side the screen does
/// not show), so the march fails it (`FAIL_BEHIND`) instead of taking the bar's colour,
/// which would streak the bar along every such ray. (With the thickness alone deciding,
/// as before, every one of these rays was a hit on the bar.) The GPU march matches the
/// CPU's on each.
#[test]
fn a_ray_passing_just_behind_a_silhouette_is_not_a_hit() {
    use glam::{Mat3, Vec3};
    let ctx = common::context();
    let (w, h) = (131usize, 77usize);
    let (band, bar) = (20..30usize, 80..84usize);
    let mirror_depth = 0.97f32;
    let probe = Fixture::new(&ctx, 3, w as u32, h as u32, |_| {}).without_glossy(&ctx);
    let frame = probe.frame;
    drop(probe);
    let p = frame.proj;
    let view_z = |d: f32| -p.w_axis.z / (d + p.z_axis.z);
    let depth_of = |z: f32| -p.w_axis.z / z - p.z_axis.z;
    // The bar 1% nearer than the mirror band (and so than its rays).
    let bar_depth = depth_of(view_z(mirror_depth) * 0.99);
    let to_world = Mat3::from_mat4(frame.view).transpose();
    let right = to_world * Vec3::X;
    let camera = frame.view.inverse().w_axis.truncate();
    let f = Fixture::new(&ctx, 3, w as u32, h as u32, |g| {
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (depth, normal) = if band.contains(&x) && (20..60).contains(&y) {
                    // A mirror whose normal halves the view ray and the camera's right:
                    // the reflection runs to the right at the pixel's own view depth.
                    let q = IVec2::new(x as i32, y as i32);
                    let v =
                        (speculum::cpu_ref::shading::world_from_depth(&frame, q, mirror_depth) - camera).normalize();
                    let n = (right - v).normalize();
                    (mirror_depth, [n.x, n.y, n.z, 0.9])
                } else if bar.contains(&x) {
                    // Facing back along the rays and a little towards the camera.
                    let n = (-right + 0.3 * (to_world * Vec3::Z)).normalize();
                    (bar_depth, [n.x, n.y, n.z, 0.0])
                } else {
                    (1.0, [0.0, 1.0, 0.0, 0.0])
                };
                g.depth[i] = depth;
                g.normal[i] = normal;
                g.material[i] = 0;
            }
        }
    });
    // Mirror rays: a glossy lobe's rays would not all run along the band.
    let f = f.without_glossy(&ctx);
    let general = vk::ImageLayout::GENERAL;
    // The default march and thickness, every failure traced (the march's outcome alone).
    let params = SsrParams {
        trace_min_weight: 0.0,
        ..SsrParams::from_settings(&f.settings)
    };
    assert!(params.hiz && params.thickness > 0.02, "the default march and thickness");
    f.poison();
    ctx.one_shot(|cmd| {
        f.pass.classify(cmd, (&f.ubo, &f.gb), &params, Classify::Tiles);
        f.record_march(cmd, &params);
    })
    .unwrap();
    let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&f.pass.out.mask.read(general).unwrap());
    let pyramid = f.pyramid();
    let inputs = f.inputs(&pyramid);
    let mut behind = 0;
    for y in 20..60 {
        for x in band.clone() {
            let q = IVec2::new(x as i32, y as i32);
            let want = ssr::march(&frame, q, &inputs, &params);
            assert_eq!(mask[y * w + x], want.fail, "pixel {q}: {want:?}");
            assert!(
                want.fail != 0 && want.fail != FAIL_BLEND,
                "pixel {q} hit the bar: {want:?}"
            );
            behind += (want.fail == FAIL_BEHIND) as usize;
        }
    }
    assert_eq!(behind, band.len() * 40, "every ray passes behind the bar");
}
