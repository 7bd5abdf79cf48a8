//! The shadow compositor: `shadow.classify` against its CPU reference on random
//! G-buffers; on real frames the hybrid answers like the all-rays frame, traces only
//! where the shadow map is unsure, and traces exactly what `rays` would there. (The
//! frame's visibility against the CPU's, rays included: tests/suite/rt_reflect.rs.)

use crate::common;

use ash::vk;
use glam::{IVec2, Vec3};
use rand::Rng;
use speculum::cpu_ref::{shading, shadows};
use speculum::passes::shadow_trace::ShadowTracePass;
use speculum::settings::Shadows;
use speculum::shader_defines::{MATERIAL_NONE, SHADOW_ALL, SHADOW_EDGE, SHADOW_GRAZING, SHADOW_NEAR};
use speculum::vk::barrier;
use speculum::{Renderer, Settings};

/// A random G-buffer over a shadow map of random occluder rectangles on an empty
/// (far) map: sure-lit, sure-dark, edge, near-the-compare and grazing pixels all occur.
/// The mask equals the CPU's and so does the visibility (-1 where listed), but for
/// compares on a threshold's last bit (at most 1 in 200 pixels).
#[test]
fn shadow_classify_matches_cpu_on_random_gbuffers() {
    let ctx = common::context();
    let mut rng = common::rng(24);
    let settings = Settings {
        width: 61,
        height: 47,
        shadow_map_size: 64,
        pcf_radius: 1,
        shadow_band: 0.01,
        ..Default::default()
    };
    let (frame, extent) = common::room_frame(&settings);
    let n = (extent.width * extent.height) as usize;
    let g = common::random_gbuffer(&mut rng, n);
    let (depth, normal, material) = (&g.depth, &g.normal, &g.material);
    let size = settings.shadow_map_size as usize;
    let mut shadow = vec![1.0f32; size * size];
    for _ in 0..12 {
        let (x0, y0) = (rng.random_range(0..size), rng.random_range(0..size));
        let (x1, y1) = (
            (x0 + rng.random_range(4..24)).min(size),
            (y0 + rng.random_range(4..24)).min(size),
        );
        let d = rng.random_range(0.0..1.0f32);
        for y in y0..y1 {
            shadow[y * size + x0..y * size + x1].fill(d);
        }
    }
    let gb = common::upload_gbuffer(&ctx, extent, &g, None);
    let shadow_map = common::shadow_map_image(&ctx, size as u32, &shadow);
    let ubo = common::frame_ubo(&ctx, &frame);
    let map = shading::ShadowMap {
        size: size as u32,
        depth: &shadow,
    };
    let pass = ShadowTracePass::new(&ctx, extent).unwrap();
    let general = vk::ImageLayout::GENERAL;
    for mode in [Shadows::Hybrid, Shadows::Rays] {
        pass.out
            .mask
            .write(bytemuck::cast_slice(&vec![0xdead_beefu32; n]), general)
            .unwrap();
        pass.out
            .visibility
            .write(bytemuck::cast_slice(&vec![-7.0f32; n]), general)
            .unwrap();
        ctx.one_shot(|cmd| {
            pass.classify(cmd, &ubo, &gb, &shadow_map, mode);
            let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
            barrier::record(&ctx.device, cmd, &[b], &[]);
        })
        .unwrap();
        let mask: Vec<u32> = bytemuck::pod_collect_to_vec(&pass.out.mask.read(general).unwrap());
        let vis: Vec<f32> = bytemuck::pod_collect_to_vec(&pass.out.visibility.read(general).unwrap());
        let (mut differ, mut seen, mut sure) = (0usize, 0u32, [0usize; 2]);
        for i in 0..n {
            let p = IVec2::new((i % extent.width as usize) as i32, (i / extent.width as usize) as i32);
            let nrm = Vec3::new(normal[i][0], normal[i][1], normal[i][2]);
            let want = shadows::classify(&frame, &map, mode, p, (depth[i], nrm, material[i]));
            differ += ((mask[i], vis[i]) != want) as usize;
            seen |= mask[i];
            let lit = material[i] != MATERIAL_NONE && nrm.normalize().dot(frame.light_dir.truncate()) > 0.0;
            if lit && mask[i] == 0 {
                sure[(vis[i] == 1.0) as usize] += 1;
            }
        }
        println!("{mode:?}: {differ} of {n} pixels differ; reasons seen {seen:#x}; sure dark, lit {sure:?}");
        assert!(
            differ * 200 <= n,
            "{mode:?}: {differ} of {n} pixels differ from the CPU's"
        );
        if mode == Shadows::Hybrid {
            for bit in [SHADOW_EDGE, SHADOW_NEAR, SHADOW_GRAZING] {
                assert!(seen & bit != 0, "reason {bit} never occurs");
            }
            assert!(sure[0] > n / 50 && sure[1] > n / 50, "sure dark, lit: {sure:?}");
        } else {
            assert_eq!(seen, SHADOW_ALL);
        }
    }
}

