//! GPU kernels against their CPU references on random inputs.
//!
//! Tolerances: `compose` writes 8-bit values; Vulkan allows UNORM conversion to differ
//! from round-to-nearest, and GPU pow/exp differ from libm in the last bits, so a
//! channel may differ by 1 LSB. `light.direct` is compared in f32 with a relative
//! tolerance of 2e-3 plus 2e-4 absolute (GPU `pow`/`normalize` are not correctly rounded;
//! the sharp specular lobe amplifies their error).

mod common;

use ash::vk;
use glam::{IVec2, Vec3, Vec4Swizzles};
use rand::Rng;
use speculum::cpu_ref::{self, shading};
use speculum::passes::compose::ComposePass;
use speculum::passes::gbuffer::GBuffer;
use speculum::passes::light_direct::LightDirectPass;
use speculum::shader_defines::MATERIAL_NONE;
use speculum::vk::{barrier, Image};

const POISON_F32: f32 = -12345.0;

/// compose: random HDR texels (including negatives, zeros, values far above 1, and
/// NaN, infinities and values whose square overflows f32) tonemap to exactly the CPU
/// reference, within 1 LSB: NaN black, the overflowing ones white.
#[test]
fn compose_matches_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(1);
    let extent = vk::Extent2D { width: 67, height: 45 }; // not a multiple of the workgroup
    let exposure = 1.7;
    let texels: Vec<[f32; 4]> = (0..extent.width * extent.height)
        .map(|_| {
            if rng.random_bool(0.05) {
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
        .collect();
    let hdr = Image::new(
        &ctx,
        "test.hdr",
        extent,
        speculum::passes::light_direct::FORMAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    hdr.write(bytemuck::cast_slice(&texels), vk::ImageLayout::GENERAL)
        .unwrap();
    let pass = ComposePass::new(&ctx, extent).unwrap();
    // Poison the output so that unwritten texels cannot pass.
    let poison = vec![0x5au8; (extent.width * extent.height * 4) as usize];
    pass.ldr.write(&poison, vk::ImageLayout::GENERAL).unwrap();
    // Reflection inputs are bound but unused in the plain mode tested here.
    let normal = Image::new(
        &ctx,
        "test.normal",
        extent,
        vk::Format::R16G16B16A16_SFLOAT,
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    normal
        .write(
            &vec![0u8; (extent.width * extent.height * 8) as usize],
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        )
        .unwrap();
    let inputs = speculum::passes::compose::ComposeInputs {
        hdr: &hdr,
        reflection: &hdr,
        normal: &normal,
    };
    ctx.one_shot(|cmd| {
        pass.record(cmd, &inputs, exposure, speculum::passes::compose::ComposeMode::Plain);
    })
    .unwrap();
    let gpu = pass.ldr.read(vk::ImageLayout::GENERAL).unwrap();
    let mut worst = 0i32;
    for (i, t) in texels.iter().enumerate() {
        let want = cpu_ref::compose::tonemap(*t, exposure);
        for c in 0..4 {
            let d = (gpu[i * 4 + c] as i32 - want[c] as i32).abs();
            worst = worst.max(d);
            assert!(
                d <= 1,
                "texel {i} channel {c}: gpu {} cpu {} (input {:?})",
                gpu[i * 4 + c],
                want[c],
                t
            );
        }
    }
    println!("compose: worst difference {worst} LSB");
    common::assert_no_validation_messages(&ctx);
}

/// light.direct: a random G-buffer (depths, normals, albedo, roughness, reflectivity,
/// sky pixels) and a random shadow map shade like the CPU reference.
#[test]
fn light_direct_matches_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(2);
    let scene = speculum::scene::builtin::room().unwrap();
    let settings = speculum::Settings {
        width: 45,
        height: 37,
        shadow_map_size: 64,
        pcf_radius: 2,
        ..Default::default()
    };
    settings.validate().unwrap();
    let frame = speculum::renderer::frame_uniforms(&scene, &settings);
    let extent = vk::Extent2D {
        width: settings.width,
        height: settings.height,
    };
    let n = (extent.width * extent.height) as usize;

    let common::RandomGBuffer {
        depth,
        normal,
        normal_bytes,
        material,
    } = common::random_gbuffer(&mut rng, n);
    let albedo: Vec<u8> = (0..n * 4).map(|_| rng.random()).collect();
    let shadow: Vec<f32> = (0..64 * 64).map(|_| rng.random_range(0.0..1.0f32)).collect();

    let gb = GBuffer::new(&ctx, extent).unwrap();
    let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    gb.depth.write(bytemuck::cast_slice(&depth), ro).unwrap();
    gb.normal.write(&normal_bytes, ro).unwrap();
    gb.albedo.write(&albedo, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&material), ro).unwrap();
    let shadow_map = Image::new(
        &ctx,
        "test.shadow",
        vk::Extent2D { width: 64, height: 64 },
        vk::Format::D32_SFLOAT,
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    shadow_map.write(bytemuck::cast_slice(&shadow), ro).unwrap();
    let ubo = common::frame_ubo(&ctx, &frame);
    let pass = LightDirectPass::new(&ctx, extent).unwrap();
    pass.lit
        .write(
            bytemuck::cast_slice(&vec![[POISON_F32; 4]; n]),
            vk::ImageLayout::GENERAL,
        )
        .unwrap();
    ctx.one_shot(|cmd| {
        pass.record(cmd, &ubo, &gb, &shadow_map);
        // RAW: the readback copy sees the shader's writes.
        let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
        barrier::record(&ctx.device, cmd, &[b], &[]);
    })
    .unwrap();
    let gpu: Vec<[f32; 4]> = bytemuck::cast_slice(&pass.lit.read(vk::ImageLayout::GENERAL).unwrap()).to_vec();

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
                let a = |c: usize| albedo[i * 4 + c] as f32 / 255.0;
                let vis = shading::shadow_visibility(&frame, &map, w);
                if vis < 1.0 {
                    shadowed += 1;
                }
                let nrm = Vec3::new(normal[i][0], normal[i][1], normal[i][2]).normalize();
                shading::shade_direct(
                    &frame,
                    Vec3::new(a(0), a(1), a(2)),
                    a(3),
                    normal[i][3],
                    nrm,
                    to_camera.normalize(),
                    vis,
                )
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
    common::assert_no_validation_messages(&ctx);
}
