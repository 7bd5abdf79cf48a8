//! ssr.classify against its CPU reference on a random G-buffer, and ssr.trace's
//! coverage of the march list it dispatches over.
//!
//! Tolerance: the heading confidence goes through GPU `normalize` and matrix products
//! that are not correctly rounded, so a pixel whose confidence lies within 1e-4 of the
//! threshold may be classified either way; every other pixel must match exactly.

mod common;

use ash::vk;
use glam::IVec2;
use rand::Rng;
use speculum::cpu_ref::ssr::{self, Class};
use speculum::passes::gbuffer::GBuffer;
use speculum::passes::ssr_trace::{SsrParams, SsrPass};
use speculum::shader_defines::{FAIL_LOW_CONFIDENCE, LIST_STRIPES, SSR_LIST_WG};
use speculum::vk::{barrier, Image};

const POISON_MASK: u32 = 0xdead_beef;
const POISON_COLOR: [f32; 4] = [-12345.0, -12345.0, -12345.0, 99.0];

/// Every pixel classifies as the CPU says: not reflective (mask 0), failed on its
/// heading (FAIL_LOW_CONFIDENCE) or listed for the march, each exactly once; listed
/// pixels are left to the march (their poison stays); the dispatch arguments cover the
/// list. The `rt` variant fails every reflective pixel and lists none. Then the march
/// over the list writes every listed pixel, the list being long enough to span several
/// stripes of `list_entry` with a remainder (a chunk taken twice or never leaves
/// poison).
#[test]
fn classify_matches_cpu_and_the_march_covers_its_list() {
    let ctx = common::context();
    let mut rng = common::rng(77);
    let scene = speculum::scene::procedural::room().unwrap();
    let settings = speculum::Settings {
        width: 157,
        height: 83,
        ..Default::default()
    };
    let frame = speculum::renderer::frame_uniforms(&scene, &settings);
    let (w, h) = (settings.width as usize, settings.height as usize);
    let n = w * h;
    let extent = vk::Extent2D {
        width: w as u32,
        height: h as u32,
    };
    let g = common::random_gbuffer(&mut rng, n);
    let gb = GBuffer::new(&ctx, extent).unwrap();
    let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let general = vk::ImageLayout::GENERAL;
    gb.depth.write(bytemuck::cast_slice(&g.depth), ro).unwrap();
    gb.normal.write(&g.normal_bytes, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&g.material), ro).unwrap();
    let lit_texels: Vec<[f32; 4]> = (0..n)
        .map(|_| [rng.random_range(0.0..3.0), rng.random_range(0.0..1.0), 0.5, 1.0])
        .collect();
    let lit = Image::new(
        &ctx,
        "test.lit",
        extent,
        vk::Format::R32G32B32A32_SFLOAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    lit.write(bytemuck::cast_slice(&lit_texels), general).unwrap();
    let ubo = common::frame_ubo(&ctx, &frame);
    let pass = SsrPass::new(&ctx, extent).unwrap();
    let params = SsrParams::from_settings(&settings);

    for (mask_only, march) in [(false, false), (true, false), (false, true)] {
        let out = &pass.out;
        out.mask
            .write(bytemuck::cast_slice(&vec![POISON_MASK; n]), general)
            .unwrap();
        out.color
            .write(bytemuck::cast_slice(&vec![POISON_COLOR; n]), general)
            .unwrap();
        out.march_list
            .write(&vec![0xcdu8; out.march_list.size as usize])
            .unwrap();
        out.march_args.write(&[0xcdu8; 16]).unwrap();
        ctx.one_shot(|cmd| {
            pass.classify(cmd, &ubo, &gb, &params, mask_only);
            if march {
                pass.trace(cmd, &ubo, &gb, &lit, &params);
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
        assert_eq!(
            args[..3],
            [len.div_ceil(SSR_LIST_WG as usize) as u32, 1, 1],
            "dispatch arguments"
        );
        let mut listed = vec![false; n];
        for &e in &list_raw[..len] {
            let (x, y) = ((e & 0xffff) as usize, (e >> 16) as usize);
            assert!(x < w && y < h, "list entry {e:#x}");
            assert!(!listed[y * w + x], "pixel ({x}, {y}) listed twice");
            listed[y * w + x] = true;
        }

        let (mut counts, mut borderline) = ([0usize; 3], 0);
        for i in 0..n {
            let p = IVec2::new((i % w) as i32, (i / w) as i32);
            let texel = (g.depth[i], g.normal[i], g.material[i]);
            let (want, heading) = ssr::classify(
                &frame,
                p,
                texel,
                params.min_confidence,
                params.reflective_min,
                mask_only,
            );
            let got = if listed[i] { Class::March } else { Class::Done(mask[i]) };
            if got != want && (heading - params.min_confidence).abs() < 1e-4 {
                borderline += 1;
                continue;
            }
            assert_eq!(got, want, "pixel {p} (mask only {mask_only})");
            match want {
                Class::Done(0) => counts[0] += 1,
                Class::Done(_) => counts[1] += 1,
                Class::March => counts[2] += 1,
            }
            match (want, march) {
                (Class::Done(_), _) => assert_eq!(color[i], [0.0; 4], "pixel {p}: SSR colour"),
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
        // Every class occurs (the rt variant lists none and fails every reflective
        // pixel), so each comparison above means something.
        if mask_only {
            assert!(counts[0] > 0 && counts[1] > 0 && counts[2] == 0, "{counts:?}");
            assert_eq!(len, 0);
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
    common::assert_no_validation_messages(&ctx);
}
