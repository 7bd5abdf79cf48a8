//! `ssr.compact` against the CPU on random masks: the list (in tile order) and its count
//! exactly, and the indirect dispatch arguments.

use crate::common;

use ash::vk;
use rand::Rng;
use speculum::cpu_ref::compact::compact;
use speculum::passes::ssr_compact::CompactPass;
use speculum::passes::ssr_trace::MASK_FORMAT;
use speculum::shader_defines::{FAIL_UNTRACED, RT_LIST_WG};
use speculum::vk::Image;

#[test]
fn compaction_matches_cpu_on_random_masks() {
    let ctx = common::context();
    let mut rng = common::rng(3);
    for (w, h) in [(1u32, 1u32), (67, 45), (300, 7), (960, 540)] {
        for density in [0.0, 0.003, 0.3, 0.97, 1.0] {
            let extent = vk::Extent2D { width: w, height: h };
            // Masks carry reason bits: any nonzero value means "needs a ray", unless it
            // is marked untraced (FAIL_UNTRACED with a reason: left out).
            let mask: Vec<u32> = (0..w * h)
                .map(|_| {
                    if rng.random_bool(density) {
                        let untraced = if rng.random_bool(0.2) { FAIL_UNTRACED } else { 0 };
                        rng.random_range(1..32) | untraced
                    } else {
                        0
                    }
                })
                .collect();
            let img = Image::new(
                &ctx,
                "test.mask",
                extent,
                MASK_FORMAT,
                vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .unwrap();
            img.write(bytemuck::cast_slice(&mask), vk::ImageLayout::GENERAL)
                .unwrap();
            let pass = CompactPass::new(&ctx, speculum::passes::ssr_compact::PIPELINES, extent).unwrap();
            // Poison the outputs: stale values cannot pass.
            pass.out
                .pixels
                .write(&vec![0xcdu8; pass.out.pixels.size as usize])
                .unwrap();
            pass.out.indirect.write(&[0xcdu8; 32]).unwrap();
            ctx.one_shot(|cmd| pass.record(cmd, &img)).unwrap();
            let want = compact(&mask, w, h);
            let args: Vec<u32> = bytemuck::pod_collect_to_vec(&pass.out.indirect.read().unwrap());
            assert_eq!(
                args,
                {
                    let [x, y] = speculum::passes::list_groups((want.len() as u32).div_ceil(RT_LIST_WG));
                    let n = want.len() as u32;
                    // The dispatch's arguments and count, then the trace-rays launch's.
                    [x, y, 1, n, n, 1, 1, 0]
                },
                "{w}x{h} density {density}"
            );
            let got: Vec<u32> = bytemuck::pod_collect_to_vec(&pass.out.pixels.read().unwrap());
            assert_eq!(&got[..want.len()], &want[..], "{w}x{h} density {density}");
            let pixels = pass.out.read_pixels().unwrap();
            assert!(pixels.iter().all(|&(x, y)| {
                let m = mask[(y * w + x) as usize];
                m != 0 && m & FAIL_UNTRACED == 0
            }));
        }
    }
}

/// The list's order visits every pixel exactly once, whole 8x8 blocks at a time.
#[test]
fn list_order_is_a_permutation_of_the_pixels() {
    for (w, h) in [(1u32, 1u32), (67, 45), (8, 16), (300, 7)] {
        let order: Vec<(u32, u32)> = speculum::cpu_ref::compact::order(w, h).collect();
        let mut seen = vec![0u32; (w * h) as usize];
        for &(x, y) in &order {
            seen[(y * w + x) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1), "{w}x{h}: a pixel listed other than once");
        // The first block's pixels come first.
        let first = (w.min(8) * h.min(8)) as usize;
        assert!(order[..first].iter().all(|&(x, y)| x < 8 && y < 8), "{w}x{h}");
    }
}
