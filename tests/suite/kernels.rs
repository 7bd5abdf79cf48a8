//! GPU kernels against their CPU references on random inputs.
//!
//! Tolerances: `compose` writes 8-bit values; Vulkan allows UNORM conversion to differ
//! from round-to-nearest, and GPU pow/exp differ from libm in the last bits, so a
//! channel may differ by 1 LSB. `light.direct` is compared in f32 with a relative
//! tolerance of 2e-3 plus 2e-4 absolute (GPU `pow`/`normalize` are not correctly rounded;
//! the sharp specular lobe amplifies their error).

use crate::common;

use ash::vk;
use glam::{IVec2, Vec3, Vec4Swizzles};
use rand::Rng;
use speculum::cpu_ref::{self, shading};
use speculum::passes::compose::ComposePass;
use speculum::passes::light_direct::{LightDirectPass, Sun};
use speculum::passes::shadow_trace;
use speculum::passes::GBuffer;
use speculum::shader_defines::MATERIAL_NONE;
use speculum::vk::{barrier, Image};

const POISON_F32: f32 = -12345.0;

/// compose: random HDR texels (including negatives, zeros, values far above 1, and
/// NaN, infinities and values whose square overflows f32) tonemap to exactly the CPU
/// reference, within 1 LSB: NaN black, the overflowing ones white. In the reflecting
/// mode a random G-buffer (normals, base colours, reflectivity, metallic materials,
/// sky pixels) weighs a random reflection by reflectivity x Fresnel first.
#[test]
fn compose_matches_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(1);
    let extent = vk::Extent2D { width: 67, height: 45 }; // not a multiple of the workgroup
    let n = (extent.width * extent.height) as usize;
    let exposure = 1.7;
    let mut random_hdr = |special_too: bool| -> Vec<[f32; 4]> {
        (0..n)
            .map(|_| {
                if special_too && rng.random_bool(0.05) {
                    let special = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30, 3e19, f32::MAX];
                    let pick = |rng: &mut rand::rngs::StdRng| special[rng.random_range(0..special.len())];
                    return [pick(&mut rng), pick(&mut rng), rng.random_range(0.0..1.0), 1.0];
                }
                let scale = if rng.random_bool(0.1) { 40.0 } else { 2.0 };
                [
                    rng.random_range(-0.1..1.0) * scale,
                    rng.random_range(0.0..1.0) * scale,
                    rng.random_range(0.0..1.0f32).powi(3),
                    1.0,
                ]
            })
            .collect()
    };
    let texels = random_hdr(true);
    let reflected: Vec<[f32; 4]> = random_hdr(false)
        .into_iter()
        .map(|t| [t[0].abs(), t[1], t[2], 2.0])
        .collect();
    let storage = |name: &str, data: &[[f32; 4]]| {
        let img = Image::new(
            &ctx,
            name,
            extent,
            speculum::passes::light_direct::FORMAT,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
        )
        .unwrap();
        img.write(bytemuck::cast_slice(data), vk::ImageLayout::GENERAL).unwrap();
        img
    };
    let (hdr, reflection) = (storage("test.hdr", &texels), storage("test.reflection", &reflected));
    let mut rng = common::rng(7);
    let g = common::random_gbuffer(&mut rng, n);
    let albedo: Vec<u8> = (0..n * 4).map(|_| rng.random()).collect();
    let gb = GBuffer::new(&ctx, extent).unwrap();
    let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    gb.depth.write(bytemuck::cast_slice(&g.depth), ro).unwrap();
    gb.normal.write(&g.normal_bytes, ro).unwrap();
    gb.albedo.write(&albedo, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&g.material), ro).unwrap();
    let metallic = common::random_metallic(&mut rng, &gb, &g.material);
    let scene = speculum::scene::builtin::room().unwrap();
    let settings = speculum::Settings {
        width: extent.width,
        height: extent.height,
        ..Default::default()
    };
    let frame = speculum::renderer::frame_uniforms(&scene, &settings);
    let ubo = common::frame_ubo(&ctx, &frame);
    let pass = ComposePass::new(&ctx, extent).unwrap();
    // A random fail mask: 0 (SSR answered), single reasons and several bits at once.
    let mask: Vec<u32> = (0..n)
        .map(|_| match rng.random_range(0..4) {
            0 => 0,
            1 => 1 << rng.random_range(0..8),
            _ => rng.random_range(1..256),
        })
        .collect();
    let fail_mask = Image::storage(&ctx, "test.fail_mask", extent, speculum::passes::ssr_trace::MASK_FORMAT).unwrap();
    fail_mask
        .write(bytemuck::cast_slice(&mask), vk::ImageLayout::GENERAL)
        .unwrap();
    let reflective_min = 0.3;
    let inputs = speculum::passes::compose::ComposeInputs {
        frame: &ubo,
        hdr: &hdr,
        reflection: &reflection,
        gbuffer: &gb,
        fail_mask: &fail_mask,
        reflective_min,
    };
    use speculum::passes::compose::ComposeMode;
    for mode in [ComposeMode::Plain, ComposeMode::Reflect] {
        // Poison the output so that unwritten texels cannot pass.
        let poison = vec![0x5au8; n * 4];
        pass.out.write(&poison, vk::ImageLayout::GENERAL).unwrap();
        ctx.one_shot(|cmd| pass.record(cmd, &inputs, exposure, mode)).unwrap();
        let gpu = pass.out.read(vk::ImageLayout::GENERAL).unwrap();
        let mut worst = 0i32;
        for (i, t) in texels.iter().enumerate() {
            let mut hdr = *t;
            if mode == ComposeMode::Reflect && g.material[i] != MATERIAL_NONE {
                let p = IVec2::new((i % extent.width as usize) as i32, (i / extent.width as usize) as i32);
                let w = shading::world_from_depth(&frame, p, g.depth[i]);
                let v = (frame.camera_pos.xyz() - w).normalize();
                let nrm = Vec3::new(g.normal[i][0], g.normal[i][1], g.normal[i][2]).normalize();
                let base = cpu_ref::albedo_texel(&albedo[4 * i..4 * i + 4]).0;
                let weight = shading::reflection_weight(base, metallic[i], g.normal[i][3], nrm, v);
                for c in 0..3 {
                    hdr[c] += weight[c] * reflected[i][c];
                }
            }
            let want = cpu_ref::compose::tonemap(hdr, exposure);
            for c in 0..4 {
                let d = (gpu[i * 4 + c] as i32 - want[c] as i32).abs();
                worst = worst.max(d);
                assert!(
                    d <= 1,
                    "{mode:?} texel {i} channel {c}: gpu {} cpu {} (input {:?})",
                    gpu[i * 4 + c],
                    want[c],
                    t
                );
            }
        }
        println!("compose {mode:?}: worst difference {worst} LSB");
    }
    // The fail-mask view paints exactly what `--fail-mask` images (the CPU) do.
    let poison = vec![0x5au8; n * 4];
    pass.out.write(&poison, vk::ImageLayout::GENERAL).unwrap();
    ctx.one_shot(|cmd| pass.record(cmd, &inputs, exposure, ComposeMode::FailMask))
        .unwrap();
    let gpu = pass.out.read(vk::ImageLayout::GENERAL).unwrap();
    let maps = speculum::reflection_maps::ReflectionMaps {
        reflective: (0..n)
            .map(|i| g.material[i] != MATERIAL_NONE && g.normal[i][3] > reflective_min)
            .collect(),
        mask,
        traced: true,
    };
    let reflective = maps.reflective.iter().filter(|r| **r).count();
    assert!(
        reflective > n / 4 && reflective < n,
        "{reflective} of {n} pixels reflect"
    );
    assert_eq!(gpu, maps.fail_mask_rgba(), "fail-mask view");
}