/// Renders `scene` under each of `shadows` and returns each frame's shadow maps.
fn frames(
    scene: &speculum::scene::Scene,
    settings: &Settings,
    shadows: &[Shadows],
) -> Vec<speculum::shadow_maps::ShadowMaps> {
    let ctx = common::context();
    shadows
        .iter()
        .map(|&s| {
            let settings = Settings {
                shadows: s,
                ..settings.clone()
            };
            let mut r = Renderer::new(&ctx, scene, &settings).unwrap();
            r.render_frame().unwrap();
            r.shadow_maps().unwrap()
        })
        .collect()
}

/// On `room` the hybrid's visibility equals the all-rays frame's on at least 99.5% of
/// the lit pixels while it traces at most a quarter of them, and where it traces it
/// gets exactly what `rays` got (the same ray from the same G-buffer).
#[test]
fn hybrid_shadows_match_rays_on_room() {
    let settings = Settings {
        width: 480,
        height: 270,
        ..Default::default()
    };
    let room = speculum::scene::load("room").unwrap();
    let [hybrid, rays] = &frames(&room, &settings, &[Shadows::Hybrid, Shadows::Rays])[..] else {
        unreachable!()
    };
    assert_eq!(hybrid.lit, rays.lit, "the same G-buffer");
    let lit: Vec<usize> = (0..hybrid.lit.len()).filter(|&i| hybrid.lit[i]).collect();
    let traced = lit.iter().filter(|&&i| hybrid.mask[i] != 0).count();
    let agree = lit
        .iter()
        .filter(|&&i| hybrid.visibility[i] == rays.visibility[i])
        .count();
    for &i in lit.iter().filter(|&&i| hybrid.mask[i] != 0) {
        assert_eq!(hybrid.visibility[i], rays.visibility[i], "traced pixel {i}");
    }
    let (n, share, agreement) = (
        lit.len(),
        traced as f64 / lit.len() as f64,
        agree as f64 / lit.len() as f64,
    );
    println!(
        "room: {n} lit pixels, hybrid traced {:.1}%, agrees with rays on {:.3}%",
        100.0 * share,
        100.0 * agreement
    );
    assert!(n > hybrid.lit.len() / 2, "{n} lit pixels");
    assert!(agreement >= 0.995, "agreement {agreement}");
    assert!(share <= 0.25, "traced share {share}");
    assert!(traced > 0, "nothing traced: the hybrid is the map");
}

/// What the hybrid is for: a low sun and a shadow map without depth bias (neither the
/// compare's nor the raster's) shade `room`'s lit surfaces with acne, so the map's
/// visibility is wrong on many lit pixels; the hybrid sees the doubt (texels that
/// disagree or sit on the compare, a grazing sun) and traces them, and its visibility
/// is the rays' on all but a few. (The rays' visibility equals the CPU's:
/// tests/suite/rt_reflect.rs.)
#[test]
fn hybrid_shadows_fix_what_the_map_gets_wrong() {
    let mut room = speculum::scene::load("room").unwrap();
    room.light.direction = Vec3::new(0.8, 0.25, 0.3).normalize();
    let settings = Settings {
        width: 320,
        height: 180,
        shadow_bias: 0.0,
        shadow_slope_bias: 0.0,
        ..Default::default()
    };
    let all = [Shadows::Map, Shadows::Hybrid, Shadows::Rays];
    let [map, hybrid, rays] = &frames(&room, &settings, &all)[..] else {
        unreachable!()
    };
    let lit: Vec<usize> = (0..rays.lit.len()).filter(|&i| rays.lit[i]).collect();
    let wrong = |m: &speculum::shadow_maps::ShadowMaps| {
        let n = lit
            .iter()
            .filter(|&&i| (m.visibility[i] - rays.visibility[i]).abs() > 0.5)
            .count();
        n as f64 / lit.len() as f64
    };
    let (map_wrong, hybrid_wrong) = (wrong(map), wrong(hybrid));
    let traced = hybrid.stats().ray_fraction();
    println!(
        "acne: {} lit pixels; map wrong on {:.2}%, hybrid on {:.3}% ({:.1}% traced)",
        lit.len(),
        100.0 * map_wrong,
        100.0 * hybrid_wrong,
        100.0 * traced
    );
    assert!(lit.len() > rays.lit.len() / 3, "{} lit pixels", lit.len());
    assert!(map_wrong > 0.05, "the map should show acne here: wrong on {map_wrong}");
    assert!(hybrid_wrong < 0.005, "hybrid wrong on {hybrid_wrong}");
    assert!(traced < 0.9, "the hybrid should not trace everything: {traced}");
}

