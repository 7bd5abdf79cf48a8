//! Glossy reflections: the GGX VNDF directions and the spatial filter against their
//! CPU references on random inputs, and the glossy frame itself.
//!
//! Tolerances: directions within 2e-4 per component (GPU `sin`, `cos`, `sqrt` and
//! `normalize` are not correctly rounded; a few ULPs in the sample grow through two
//! normalizations and the basis change); the filter within 2e-3 relative + 2e-4 absolute
//! (GPU `exp`/`pow` in its weights, and a tap offset that rounds the other way at .5 is
//! allowed in at most 0.5% of pixels).

use crate::common;

use ash::vk;
use glam::{IVec2, Vec3};
use rand::Rng;
use speculum::cpu_ref::{denoise, glossy};
use speculum::passes::reflect_denoise::{DenoiseInputs, DenoiseParams, DenoisePass};
use speculum::shader_defines::{MATERIAL_NONE, SOURCE_RT, SOURCE_SSR};

/// The filter tests' `reflective_min`.
const REFLECTIVE_MIN: f32 = 0.1;
use speculum::vk::{Buffer, Groups, Image, Pipeline, Resource};

fn random_unit(rng: &mut impl Rng) -> Vec3 {
    Vec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize_or(Vec3::Y)
}

/// glossy_direction on the GPU equals the CPU's for random normals, views (on the
/// normal's side), roughness from mirror to fully rough, pixels, sample indices, frame
/// indices and streams; every direction is unit and above the surface.
#[test]
fn glossy_directions_match_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(40);
    let n_cases = 4000usize;
    for (frame_index, rays, stream) in [(0u32, 1u32, 0u32), (917, 4, 1), (u32::MAX - 2, 16, 7)] {
        let frame = speculum::gpu_types::FrameUniforms {
            frame_index,
            reflection_rays: rays,
            sample_stream: stream,
            glossy: 1,
            ..Default::default()
        };
        let mut cases = Vec::with_capacity(3 * n_cases);
        let mut want = Vec::with_capacity(n_cases);
        for _ in 0..n_cases {
            let n = random_unit(&mut rng);
            let mut v = random_unit(&mut rng);
            if v.dot(n) < 0.0 {
                v = -v;
            }
            let r = if rng.random_bool(0.1) {
                1.0
            } else {
                rng.random_range(0.0..1.0f32)
            };
            let s = rng.random_range(0..rays);
            let p = IVec2::new(rng.random_range(0..4096), rng.random_range(0..4096));
            cases.extend([
                n.extend(r),
                v.extend(s as f32),
                glam::Vec4::new(p.x as f32, p.y as f32, 0.0, 0.0),
            ]);
            want.push(glossy::glossy_direction(&frame, p, n, v, r, s));
        }
        let ubo = common::frame_ubo(&ctx, &frame);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let input = Buffer::with_data(&ctx, "test.cases", usage, bytemuck::cast_slice(&cases)).unwrap();
        let out = Buffer::device_list(&ctx, "test.directions", (n_cases * 16) as u64).unwrap();
        out.write(&vec![0xffu8; n_cases * 16]).unwrap(); // poison: NaN
        let pipeline =
            Pipeline::compute::<u32>(&ctx, "test.glossy_sample", speculum::shaders::GLOSSY_SAMPLE_COMP).unwrap();
        ctx.one_shot(|cmd| {
            // Bound by name, in another order than the shader's slots.
            let res = [
                ("directions", Resource::Buffer(&out)),
                ("frame", Resource::Buffer(&ubo)),
                ("cases", Resource::Buffer(&input)),
            ];
            pipeline.dispatch(cmd, &res, &(n_cases as u32), Groups::Cover([n_cases as u32, 1, 1]));
        })
        .unwrap();
        let got: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&out.read().unwrap());
        let mut spread = 0.0f32;
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            let g = Vec3::new(g[0], g[1], g[2]);
            assert!(
                (g - *w).abs().max_element() < 2e-4,
                "case {i} (frame {frame_index}): GPU {g} vs CPU {w}"
            );
            let n = cases[3 * i].truncate();
            assert!(
                (g.length() - 1.0).abs() < 1e-4 && g.dot(n) > 0.0,
                "case {i}: {g} not above {n}"
            );
            spread += 1.0 - g.dot(w.normalize());
        }
        assert!(spread.is_finite());
    }
}

