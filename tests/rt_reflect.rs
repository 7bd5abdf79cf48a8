//! rt.trace for reflections (`rt_reflect.comp`) against its CPU reference: every
//! reflective pixel's path, bounces and shading, on real scenes in `rt` mode.
//!
//! Tolerance: a colour channel may differ by 2e-3 relative plus 2e-4 absolute (GPU
//! `pow` and `normalize` are not correctly rounded, and the sharp specular lobe
//! amplifies their error, as in light.direct). A path may also part from the CPU's
//! where a ray grazes the edge between two surfaces and float rounding picks the other
//! one; such pixels may be at most 0.5% of the reflective ones.

mod common;

use ash::vk;
use glam::{IVec2, Vec3};
use speculum::cpu_ref::reflect::{reflected_radiance, PathScene};
use speculum::cpu_ref::shading::ShadowMap;
use speculum::cpu_ref::trace::CpuBvh;
use speculum::gpu_types::GpuMaterial;
use speculum::settings::Mode;
use speculum::{Renderer, Settings};

const POISON: [f32; 4] = [-12345.0, -12345.0, -12345.0, 99.0];

/// Shadows from the shadow map on `room`, from shadow rays on `mirrors`; up to three
/// bounces, and paths of two or more rays must occur for the comparison to cover them.
#[test]
fn reflected_paths_match_cpu_reference() {
    let ctx = common::context();
    for (name, shadow_rays) in [("room", false), ("mirrors", true)] {
        let scene = speculum::scene::load(name).unwrap();
        let settings = Settings {
            width: 192,
            height: 108,
            mode: Mode::Rt,
            shadow_rays,
            ..Default::default()
        };
        let (w, h) = (settings.width as usize, settings.height as usize);
        let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
        let general = vk::ImageLayout::GENERAL;
        r.rt.color
            .write(bytemuck::cast_slice(&vec![POISON; w * h]), general)
            .unwrap();
        r.render_frame().unwrap();
        let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&r.gbuffer.targets.depth).unwrap());
        let normal = speculum::cpu_ref::rgba16f_to_f32(&r.read_target(&r.gbuffer.targets.normal).unwrap());
        let shadow: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&r.shadow.map).unwrap());
        let gpu: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&r.rt.color.read(general).unwrap());
        let reflective = r.reflection_maps().unwrap().reflective;
        let frame = *r.uniforms();
        let bvh = CpuBvh::build(&scene.vertices, &scene.indices);
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
        let shadow_map = ShadowMap {
            size: settings.shadow_map_size,
            depth: &shadow,
        };
        let path_scene = PathScene {
            frame: &frame,
            bvh: &bvh,
            vertices: &scene.vertices,
            indices: &scene.indices,
            materials: &materials,
            shadow_map: &shadow_map,
            shadow_rays,
        };
        let (mut compared, mut parted, mut multi) = (0usize, 0usize, 0usize);
        for i in (0..w * h).filter(|&i| reflective[i]) {
            let p = IVec2::new((i % w) as i32, (i / w) as i32);
            let n = Vec3::new(normal[i][0], normal[i][1], normal[i][2]);
            let (want, rays) = reflected_radiance(&path_scene, p, depth[i], n, settings.max_bounces);
            let got = Vec3::new(gpu[i][0], gpu[i][1], gpu[i][2]);
            assert_eq!(gpu[i][3], 1.0, "{name} pixel {p}: not traced ({:?})", gpu[i]);
            compared += 1;
            multi += (rays >= 2) as usize;
            let close = (0..3).all(|c| (got[c] - want[c]).abs() <= 2e-3 * want[c].abs() + 2e-4);
            if !close {
                parted += 1;
            }
        }
        assert!(compared > w * h / 4, "{name}: {compared} reflective pixels");
        assert!(multi > compared / 50, "{name}: {multi} paths of two or more rays");
        assert!(
            parted * 200 <= compared,
            "{name}: {parted} of {compared} paths differ from the CPU's"
        );
    }
    common::assert_no_validation_messages(&ctx);
}
