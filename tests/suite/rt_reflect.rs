//! rt.trace for reflections (`rt_reflect.comp`) against its CPU reference: every
//! reflective pixel's path, bounces and shading, on real scenes in `rt` mode.
//!
//! Tolerance: a colour channel may differ by 2e-3 relative plus 2e-4 absolute (GPU
//! `pow` and `normalize` are not correctly rounded, and the sharp specular lobe
//! amplifies their error, as in light.direct). A path may also part from the CPU's
//! where a ray grazes the edge between two surfaces and float rounding picks the other
//! one; such pixels may be at most 0.5% of the reflective ones. Texture lookups at hits
//! add the GPU's filtering precision (NVIDIA interpolates with 8-bit weights): on the
//! textured scene a channel may also differ by 8e-3 absolute, two steps of 1/256 of the
//! texels' full contrast (lavapipe stays within 1e-3 on all but 3 of 11,540 pixels).

use crate::common;

use ash::vk;
use glam::{IVec2, Vec3};
use speculum::cpu_ref::reflect::{reflected_radiance, PathScene, Triangles};
use speculum::cpu_ref::shading::ShadowMap;
use speculum::cpu_ref::texture::TextureArray;
use speculum::cpu_ref::trace::CpuBvh;
use speculum::gpu_types::GpuMaterial;
use speculum::scene::{texture, Camera, Material, Scene, SceneBuilder, Texture, TriMesh};
use speculum::settings::{Mode, Shadows};
use speculum::{Renderer, Settings};

const POISON: [f32; 4] = [-12345.0, -12345.0, -12345.0, 99.0];
/// Frames rendered on `drop` before the comparison (its bodies fall and bounce).
const DROP_FRAMES: u32 = 40;

/// Random-coloured texels (a 64² and a 200x120 texture, so layers are resampled to
/// 256²) on a floor and a box's faces seen in two mirrors and a mirror sphere: the
/// reflections minify the textures, so the ray cones pick several mip levels.
fn textured_scene() -> Scene {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let mut random = |w, h| {
        let image = image::RgbaImage::from_fn(w, h, |_, _| {
            image::Rgba([rng.random(), rng.random(), rng.random(), 255])
        });
        Texture::colour(format!("random {w}x{h}"), image)
    };
    let mut b = SceneBuilder::new("textured");
    let (t0, t1) = (b.texture(random(64, 64)), b.texture(random(200, 120)));
    let floor = b.material(Material::new("floor", [0.9, 0.85, 0.8], 0.3, 0.3).textured(t0));
    let boxes = b.material(Material::new("box", [1.0, 1.0, 1.0], 0.5, 0.2).textured(t1));
    let mirror = b.material(Material::new("mirror", [0.9, 0.9, 0.9], 0.02, 0.9));
    let mut floor_mesh = TriMesh::quad(12.0, 12.0);
    floor_mesh.uvs.iter_mut().for_each(|uv| *uv *= 6.0); // repeats 6x
    b.mesh(floor_mesh, glam::Mat4::IDENTITY, floor);
    b.mesh(
        TriMesh::cuboid(glam::Vec3::splat(1.2)),
        glam::Mat4::from_translation(glam::Vec3::new(-1.5, 0.6, -1.0)),
        boxes,
    );
    b.mesh(
        TriMesh::sphere(1.0, 48, 24),
        glam::Mat4::from_translation(glam::Vec3::new(1.2, 1.0, -0.5)),
        mirror,
    );
    for x in [-4.0f32, 4.0] {
        let wall = glam::Mat4::from_translation(glam::Vec3::new(x, 1.5, -2.0))
            * glam::Mat4::from_rotation_z(-x.signum() * std::f32::consts::FRAC_PI_2)
            * glam::Mat4::from_rotation_x(0.3);
        b.mesh(TriMesh::quad(3.0, 8.0), wall, mirror);
    }
    b.camera(Camera {
        position: glam::Vec3::new(0.0, 2.5, 6.0),
        target: glam::Vec3::new(0.0, 0.8, -1.0),
        up: glam::Vec3::Y,
        fov_y_deg: 60.0,
        near: 0.05,
        far: 60.0,
    });
    b.build().unwrap()
}