/// A G-buffer in patches (a normal, a depth slope, a roughness from mirror past the
/// rough cut-off per patch, with noise; three in ten patches moved since the frame
/// before), sky and weak reflectors among them, and a noisy merged reflection with
/// fireflies.
struct FilterCase {
    depth: Vec<f32>,
    normal: Vec<[f32; 4]>,
    normal_bytes: Vec<u8>,
    albedo: Vec<u8>,
    roughness: Vec<f32>,
    material: Vec<u32>,
    merged: Vec<[f32; 4]>,
    /// The motion as the GPU reads it (rounded through RGBA16F), and its texels.
    motion: Vec<[f32; 4]>,
    motion_bytes: Vec<u8>,
}

fn filter_case(rng: &mut impl Rng, w: usize, h: usize) -> FilterCase {
    let patch = |x: usize, y: usize| (x / 23 + 7 * (y / 19)) as u64;
    let mut normal = Vec::new();
    let (mut depth, mut albedo, mut material, mut merged) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut motion = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut prng = common::rng(patch(x, y));
            let n0 = random_unit(&mut prng);
            let r_byte: u8 = prng.random_range(0..150);
            let d0 = prng.random_range(0.95..0.995f32);
            let moved = if prng.random_bool(0.3) {
                random_unit(&mut prng) * prng.random_range(0.005..0.05f32)
            } else {
                Vec3::ZERO
            };
            motion.push([moved.x, moved.y, moved.z, 0.0]);
            let n = (n0 + 0.05 * random_unit(rng)).normalize();
            let sky = rng.random_bool(0.05);
            // The sky's normal target is cleared to 0, its reflectivity too.
            let reflectivity = if sky || rng.random_bool(0.05) {
                0.0
            } else {
                rng.random_range(0.2..1.0)
            };
            normal.push([n.x, n.y, n.z, reflectivity]);
            depth.push(d0 + 1e-4 * (x % 23) as f32 + rng.random_range(0.0..2e-5));
            let r = r_byte.saturating_add(rng.random_range(0..8));
            albedo.extend([rng.random::<u8>(), rng.random(), rng.random(), r]);
            material.push(if sky { MATERIAL_NONE } else { rng.random_range(0..4) });
            let firefly = if rng.random_bool(0.02) { 50.0 } else { 1.0 };
            let source = if rng.random_bool(0.5) { SOURCE_SSR } else { SOURCE_RT };
            merged.push([
                rng.random_range(0.0..1.0) * firefly,
                rng.random_range(0.0..2.0),
                rng.random_range(0.0..0.5),
                source as f32,
            ]);
        }
    }
    let normal_bytes = speculum::cpu_ref::f32_to_rgba16f(&normal);
    let normal = speculum::gpu_types::rgba16f_to_f32(&normal_bytes);
    let roughness = albedo.chunks(4).map(|t| t[3] as f32 / 255.0).collect();
    let motion_bytes = speculum::cpu_ref::f32_to_rgba16f(&motion);
    let motion = speculum::gpu_types::rgba16f_to_f32(&motion_bytes);
    FilterCase {
        motion,
        motion_bytes,
        depth,
        normal,
        normal_bytes,
        albedo,
        roughness,
        material,
        merged,
    }
}

/// A filter test's inputs on the GPU: `room`'s frame with glossy reflections at w x h,
/// a random `FilterCase` in a G-buffer, the merged-reflection image and the pass.
struct FilterRig {
    frame: speculum::gpu_types::FrameUniforms,
    case: FilterCase,
    gb: speculum::passes::GBuffer,
    merged: Image,
    pass: DenoisePass,
    /// The glossy pixels (`cpu_ref::denoise::glossy_pixels`), as `ssr.classify` lists
    /// them, and the list and its indirect arguments on the GPU.
    glossy: Vec<IVec2>,
    list: Buffer,
    list_args: Buffer,
    /// Random hit distances (some far), and their image.
    hit: Vec<f32>,
    hit_image: Image,
}

