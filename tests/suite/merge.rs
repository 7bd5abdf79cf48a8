//! reflect.merge (source selection + seam-band blur) against its CPU reference on
//! random inputs. Tolerance: the blur's Gaussian weights use GPU `exp`, which is not
//! correctly rounded, so colours may differ by 1e-5 relative (+1e-6 absolute); the
//! source labels in alpha must match exactly.

use crate::common;

use ash::vk;
use rand::Rng;
use speculum::cpu_ref::{self, merge};
use speculum::passes::reflect_merge::{BlurParams, MergeInputs, MergeParams, MergePass};
use speculum::passes::GBuffer;
use speculum::shader_defines::{FAIL_BLEND, FAIL_UNTRACED, MATERIAL_NONE, SOURCE_NONE};
use speculum::vk::{barrier, Image};

const POISON: [f32; 4] = [-12345.0, -12345.0, -12345.0, 99.0];

/// Every pixel's source and (seam-blurred) colour equal the CPU's: SSR, RT, and faded
/// SSR hits blended with RT by confidence; several radii and bands; skipped tiles left
/// untouched; and the `ssr` mode (failed pixels get nothing, faded hits fade out).
#[test]
fn merge_and_seam_blur_match_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(41);
    let (w, h) = (157usize, 83usize); // more than one BLUR_LINE segment on both axes
    let n = w * h;
    let extent = vk::Extent2D {
        width: w as u32,
        height: h as u32,
    };
    let settings = speculum::Settings {
        width: w as u32,
        height: h as u32,
        ..Default::default()
    };
    let scene = speculum::scene::builtin::room().unwrap();
    let frame = speculum::renderer::frame_uniforms(&scene, &settings);
    let reflective_min = 0.3;

    let normal: Vec<[f32; 4]> = (0..n).map(|_| [0.0, 1.0, 0.0, rng.random_range(0.0..1.0)]).collect();
    let normal_bytes = cpu_ref::f32_to_rgba16f(&normal);
    let normal = speculum::gpu_types::rgba16f_to_f32(&normal_bytes); // what the GPU reads
    let material = common::random_material_ids(&mut rng, n, 0.1, 5);
    // Failed pixels in blobs of varying density, so seams are both long and ragged,
    // beside regions of one source only (SSR on the left, RT at the bottom) whose tiles
    // the blur must skip without changing them.
    let fail: Vec<u32> = (0..n)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let p = if x < 37 {
                0.0
            } else if y > 58 {
                1.0
            } else if (x / 23 + y / 17) % 2 == 0 {
                0.15
            } else {
                0.85
            };
            // Any reason, FAIL_BLEND (a faded SSR hit, blended by confidence) and
            // untraced ones (SSR's answer kept) included.
            let reasons = [1u32, 2, 4, 8, 16, 32, FAIL_BLEND, FAIL_BLEND, 16 | FAIL_UNTRACED];
            if rng.random_bool(p) {
                reasons[rng.random_range(0..reasons.len())]
            } else {
                0
            }
        })
        .collect();
    let colour = |rng: &mut rand::rngs::StdRng| -> Vec<[f32; 4]> {
        (0..n)
            .map(|_| {
                [
                    rng.random_range(0.0..4.0),
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..0.5),
                    rng.random_range(0.3..1.0), // SSR confidence (unused in RT colour)
                ]
            })
            .collect()
    };
    let (ssr, rt) = (colour(&mut rng), colour(&mut rng));

    let gb = GBuffer::new(&ctx, extent).unwrap();
    let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let general = vk::ImageLayout::GENERAL;
    gb.normal.write(&normal_bytes, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&material), ro).unwrap();
    // Roughness in the albedo's alpha: mirror, glossy and rough pixels side by side (the
    // seam blur's range is wider around glossy ones).
    let albedo: Vec<u8> = (0..n).flat_map(|_| [128, 128, 128, rng.random::<u8>()]).collect();
    gb.albedo.write(&albedo, ro).unwrap();
    let glossy: Vec<bool> = (0..n)
        .map(|i| cpu_ref::glossy::is_glossy(&frame, albedo[4 * i + 3] as f32 / 255.0))
        .collect();
    assert!(
        glossy.iter().any(|&g| g) && glossy.iter().any(|&g| !g),
        "both kinds of pixel"
    );
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST;
    let image = |name: &str, format: vk::Format, data: &[u8]| {
        let i = Image::new(&ctx, name, extent, format, storage).unwrap();
        i.write(data, general).unwrap();
        i
    };
    let mask_img = image("test.mask", vk::Format::R32_UINT, bytemuck::cast_slice(&fail));
    let rgba = vk::Format::R32G32B32A32_SFLOAT;
    let ssr_img = image("test.ssr", rgba, bytemuck::cast_slice(&ssr));
    let rt_img = image("test.rt", rgba, bytemuck::cast_slice(&rt));
    let ubo = common::frame_ubo(&ctx, &frame);
    let pass = MergePass::new(&ctx, extent).unwrap();

    for (radius, band, rt_enabled) in [
        (3, 3, true),
        (5, 2, true),
        (1, 9, true),
        (16, 64, true),
        (0, 3, true),
        (3, 3, false),
    ] {
        let poison = vec![POISON; n];
        pass.out.write(bytemuck::cast_slice(&poison), general).unwrap();
        pass.scratch().write(bytemuck::cast_slice(&poison), general).unwrap();
        for b in pass.tile_buffers() {
            b.write(&vec![0xcdu8; b.size as usize]).unwrap();
        }
        ctx.one_shot(|cmd| {
            let inputs = MergeInputs {
                frame: &ubo,
                gbuffer: &gb,
                fail_mask: &mask_img,
                ssr: &ssr_img,
                rt: &rt_img,
            };
            let params = MergeParams {
                rt_enabled,
                reflective_min,
                blur: BlurParams { radius, band },
            };
            pass.record(cmd, &inputs, params);
            // RAW: the readback copy sees the shader's writes.
            let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
            barrier::record(&ctx.device, cmd, &[b], &[]);
        })
        .unwrap();
        let gpu: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&pass.out.read(general).unwrap());

        let merged: Vec<[f32; 4]> = (0..n)
            .map(|i| {
                let reflective = material[i] != MATERIAL_NONE && normal[i][3] > reflective_min;
                let block = ((i / w) & !1) * w + ((i % w) & !1);
                merge::merge(fail[i], ssr[i], rt[i], reflective, rt_enabled, (fail[block], rt[block]))
            })
            .collect();
        let (r, b) = (radius as i32, band as i32);
        let want = if radius == 0 {
            merged.clone()
        } else {
            let horizontal = merge::seam_blur(&merged, &glossy, w, h, [1, 0], r, b);
            merge::seam_blur(&horizontal, &glossy, w, h, [0, 1], r, b)
        };
        let mut blurred = 0;
        for i in 0..n {
            assert_eq!(
                gpu[i][3], want[i][3],
                "pixel {i}: source (radius {radius}, band {band})"
            );
            for c in 0..3 {
                let tol = want[i][c].abs() * 1e-5 + 1e-6;
                assert!(
                    (gpu[i][c] - want[i][c]).abs() <= tol,
                    "pixel ({}, {}) channel {c}: gpu {} cpu {} (radius {radius}, band {band}, rt {rt_enabled})",
                    i % w,
                    i / w,
                    gpu[i][c],
                    want[i][c]
                );
            }
            blurred += (want[i] != merged[i]) as usize;
        }
        if radius > 0 {
            // The tiles the blur works on: activity per tile and the list, exactly.
            let (active, listed) = pass.read_tiles().unwrap();
            let want_active = merge::active_tiles(&merged, w, h, band);
            assert_eq!(active, want_active, "tile activity (band {band})");
            let want_listed: Vec<u32> = (0..want_active.len() as u32)
                .filter(|&t| want_active[t as usize])
                .collect();
            assert_eq!(listed, want_listed, "listed tiles (band {band})");
            // Both kinds of tile must occur for the comparison to mean anything (a band
            // of 64 reaches every tile of this image from a seam).
            let (n_listed, n_tiles) = (listed.len(), active.len());
            if rt_enabled {
                assert!(n_listed > 0, "no tile active (band {band})");
            }
            if band < 16 {
                assert!(n_listed < n_tiles, "every tile active (band {band})");
            }
        }
        let none = want.iter().filter(|p| p[3] as u32 == SOURCE_NONE).count();
        println!("radius {radius} band {band} rt {rt_enabled}: {blurred} pixels blurred, {none} without reflection");
        // The inputs must exercise what is compared: seams where both sources exist.
        assert!(none > n / 20, "some pixels have no reflection ({none})");
        if radius > 0 && rt_enabled {
            assert!(blurred > n / 10, "the blur should change many pixels ({blurred})");
        } else {
            assert_eq!(blurred, 0, "no seams, or no blur: nothing changes");
        }
    }
}