/// light.direct: a random G-buffer (depths, normals, albedo, roughness, reflectivity,
/// sky pixels) and a random shadow map shade like the CPU reference; and so they do
/// with a random visibility image in the map's place (shadows `rays` and `hybrid`).
#[test]
fn light_direct_matches_cpu_reference() {
    for traced in [false, true] {
        light_direct_case(traced);
    }
}

fn light_direct_case(traced: bool) {
    let ctx = common::context();
    let mut rng = common::rng(2);
    let settings = speculum::Settings {
        width: 45,
        height: 37,
        shadow_map_size: 64,
        pcf_radius: 2,
        ..Default::default()
    };
    let (frame, extent) = common::room_frame(&settings);
    let n = (extent.width * extent.height) as usize;
    let g = common::random_gbuffer(&mut rng, n);
    let (depth, normal, material) = (&g.depth, &g.normal, &g.material);
    let albedo: Vec<u8> = (0..n * 4).map(|_| rng.random()).collect();
    let shadow: Vec<f32> = (0..64 * 64).map(|_| rng.random_range(0.0..1.0f32)).collect();

    let gb = common::upload_gbuffer(&ctx, extent, &g, Some(&albedo));
    let shadow_map = common::shadow_map_image(&ctx, 64, &shadow);
    let ubo = common::frame_ubo(&ctx, &frame);
    let metallic = common::random_metallic(&mut rng, &gb, material);
    let pass = LightDirectPass::new(&ctx, extent).unwrap();
    pass.out
        .write(
            bytemuck::cast_slice(&vec![[POISON_F32; 4]; n]),
            vk::ImageLayout::GENERAL,
        )
        .unwrap();
    let visibility: Vec<f32> = (0..n).map(|_| rng.random_range(0.0..1.0f32)).collect();
    let visibility_image = Image::storage(&ctx, "test.visibility", extent, shadow_trace::VISIBILITY_FORMAT).unwrap();
    visibility_image
        .write(bytemuck::cast_slice(&visibility), vk::ImageLayout::GENERAL)
        .unwrap();
    let sun = Sun {
        map: &shadow_map,
        visibility: &visibility_image,
        traced,
    };
    ctx.one_shot(|cmd| {
        pass.record(cmd, &ubo, &gb, sun);
        // RAW: the readback copy sees the shader's writes.
        let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
        barrier::record(&ctx.device, cmd, &[b], &[]);
    })
    .unwrap();
    let gpu: Vec<[f32; 4]> = bytemuck::cast_slice(&pass.out.read(vk::ImageLayout::GENERAL).unwrap()).to_vec();
    // Under the map, light.direct writes back the visibility it shaded with.
    let gpu_visibility: Vec<f32> =
        bytemuck::pod_collect_to_vec(&visibility_image.read(vk::ImageLayout::GENERAL).unwrap());

    let map = shading::ShadowMap {
        size: 64,
        depth: &shadow,
    };
    let mut shadowed = 0;
    let mut worst = 0f32;
    for y in 0..extent.height as i32 {
        for x in 0..extent.width as i32 {
            let i = (y * extent.width as i32 + x) as usize;
            let p = IVec2::new(x, y);
            let w = shading::world_from_depth(&frame, p, depth[i]);
            let to_camera = frame.camera_pos.xyz() - w;
            let want = if material[i] == MATERIAL_NONE {
                shading::sky(&frame, -to_camera.normalize())
            } else {
                let (base, roughness) = cpu_ref::albedo_texel(&albedo[4 * i..4 * i + 4]);
                let vis = if traced {
                    visibility[i]
                } else {
                    shading::shadow_visibility(&frame, &map, w)
                };
                let written = if traced { visibility[i] } else { vis };
                assert!(
                    (gpu_visibility[i] - written).abs() <= 1e-4,
                    "pixel {p}: visibility {} vs {written}",
                    gpu_visibility[i]
                );
                if vis < 1.0 {
                    shadowed += 1;
                }
                let nrm = Vec3::new(normal[i][0], normal[i][1], normal[i][2]).normalize();
                let surface = shading::Surface {
                    base,
                    roughness,
                    reflectivity: normal[i][3],
                    metallic: metallic[i],
                };
                shading::shade_direct(&frame, surface, nrm, to_camera.normalize(), vis)
            };
            let got = Vec3::new(gpu[i][0], gpu[i][1], gpu[i][2]);
            let err = (got - want).abs();
            let tol = want.abs() * 2e-3 + 2e-4;
            worst = worst.max((err / tol).max_element());
            assert!(
                err.cmple(tol).all(),
                "pixel {p}: gpu {got} cpu {want} (material {})",
                material[i]
            );
            assert_eq!(gpu[i][3], 1.0);
        }
    }
    assert!(
        shadowed > n / 4,
        "the random shadow map should shadow many pixels ({shadowed})"
    );
    println!("light.direct: worst error {worst:.3} of tolerance");
}