impl FilterRig {
    fn new(ctx: &std::sync::Arc<speculum::vk::Context>, seed: u64, w: usize, h: usize) -> Self {
        let settings = speculum::Settings {
            width: w as u32,
            height: h as u32,
            glossy: true,
            ..Default::default()
        };
        let (frame, extent) = common::room_frame(&settings);
        let case = filter_case(&mut common::rng(seed), w, h);
        let g = common::RandomGBuffer {
            depth: case.depth.clone(),
            normal: case.normal.clone(),
            normal_bytes: case.normal_bytes.clone(),
            material: case.material.clone(),
        };
        let gb = common::upload_gbuffer(ctx, extent, &g, Some(&case.albedo));
        gb.motion
            .write(&case.motion_bytes, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            .unwrap();
        let format = speculum::passes::reflect_denoise::FORMAT;
        let merged = Image::storage(ctx, "test.merged", extent, format).unwrap();
        merged
            .write(bytemuck::cast_slice(&case.merged), vk::ImageLayout::GENERAL)
            .unwrap();
        let pass = DenoisePass::new(ctx, extent).unwrap();
        let mut rig = Self {
            frame,
            case,
            gb,
            merged,
            pass,
            glossy: Vec::new(),
            list: Buffer::device_list(ctx, "test.glossy_list", (w * h * 4) as u64).unwrap(),
            list_args: Buffer::device_list(ctx, "test.glossy_args", 16).unwrap(),
            hit: Vec::new(),
            hit_image: Image::storage(ctx, "test.hit", extent, vk::Format::R32_SFLOAT).unwrap(),
        };
        let mut rng = common::rng(seed + 1000);
        rig.hit = (0..w * h)
            .map(|_| {
                if rng.random_bool(0.2) {
                    1e30
                } else {
                    rng.random_range(0.01..20.0f32)
                }
            })
            .collect();
        rig.hit_image
            .write(bytemuck::cast_slice(&rig.hit), vk::ImageLayout::GENERAL)
            .unwrap();
        rig.glossy = denoise::glossy_pixels(&rig.frame, &rig.surfaces(), REFLECTIVE_MIN);
        let packed: Vec<u32> = rig.glossy.iter().map(|p| p.x as u32 | (p.y as u32) << 16).collect();
        rig.list.write(bytemuck::cast_slice(&packed)).unwrap();
        let groups = (packed.len() as u32).div_ceil(speculum::shader_defines::SSR_LIST_WG);
        rig.list_args
            .write(bytemuck::cast_slice(&[groups, 1, 1, packed.len() as u32]))
            .unwrap();
        rig
    }

    /// Records the pass over the rig's inputs with frame uniforms `ubo` (of `frame`).
    fn record(
        &mut self,
        ctx: &speculum::vk::Context,
        ubo: &Buffer,
        params: DenoiseParams,
        frame: &speculum::gpu_types::FrameUniforms,
    ) {
        let inputs = DenoiseInputs {
            frame: ubo,
            gbuffer: &self.gb,
            merged: &self.merged,
            list: &self.list,
            list_args: &self.list_args,
            hit_distance: &self.hit_image,
        };
        let pass = &mut self.pass;
        ctx.one_shot(|cmd| pass.record(cmd, &inputs, params, frame)).unwrap();
    }

    fn surfaces(&self) -> denoise::Surfaces<'_> {
        denoise::Surfaces {
            depth: &self.case.depth,
            normal: &self.case.normal,
            roughness: &self.case.roughness,
            material: &self.case.material,
            motion: &self.case.motion,
        }
    }
}