/// `shadow.trace` on a random G-buffer (random depths and normals over `room`: points
/// in the air, inside boxes, on walls, facing every way) through `room`'s BVH: every
/// lit pixel listed under `rays`, its visibility equal to `cpu_ref::shadows::
/// ray_visibility` but for rays through a triangle's edge (at most 1 in 500); the
/// visibility poisoned first, so a pixel the kernel missed fails.
#[test]
fn shadow_trace_matches_cpu_on_a_random_gbuffer() {
    use speculum::cpu_ref::reflect::PathScene;
    use speculum::cpu_ref::texture::TextureArray;
    use speculum::cpu_ref::trace::CpuBvh;
    use speculum::passes::shadow_trace::Kernel;
    use speculum::tracers::{Lbvh, TraceScene};
    let ctx = common::context();
    let mut rng = common::rng(25);
    let room = speculum::scene::load("room").unwrap();
    let settings = Settings {
        width: 96,
        height: 64,
        shadows: Shadows::Rays,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &room, &settings).unwrap();
    r.render_frame().unwrap();
    let frame = *r.uniforms();
    let n = (settings.width * settings.height) as usize;
    let g = common::random_gbuffer(&mut rng, n);
    let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let gb = &r.lighting.gbuffer.out;
    gb.depth.write(bytemuck::cast_slice(&g.depth), ro).unwrap();
    gb.normal.write(&g.normal_bytes, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&g.material), ro).unwrap();
    let general = vk::ImageLayout::GENERAL;
    r.lighting
        .shadow_trace
        .out
        .visibility
        .write(bytemuck::cast_slice(&vec![-7.0f32; n]), general)
        .unwrap();
    let ubo = common::frame_ubo(&ctx, &frame);
    let scene = TraceScene {
        static_bvh: Some(r.static_traceable()),
        dynamic_bvh: None,
    };
    let kernel = Kernel::<Lbvh>::new(&ctx).unwrap();
    ctx.one_shot(|cmd| {
        r.lighting
            .shadow_trace
            .classify(cmd, &ubo, gb, &r.lighting.shadow.out, Shadows::Rays);
        r.lighting.shadow_compact.record(cmd, &r.lighting.shadow_trace.out.mask);
        r.lighting
            .shadow_trace
            .trace(cmd, (&kernel, &scene), &ubo, gb, &r.lighting.shadow_compact.out);
        let b = barrier::memory(barrier::access::COMPUTE_WRITE, barrier::access::TRANSFER_READ);
        barrier::record(&ctx.device, cmd, &[b], &[]);
    })
    .unwrap();
    let vis: Vec<f32> = bytemuck::pod_collect_to_vec(&r.lighting.shadow_trace.out.visibility.read(general).unwrap());
    let listed = r.lighting.shadow_compact.out.read_count().unwrap() as usize;

    let bvh = CpuBvh::build(&room.vertices, &room.indices);
    let materials: Vec<_> = room.materials.iter().map(|m| m.gpu()).collect();
    let textures = TextureArray::new(&room.textures, speculum::scene::texture::LAYER_MAX);
    let no_map = [1.0f32];
    let map = shading::ShadowMap {
        size: 1,
        depth: &no_map,
    };
    let s = PathScene {
        frame: &frame,
        bvh: &bvh,
        vertices: &room.vertices,
        indices: &room.indices,
        uvs: &room.uvs,
        materials: &materials,
        textures: &textures,
        shadow_map: &map,
        shadows: Shadows::Rays,
        dynamic: None,
    };
    let w = settings.width as usize;
    let (mut lit, mut dark, mut differ) = (0usize, 0usize, 0usize);
    for (i, &got) in vis.iter().enumerate() {
        let nrm = Vec3::new(g.normal[i][0], g.normal[i][1], g.normal[i][2]);
        let p = IVec2::new((i % w) as i32, (i / w) as i32);
        if g.material[i] == MATERIAL_NONE || nrm.normalize().dot(frame.light_dir.truncate()) <= 0.0 {
            continue;
        }
        lit += 1;
        let want = shadows::ray_visibility(&s, p, g.depth[i], nrm);
        assert!(got == 0.0 || got == 1.0, "pixel {p}: visibility {got}");
        dark += (got == 0.0) as usize;
        differ += (got != want) as usize;
    }
    println!("shadow.trace: {lit} lit pixels, {dark} shadowed, {differ} differ from the CPU");
    // The CPU's n.l > 0 and the GPU's may part on a pixel exactly at the terminator.
    assert!(
        listed.abs_diff(lit) * 1000 <= lit,
        "rays lists every lit pixel: {listed} vs {lit}"
    );
    assert!(dark > lit / 50 && dark < lit * 9 / 10, "{dark} of {lit} shadowed");
    assert!(differ * 500 <= lit, "{differ} of {lit} differ");
}