/// Each scene under one of the `shadows` settings (the map, rays, the hybrid), which
/// shadows the visible surface and the hits alike; up to three bounces, and paths of
/// two or more rays must occur for the comparison to cover them. Under rays and the
/// hybrid the frame's visibility (shadow.classify, shadow.compact, shadow.trace; the
/// dynamic scenes' from that frame's dynamic BVH) is compared with the CPU's too. With
/// glossy reflections (`glossy` with 2 rays per pixel, `room` and `drop` with 1) the
/// glossy pixels' sampled paths are compared as well, and every pixel's distance to its
/// first hit (`ssr.hit_distance`).
#[test]
fn reflected_paths_match_cpu_reference() {
    let ctx = common::context();
    for (name, shadows, rays) in [
        ("room", Shadows::Hybrid, 0),
        ("room", Shadows::Map, 0),
        ("mirrors", Shadows::Rays, 0),
        ("textured", Shadows::Map, 0),
        ("drop", Shadows::Map, 0),
        ("drop", Shadows::Hybrid, 0),
        ("cloth", Shadows::Rays, 0),
        ("glossy", Shadows::Map, 2),
        ("room", Shadows::Hybrid, 1),
        ("drop", Shadows::Map, 1),
    ] {
        // rays 0: glossy off; else glossy on with that many rays per glossy pixel.
        let scene = if name == "textured" {
            textured_scene()
        } else {
            speculum::scene::load(name).unwrap()
        };
        let textured = !scene.textures.is_empty();
        let settings = Settings {
            width: 192,
            height: 108,
            mode: Mode::Rt,
            shadows,
            glossy: rays > 0,
            reflection_rays: rays.max(1),
            ..Default::default()
        };
        let (w, h) = (settings.width as usize, settings.height as usize);
        let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
        let general = vk::ImageLayout::GENERAL;
        r.reflections
            .rt
            .out
            .write(bytemuck::cast_slice(&vec![POISON; w * h]), general)
            .unwrap();
        r.lighting
            .shadow_trace
            .out
            .visibility
            .write(bytemuck::cast_slice(&vec![POISON[0]; w * h]), general)
            .unwrap();
        // A dynamic scene: the world after DROP_FRAMES time steps, bodies in the air
        // and on the floor.
        let frames = if scene.is_dynamic() { DROP_FRAMES } else { 1 };
        for _ in 0..frames {
            r.render_frame().unwrap();
        }
        let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&r.lighting.gbuffer.out.depth).unwrap());
        let normal = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&r.lighting.gbuffer.out.normal).unwrap());
        let shadow: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&r.lighting.shadow.out).unwrap());
        let gpu: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&r.reflections.rt.out.read(general).unwrap());
        let reflective = r.reflection_maps().unwrap().reflective;
        let albedo = r.read_target(&r.lighting.gbuffer.out.albedo).unwrap();
        let hit: Vec<f32> = bytemuck::pod_collect_to_vec(&r.reflections.ssr.out.hit_distance.read(general).unwrap());
        // The uniforms of the frame read back (the last: its index).
        let frame = speculum::gpu_types::FrameUniforms {
            frame_index: frames - 1,
            ..*r.uniforms()
        };
        let bvh = CpuBvh::build(&scene.vertices, &scene.indices);
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
        let textures = TextureArray::new(&scene.textures, texture::LAYER_MAX);
        let shadow_map = ShadowMap {
            size: settings.shadow_map_size,
            depth: &shadow,
        };
        // The dynamic geometry of that frame, moved on the CPU by an independent world;
        // a cloth's vertices are the GPU's own (sim.cloth has its own CPU comparison in
        // tests/suite/sim.rs; 40 steps of two f32 simulations drift apart by more than the
        // shading tolerance).
        let (dyn_vertices, dyn_bvh, meshes) = if !scene.cloths.is_empty() {
            let v = r.read_dynamic_vertices().unwrap().unwrap();
            let meshes = scene.dynamic_meshes();
            let bvh = CpuBvh::build(&v, &meshes.indices);
            (v, Some(bvh), meshes)
        } else if scene.is_dynamic() {
            let mut world = speculum::sim::rigid::RigidWorld::new(&scene, settings.sim_dt).unwrap();
            for _ in 0..frames {
                world.step();
            }
            let poses = world.poses();
            let meshes = scene.dynamic_meshes();
            let v: Vec<_> = meshes
                .vertices
                .iter()
                .map(|v| speculum::cpu_ref::sim::transform(v, &poses))
                .collect();
            let bvh = CpuBvh::build(&v, &meshes.indices);
            (v, Some(bvh), meshes)
        } else {
            (Vec::new(), None, Default::default())
        };
        let dynamic = dyn_bvh.as_ref().map(|bvh| Triangles {
            bvh,
            vertices: &dyn_vertices,
            indices: &meshes.indices,
            uvs: &meshes.uvs,
        });
        let path_scene = PathScene {
            frame: &frame,
            bvh: &bvh,
            vertices: &scene.vertices,
            indices: &scene.indices,
            uvs: &scene.uvs,
            materials: &materials,
            textures: &textures,
            shadow_map: &shadow_map,
            shadows,
            dynamic,
        };
        if shadows.traces() {
            check_visibility(name, &r, &path_scene, (&depth, &normal));
        }
        let (mut compared, mut parted, mut multi, mut glossy) = (0usize, 0usize, 0usize, 0usize);

        for i in (0..w * h).filter(|&i| reflective[i]) {
            let p = IVec2::new((i % w) as i32, (i / w) as i32);
            let n = Vec3::new(normal[i][0], normal[i][1], normal[i][2]);
            let roughness = albedo[4 * i + 3] as f32 / 255.0;
            let surface = (depth[i], n, roughness);
            let (want, traced, first) = reflected_radiance(&path_scene, p, surface, settings.max_bounces);
            let got = Vec3::new(gpu[i][0], gpu[i][1], gpu[i][2]);
            assert_eq!(gpu[i][3], 1.0, "{name} pixel {p}: not traced ({:?})", gpu[i]);
            compared += 1;
            multi += (traced >= 2) as usize;
            glossy += speculum::cpu_ref::glossy::is_glossy(&frame, roughness) as usize;
            let filtering = if textured { 8e-3 } else { 0.0 };
            let close = (0..3).all(|c| (got[c] - want[c]).abs() <= 2e-3 * want[c].abs() + 2e-4 + filtering)
                && (hit[i] - first).abs() <= 1e-3 * first;

            if !close {
                parted += 1;
            }
        }
        assert!(compared > w * h / 4, "{name}: {compared} reflective pixels");
        assert!(multi > compared / 50, "{name}: {multi} paths of two or more rays");
        assert_eq!(
            glossy > compared / 10,
            rays > 0,
            "{name}: {glossy} glossy of {compared} pixels"
        );
        assert!(
            parted * 200 <= compared,
            "{name}: {parted} of {compared} paths differ from the CPU's"
        );
    }
}