/// reflect.denoise equals the CPU's filter on random G-buffers and reflections, for
/// several radii and frames; pixels that are not glossy pass through bit for bit.
#[test]
fn denoise_matches_cpu_reference() {
    let ctx = common::context();
    let (w, h) = (131usize, 77usize);
    let mut rig = FilterRig::new(&ctx, 42, w, h);
    let case = rig.case.merged.clone();
    for (radius, frame_index) in [(8u32, 0u32), (3, 5), (32, 77)] {
        let frame = speculum::gpu_types::FrameUniforms {
            frame_index,
            ..rig.frame
        };
        let ubo = common::frame_ubo(&ctx, &frame);
        rig.merged
            .write(bytemuck::cast_slice(&case), vk::ImageLayout::GENERAL)
            .unwrap();
        let poison = vec![[-12345.0f32; 4]; w * h];
        rig.pass
            .out
            .write(bytemuck::cast_slice(&poison), vk::ImageLayout::GENERAL)
            .unwrap();
        let params = DenoiseParams {
            radius,
            history: 0,
            reflective_min: REFLECTIVE_MIN,
        };
        rig.record(&ctx, &ubo, params, &frame);
        // With no history the temporal step copies the spatial result into `merged`.
        let got = read(&rig.merged);
        let want = denoise::denoise(
            &frame,
            &rig.surfaces(),
            &case,
            &rig.hit,
            &rig.glossy,
            radius,
            REFLECTIVE_MIN,
        );
        let listed: std::collections::HashSet<usize> =
            rig.glossy.iter().map(|p| p.y as usize * w + p.x as usize).collect();
        let (mut off, mut filtered) = (0usize, 0usize);
        for i in 0..w * h {
            if !listed.contains(&i) {
                assert_eq!(got[i], case[i], "pixel {i}: not glossy, changed");
                continue;
            }
            filtered += (want[i] != case[i]) as usize;
            let close = (0..4).all(|c| (got[i][c] - want[i][c]).abs() <= 2e-3 * want[i][c].abs() + 2e-4);
            off += !close as usize;
        }
        assert!(
            filtered > w * h / 10,
            "radius {radius}: only {filtered} pixels filtered"
        );
        assert!(
            off * 200 <= filtered,
            "radius {radius}: {off} of {filtered} filtered pixels differ from the CPU"
        );
    }
}

fn read(img: &Image) -> Vec<[f32; 4]> {
    bytemuck::pod_collect_to_vec(&img.read(vk::ImageLayout::GENERAL).unwrap())
}

/// A new denoiser's history holds no frame's stamp, whatever its memory held before (a
/// renderer made on the same allocator after another gets that one's memory, and its
/// frames read a stamp they had not written, made a frame of `drop` differ by a unit in
/// three pixels between two runs of one process): every texel of its meta reads -1,
/// which no frame writes.
#[test]
fn a_new_denoisers_history_holds_no_frame() {
    let ctx = common::context();
    let extent = vk::Extent2D { width: 37, height: 23 };
    for _ in 0..2 {
        let pass = DenoisePass::new(&ctx, extent).unwrap();
        let meta = read(pass.history().1);
        assert_eq!(meta.len(), 37 * 23);
        let bad = meta.iter().filter(|m| m[2] != -1.0).count();
        assert_eq!(bad, 0, "texels of a new history with a stamp");
    }
}

/// The temporal step equals the CPU's over three frames of random G-buffers: the first
/// without history, the second from the same camera (the history kept where nothing
/// moved; the moved patches reprojected by their motion), the third from a moved camera
/// (reprojected, partly disoccluded); the CPU is given the GPU's own spatial output and
/// previous history, so the step is checked alone.
#[test]
fn temporal_accumulation_matches_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(43);
    let (w, h) = (97usize, 61usize);
    let mut rig = FilterRig::new(&ctx, 44, w, h);
    let max_frames = 6;
    // The previous frame: its view, camera, accumulated reflection and meta.
    type Past = (glam::Mat4, Vec3, Vec<[f32; 4]>, Vec<[f32; 4]>);
    let mut previous: Option<Past> = None;
    let mut kept = 0usize;
    for k in 0..3u32 {
        let mut frame = speculum::gpu_types::FrameUniforms {
            frame_index: 10 + k,
            ..rig.frame
        };
        if k == 2 {
            let moved = speculum::scene::camera::Camera {
                position: frame.camera_pos.truncate() + Vec3::new(0.02, 0.01, 0.0),
                ..speculum::scene::builtin::room().unwrap().camera
            };
            frame.view_proj = moved.view_proj(w as f32 / h as f32);
            frame.inv_view_proj = frame.view_proj.inverse();
            frame.camera_pos = moved.position.extend(1.0);
        }
        let noisy: Vec<[f32; 4]> = rig
            .case
            .merged
            .iter()
            .map(|c| [c[0] * rng.random_range(0.5..1.5), c[1], c[2], c[3]])
            .collect();
        rig.merged
            .write(bytemuck::cast_slice(&noisy), vk::ImageLayout::GENERAL)
            .unwrap();
        let ubo = common::frame_ubo(&ctx, &frame);
        let params = DenoiseParams {
            radius: 4,
            history: max_frames,
            reflective_min: REFLECTIVE_MIN,
        };
        rig.record(&ctx, &ubo, params, &frame);
        let spatial = read(&rig.pass.out);
        let (hist, meta) = rig.pass.history();
        let (got, got_meta) = (read(hist), read(meta));
        let past = previous.as_ref().map(|(vp, cam, c, m)| denoise::History {
            view_proj: *vp,
            camera: *cam,
            color: c,
            meta: m,
        });
        let (want, want_meta) = denoise::temporal(
            &frame,
            &rig.surfaces(),
            &spatial,
            &rig.glossy,
            past.as_ref(),
            REFLECTIVE_MIN,
            max_frames,
        );
        let mut off = 0usize;
        for i in rig.glossy.iter().map(|p| p.y as usize * w + p.x as usize) {
            let close = (0..4).all(|c| (got[i][c] - want[i][c]).abs() <= 1e-4 * want[i][c].abs() + 1e-5);
            off += !(close && got_meta[i][1] == want_meta[i][1] && got_meta[i][2] == want_meta[i][2]) as usize;
            if k > 0 && want_meta[i][1] > 1.0 {
                kept += 1;
            }
        }
        let n = rig.glossy.len();
        assert!(
            off * 200 <= n,
            "frame {k}: {off} of {n} glossy pixels differ from the CPU"
        );
        previous = Some((frame.view_proj, frame.camera_pos.truncate(), got, got_meta));
    }
    assert!(kept > rig.glossy.len() / 2, "only {kept} pixels kept their history");
}

/// Provenance tells glossy pixels apart: on `glossy` with glossy reflections, the glossy
/// pixels SSR answered are a lighter blue, and those the tracer answered a lighter pink,
/// than the mirror pixels of either source; with glossy off, none is.
#[test]
fn provenance_shows_glossy_pixels() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::by_name("glossy").unwrap().unwrap();
    let (w, h) = (240usize, 135usize);
    let mut counts = Vec::new();
    for glossy in [true, false] {
        let settings = speculum::Settings {
            width: w as u32,
            height: h as u32,
            mode: speculum::settings::Mode::Provenance,
            glossy,
            ..Default::default()
        };
        let mut r = speculum::renderer::Renderer::new(&ctx, &scene, &settings).unwrap();
        r.render_frame().unwrap();
        let ldr = r.read_output().unwrap();
        let albedo = r.read_target(&r.lighting.gbuffer.out.albedo).unwrap();
        let maps = r.reflection_maps().unwrap();
        let frame = speculum::gpu_types::FrameUniforms {
            glossy: glossy as u32,
            ..*r.uniforms()
        };
        let (mut light, mut glossy_pixels) = (0usize, 0usize);
        for i in 0..w * h {
            let is_glossy = maps.reflective[i] && glossy::is_glossy(&frame, albedo[4 * i + 3] as f32 / 255.0);
            let (rr, g, b) = (ldr[4 * i] as i32, ldr[4 * i + 1] as i32, ldr[4 * i + 2] as i32);
            // The lighter tints lift green to at least 0.45 of the strongest channel.
            let lighter = maps.reflective[i] && 100 * g >= 40 * rr.max(b);
            glossy_pixels += is_glossy as usize;
            light += lighter as usize;
            assert_eq!(
                lighter,
                is_glossy,
                "glossy {glossy}, pixel {i}: {:?}",
                &ldr[4 * i..4 * i + 3]
            );
        }
        counts.push((glossy_pixels, light));
    }
    assert!(counts[0].0 > w * h / 10, "{counts:?}");
    assert_eq!(counts[1], (0, 0), "glossy off: no glossy pixels");
}