/// The frame's sun visibility on every lit pixel against `cpu_ref::shadows::visibility`
/// (the same classification, then the same shadow ray): equal but for rays through a
/// triangle's edge and classifications on a threshold's ulp, at most 1 in 500.
fn check_visibility(name: &str, r: &Renderer, s: &PathScene<'_>, (depth, normal): (&[f32], &[[f32; 4]])) {
    let maps = r.shadow_maps().unwrap();
    let material: Vec<u32> = bytemuck::pod_collect_to_vec(&r.read_target(&r.lighting.gbuffer.out.material).unwrap());
    let w = s.frame.resolution[0] as usize;
    let (mut lit, mut traced, mut shadowed, mut differ) = (0usize, 0usize, 0usize, 0usize);
    for i in (0..maps.lit.len()).filter(|&i| maps.lit[i]) {
        let p = IVec2::new((i % w) as i32, (i / w) as i32);
        let n = Vec3::new(normal[i][0], normal[i][1], normal[i][2]);
        let want = speculum::cpu_ref::shadows::visibility(s, p, (depth[i], n, material[i]));
        let got = maps.visibility[i];
        assert!(got == 0.0 || got == 1.0, "{name} pixel {p}: visibility {got}");
        lit += 1;
        traced += (maps.mask[i] != 0) as usize;
        shadowed += (got == 0.0) as usize;
        differ += (got != want) as usize;
    }
    assert!(lit > maps.lit.len() / 4, "{name}: {lit} lit pixels");
    assert!(traced > lit / 20, "{name}: {traced} of {lit} lit pixels traced");
    assert!(shadowed * 200 > lit, "{name}: {shadowed} of {lit} lit pixels in shadow");
    assert!(
        differ * 500 <= lit,
        "{name}: {differ} of {lit} visibilities differ from the CPU's"
    );
}
