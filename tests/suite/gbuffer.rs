//! The G-buffer of an analytic scene (a plane and a sphere) matches ray-cast values:
//! world position from depth, normal, and material id at every pixel away from
//! silhouettes; its textures are sampled per texel; and the G-buffer by primary rays
//! (`gbuffer.trace`) matches its CPU reference.

use crate::common;

use glam::{Mat4, Vec3};
use speculum::cpu_ref::texture::TextureArray;
use speculum::scene::{Camera, Material, Scene, SceneBuilder, Texture, TriMesh};
use speculum::shader_defines::MATERIAL_NONE;
use speculum::{Renderer, Settings};

const CENTER: Vec3 = Vec3::new(0.3, 1.0, -0.5);
const RADIUS: f32 = 1.0;

/// Distance along the unit ray to the sphere (with the margin of its chord to the
/// silhouette) and to the plane y = 0 (limited to the 20x20 quad).
fn analytic_hit(o: Vec3, d: Vec3) -> Option<(f32, Vec3, u32, bool)> {
    let oc = o - CENTER;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - RADIUS * RADIUS);
    let sphere = (disc > 0.0).then(|| (-b - disc.sqrt(), disc));
    let plane = (d.y < 0.0).then(|| -o.y / d.y).filter(|&t| {
        let p = o + d * t;
        p.x.abs() < 10.0 && p.z.abs() < 10.0
    });
    match (sphere, plane) {
        (Some((ts, disc)), pl) if ts > 0.0 && pl.is_none_or(|tp| ts < tp) => {
            let n = (o + d * ts - CENTER).normalize();
            // Near the silhouette a pixel mixes sphere and background: skip it.
            Some((ts, n, 1, disc > 0.02))
        }
        (s, Some(tp)) => {
            let near_silhouette = s.is_some_and(|(_, disc)| disc < 0.02) || disc.abs() < 0.02;
            Some((tp, Vec3::Y, 0, !near_silhouette))
        }
        _ => None,
    }
}

#[test]
fn gbuffer_matches_analytic_plane_and_sphere() {
    let ctx = common::context();
    let mut b = SceneBuilder::new("analytic");
    let plane = b.material(Material::new("plane", [0.5, 0.5, 0.5], 0.5, 0.25));
    let sphere = b.material(Material::new("sphere", [0.9, 0.2, 0.1], 0.1, 0.75));
    assert_eq!((plane, sphere), (0, 1));
    b.mesh(TriMesh::quad(20.0, 20.0), Mat4::IDENTITY, plane);
    b.mesh(
        TriMesh::sphere(RADIUS, 256, 128),
        Mat4::from_translation(CENTER),
        sphere,
    );
    b.camera(Camera {
        position: Vec3::new(0.5, 2.2, 4.5),
        target: Vec3::new(0.2, 0.6, -0.5),
        up: Vec3::Y,
        fov_y_deg: 50.0,
        near: 0.1,
        far: 40.0,
    });
    let scene = b.build().unwrap();
    let settings = Settings {
        width: 160,
        height: 120,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
    r.render_frame().unwrap();
    let t = &r.lighting.gbuffer.out;
    let depth: Vec<f32> = bytemuck::cast_slice(&r.read_target(&t.depth).unwrap()).to_vec();
    let normal = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.normal).unwrap());
    let albedo = r.read_target(&t.albedo).unwrap();
    let material: Vec<u32> = bytemuck::cast_slice(&r.read_target(&t.material).unwrap()).to_vec();
    let frame = *r.uniforms();

    let (mut on_sphere, mut on_plane, mut on_sky) = (0, 0, 0);
    for y in 0..settings.height as i32 {
        for x in 0..settings.width as i32 {
            let i = (y * settings.width as i32 + x) as usize;
            let p = glam::IVec2::new(x, y);
            let far = speculum::cpu_ref::shading::world_from_depth(&frame, p, 1.0);
            let o = scene.camera.position;
            let d = (far - o).normalize();
            match analytic_hit(o, d) {
                None => {
                    assert_eq!(material[i], MATERIAL_NONE, "pixel {p} sees nothing");
                    assert_eq!(depth[i], 1.0, "pixel {p}: cleared depth");
                    on_sky += 1;
                }
                Some((_, _, _, false)) => {}
                Some((t_hit, n, id, true)) => {
                    let w = speculum::cpu_ref::shading::world_from_depth(&frame, p, depth[i]);
                    let expected = o + d * t_hit;
                    // Tessellation (256x128 sphere: sagitta < 1e-4) and depth precision:
                    // positions within 1 cm at 4-7 m, normals within 1.5 degrees.
                    assert!(
                        (w - expected).length() < 0.01,
                        "pixel {p}: position {w} expected {expected}"
                    );
                    let got_n = Vec3::from_slice(&normal[i][..3]).normalize(); // f16 storage shortens it slightly
                    assert!(
                        got_n.dot(n) > 1.5f32.to_radians().cos(),
                        "pixel {p}: normal {got_n} expected {n}"
                    );
                    assert_eq!(material[i], id, "pixel {p}: material");
                    let m = &scene.materials[id as usize];
                    // Past glossy_rough_max (the plane's 0.5) no ray is traced: reflectivity 0.
                    let traced = speculum::cpu_ref::glossy::traced_reflectivity(&frame, m.reflectivity, m.roughness);
                    assert_eq!(traced == 0.0, id == 0);
                    assert!((normal[i][3] - traced).abs() < 1e-3, "pixel {p}: reflectivity");
                    assert!((albedo[i * 4 + 3] as f32 / 255.0 - m.roughness).abs() <= 0.5 / 255.0 + 1e-6);
                    let srgb = speculum::scene::texture::linear_to_srgb(m.albedo.x);
                    assert!(albedo[i * 4].abs_diff(srgb) <= 1, "pixel {p}: base colour");
                    if id == 1 {
                        on_sphere += 1;
                    } else {
                        on_plane += 1;
                    }
                }
            }
        }
    }
    // The framing puts all three on screen in quantity: the test checked real pixels.
    assert!(
        on_sphere > 2000 && on_plane > 2000 && on_sky > 500,
        "{on_sphere} {on_plane} {on_sky}"
    );
}

/// A textured plane seen obliquely, magnified (a 16² random texture over 4 m, so the
/// lookup is level 0's bilinear filter at every pixel): the G-buffer's base colour is
/// the albedo times the texture at the pixel's analytic texture coordinate. Tolerance:
/// the target's 8-bit sRGB storage (half a step) plus the interpolation of the texture
/// coordinate across the quad (a 1e-3 texel shift moves a texel step of contrast 1 by
/// 1e-3); silhouette and texel-edge pixels are not special-cased. Its roughness texture
/// (another random 16², linear data read through the array's UNORM view, so no sRGB
/// decode touches it) likewise: the G-buffer's roughness is the
/// factor times its green channel there, within half an 8-bit step and the same shift,
/// and its metallic the factor times its blue channel (glTF's layout), within the
/// half float's rounding and the same shift. Each also within what the filter weights'
/// precision allows (`subTexelPrecisionBits`, from the device: the spec's bound, not
/// one driver's error), and the data within one step of the texture's own 8 bits (a
/// filtered 8-bit UNORM value may keep 8 bits: lavapipe's fixed-point filter does).
#[test]
fn gbuffer_samples_textures_per_texel() {
    use rand::{Rng, SeedableRng};
    let ctx = common::context();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let texture = Texture::colour(
        "random 16x16",
        image::RgbaImage::from_fn(16, 16, |_, _| {
            image::Rgba([rng.random(), rng.random(), rng.random(), 255])
        }),
    );
    let rough = Texture {
        name: "random roughness 16x16".into(),
        image: image::RgbaImage::from_fn(16, 16, |_, _| image::Rgba([0, rng.random(), rng.random(), 255])),
        data: true,
    };
    let mut b = SceneBuilder::new("textured plane");
    let t = b.texture(texture);
    let tr = b.texture(rough);
    let tint = [0.9, 0.8, 1.0];
    let (roughness, metallic) = (0.8, 0.9);
    let mut m = Material::new("plane", tint, roughness, 0.0).textured(t).metal(metallic);
    m.roughness_texture = Some(tr);
    let plane = b.material(m);
    b.mesh(TriMesh::quad(4.0, 4.0), Mat4::IDENTITY, plane);
    b.camera(Camera {
        position: Vec3::new(0.3, 2.0, 2.5),
        target: Vec3::new(0.0, 0.0, 0.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        near: 0.1,
        far: 20.0,
    });
    let scene = b.build().unwrap();
    let settings = Settings {
        width: 128,
        height: 96,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
    r.render_frame().unwrap();
    let albedo = r.read_target(&r.lighting.gbuffer.out.albedo).unwrap();
    let motion = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&r.lighting.gbuffer.out.motion).unwrap());
    let material: Vec<u32> = bytemuck::cast_slice(&r.read_target(&r.lighting.gbuffer.out.material).unwrap()).to_vec();
    let frame = *r.uniforms();
    let textures = TextureArray::new(&scene.textures, speculum::scene::texture::LAYER_MAX);
    // Vulkan computes a linear filter's weights with at least the device's
    // subTexelPrecisionBits of fraction (4 is allowed; lavapipe and NVIDIA report 8): a
    // weight may be off by up to one such step on each axis, which moves a bilinear
    // result by up to the footprint's spread times two steps.
    let weight_error = 2f32.powi(1 - ctx.limits.sub_texel_precision_bits as i32);
    let filtering = |layer: u32, uv: glam::Vec2| textures.footprint_range(layer, 0, uv) * weight_error;
    let (mut checked, mut distinct) = (0, std::collections::HashSet::new());
    for y in 0..settings.height as i32 {
        for x in 0..settings.width as i32 {
            let i = (y * settings.width as i32 + x) as usize;
            let p = glam::IVec2::new(x, y);
            let o = scene.camera.position;
            let d = (speculum::cpu_ref::shading::world_from_depth(&frame, p, 1.0) - o).normalize();
            let hit = o + d * (-o.y / d.y);
            if d.y >= 0.0 || hit.x.abs() > 1.95 || hit.z.abs() > 1.95 {
                continue; // off the plane or at its edge
            }
            assert_eq!(material[i], plane, "pixel {p}");
            // quad's UVs: (0, 0) at (-2, -2), u along +x, v along +z.
            let uv = glam::Vec2::new((hit.x + 2.0) / 4.0, (hit.z + 2.0) / 4.0);
            let want = Vec3::from(tint) * textures.sample_lod(0, uv, 0.0).truncate();
            let (colour_filter, data_filter) = (Vec3::from(tint) * filtering(0, uv).truncate(), filtering(tr, uv));
            let got = speculum::cpu_ref::albedo_texel(&albedo[4 * i..4 * i + 4]).0;
            for c in 0..3 {
                // Half an sRGB step of the stored byte, plus the coordinate shift.
                let b = albedo[4 * i + c];
                let step = speculum::scene::texture::srgb_to_linear(b.saturating_add(1))
                    - speculum::scene::texture::srgb_to_linear(b.saturating_sub(1));
                assert!(
                    (got[c] - want[c]).abs() <= 0.5 * step + 2e-3 + colour_filter[c],
                    "pixel {p}: base colour {got}, texture says {want}"
                );
            }
            let want_r = roughness * textures.sample_lod(tr, uv, 0.0).y;
            let got_r = albedo[4 * i + 3] as f32 / 255.0;
            assert!(
                (got_r - want_r).abs() <= 0.5 / 255.0 + 2e-3 + roughness * (data_filter.y + 1.0 / 255.0),
                "pixel {p}: roughness {got_r}, texture says {want_r}"
            );
            let want_m = metallic * textures.sample_lod(tr, uv, 0.0).z;
            assert!(
                (motion[i][3] - want_m).abs() <= 5e-4 + 2e-3 + metallic * (data_filter.z + 1.0 / 255.0),
                "pixel {p}: metallic {}, texture says {want_m}",
                motion[i][3]
            );
            assert_eq!(motion[i][..3], [0.0; 3], "pixel {p}: a still plane moves");
            checked += 1;
            distinct.insert(albedo[4 * i..4 * i + 4].to_vec());
        }
    }
    assert!(
        checked > 5000 && distinct.len() > 1000,
        "{checked} pixels, {} colours",
        distinct.len()
    );
}

/// Bent normals (a floor whose file normals all lean 10 degrees away from the camera,
/// which views it from 2 to 40 degrees above grazing: below 20 the mirror direction
/// of the file normal dips under the floor): no G-buffer normal mirrors the view
/// below the floor. Where the file normal would, the stored normal is the clamped one,
/// whose mirror direction leaves at `BENT_NORMAL_MIN_COS` above the plane (within the
/// RGBA16F storage of the normal); elsewhere it is the file normal itself.
#[test]
fn bent_normals_never_mirror_below_the_surface() {
    use speculum::cpu_ref::texture::{clamp_bent_normal, BENT_NORMAL_MIN_COS};
    let ctx = common::context();
    let bent = Vec3::new(0.0, 10f32.to_radians().cos(), -10f32.to_radians().sin());
    let mut floor = TriMesh::quad(40.0, 40.0);
    floor.normals = vec![bent; 4];
    let mut b = SceneBuilder::new("bent floor");
    let m = b.material(Material::new("floor", [0.5; 3], 0.1, 0.8));
    b.mesh(floor, Mat4::IDENTITY, m);
    b.camera(Camera {
        position: Vec3::new(0.0, 1.5, 6.0),
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 40.0,
        near: 0.1,
        far: 60.0,
    });
    let scene = b.build().unwrap();
    let settings = Settings {
        width: 96,
        height: 64,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
    r.render_frame().unwrap();
    let t = &r.lighting.gbuffer.out;
    let depth: Vec<f32> = bytemuck::cast_slice(&r.read_target(&t.depth).unwrap()).to_vec();
    let normal = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.normal).unwrap());
    let frame = *r.uniforms();
    let (mut clamped, mut kept) = (0, 0);
    for (i, nr) in normal.iter().enumerate() {
        if depth[i] == 1.0 {
            continue;
        }
        let p = glam::IVec2::new((i % 96) as i32, (i / 96) as i32);
        let w = speculum::cpu_ref::shading::world_from_depth(&frame, p, depth[i]);
        let v = (scene.camera.position - w).normalize();
        let n = Vec3::new(nr[0], nr[1], nr[2]).normalize();
        let up = (-v).reflect(n).y;
        assert!(
            up >= BENT_NORMAL_MIN_COS - 2e-3,
            "pixel {p}: mirror direction {up} below the floor"
        );
        let want = clamp_bent_normal(bent, Vec3::Y, v);
        assert!((n - want).length() < 3e-3, "pixel {p}: normal {n}, clamped {want}");
        if (-v).reflect(bent).y < BENT_NORMAL_MIN_COS {
            clamped += 1;
        } else {
            kept += 1;
        }
    }
    assert!(clamped > 500 && kept > 100, "{clamped} clamped, {kept} kept");
}

/// Random colour texels (a 64² and a 200x120 texture, resampled to one layer size) and a
/// random roughness and metallic data texture on a 30 m floor whose texture repeats 10
/// times, seen from low over it out to the horizon (every mip level, grazing angles);
/// a textured box, a smooth sphere (its file normals bend at the silhouette) and a
/// plain wall.
fn traced_scene() -> Scene {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(23);
    let mut random = |w, h, data: bool| {
        let image = image::RgbaImage::from_fn(w, h, |_, _| {
            image::Rgba([rng.random(), rng.random(), rng.random(), 255])
        });
        let name = format!("random {w}x{h}");
        match data {
            false => Texture::colour(name, image),
            true => Texture { name, image, data },
        }
    };
    let mut b = SceneBuilder::new("traced");
    let (t0, t1, tr) = (
        b.texture(random(64, 64, false)),
        b.texture(random(200, 120, false)),
        b.texture(random(32, 32, true)),
    );
    let mut floor = Material::new("floor", [0.9, 0.85, 0.8], 0.7, 0.3)
        .textured(t0)
        .metal(0.8);
    floor.roughness_texture = Some(tr);
    let floor = b.material(floor);
    let boxes = b.material(Material::new("box", [1.0, 1.0, 1.0], 0.5, 0.2).textured(t1));
    let mirror = b.material(Material::new("mirror", [0.9, 0.9, 0.9], 0.02, 0.9));
    let wall = b.material(Material::new("wall", [0.3, 0.5, 0.7], 0.9, 0.0));
    let mut floor_mesh = TriMesh::quad(30.0, 30.0);
    floor_mesh.uvs.iter_mut().for_each(|uv| *uv *= 10.0);
    b.mesh(floor_mesh, Mat4::IDENTITY, floor);
    b.mesh(
        TriMesh::cuboid(Vec3::splat(1.2)),
        Mat4::from_translation(Vec3::new(-1.5, 0.6, -1.0)),
        boxes,
    );
    b.mesh(
        TriMesh::sphere(1.0, 24, 12),
        Mat4::from_translation(Vec3::new(1.2, 1.0, -0.5)),
        mirror,
    );
    let side = Mat4::from_translation(Vec3::new(-6.0, 2.0, -6.0)) * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
    b.mesh(TriMesh::quad(4.0, 8.0), side, wall);
    b.camera(Camera {
        position: Vec3::new(0.0, 1.2, 5.0),
        target: Vec3::new(0.0, 0.6, -3.0),
        up: Vec3::Y,
        fov_y_deg: 70.0,
        near: 0.05,
        far: 60.0,
    });
    b.build().unwrap()
}

/// How far a trilinear lookup of `layer` at `uv` and level `lod` may lie from the exact
/// one (`TextureArray::sample_lod`) on a device that honours Vulkan's filtering
/// precision: each level's bilinear weights may be one `subTexelPrecisionBits` step off on
/// each axis (the footprint's spread times two steps), the levels' blend one
/// `mipmapPrecisionBits` step (the two levels' difference times the step), and the level
/// itself 1e-3 off (the kernel's log2 and the hit's coordinates are not the CPU's bits).
fn trilinear_bound(
    textures: &TextureArray,
    layer: u32,
    uv: glam::Vec2,
    lod: f32,
    limits: &ash::vk::PhysicalDeviceLimits,
) -> glam::Vec4 {
    let last = (textures.layers[layer as usize].len() - 1) as f32;
    let lod = lod.clamp(0.0, last);
    let (l0, l1) = (lod.floor(), (lod.floor() + 1.0).min(last));
    let weight = 2f32.powi(1 - limits.sub_texel_precision_bits as i32);
    let bilinear = textures
        .footprint_range(layer, l0 as usize, uv)
        .max(textures.footprint_range(layer, l1 as usize, uv))
        * weight;
    let levels = (textures.sample_lod(layer, uv, l0) - textures.sample_lod(layer, uv, l1)).abs();
    bilinear + levels * (2f32.powi(-(limits.mipmap_precision_bits as i32)) + 1e-3)
}

/// `gbuffer.trace` (`visibility` rays) against its CPU reference, `cpu_ref::primary`,
/// through each tracer the device has, on the textured scene above, `drop` (rigid bodies
/// in flight: the dynamic BVH and motion) and `cloth` (its refit BVH), every target
/// poisoned before the traced frame. The contract (docs/precision.md):
/// - the hit: a pixel's material and depth (within 2e-6, a few units in the last place
///   of a depth near 1) are the CPU's but where the ray passes a triangle's edge and the
///   GPU's ray, made with its own rounding from the inverse view-projection, falls on the
///   other side: at most 1 in 500 of the pixels;
/// - on every other pixel, the normal within 2e-3 (half-float storage, 2^-11, and the
///   GPU's normalize), the reflectivity within the half float's step, the base colour
///   within half an sRGB step of the stored byte plus the trilinear bound above (times
///   the albedo), roughness and metallic within one 8-bit step plus the bound (times the
///   material's), the motion within 1e-3 of its length plus 1e-4 (half-float storage of
///   the difference of two barycentric sums).
#[test]
fn traced_gbuffer_matches_cpu_reference() {
    use speculum::cpu_ref::primary::{gbuffer_texel, PrimaryScene};
    use speculum::cpu_ref::reflect::Triangles;
    use speculum::cpu_ref::trace::CpuBvh;
    use speculum::gpu_types::GpuMaterial;
    use speculum::settings::{Mode, Tracer, Visibility};
    let ctx = common::context();
    assert!(
        ctx.ray_tracing.is_some() || ctx.driver_name != "llvmpipe",
        "lavapipe has ray tracing: {:?}",
        ctx.ray_tracing_missing
    );
    let tracers: Vec<Tracer> = Tracer::ALL
        .into_iter()
        .filter(|&t| t == Tracer::Lbvh || ctx.ray_tracing.is_some())
        .collect();
    let limits = ctx.limits;
    for (name, frames) in [("traced", 1), ("drop", 30), ("cloth", 12)] {
        for &tracer in &tracers {
            let scene = match name {
                "traced" => traced_scene(),
                _ => speculum::scene::load(name).unwrap(),
            };
            let settings = Settings {
                width: 160,
                height: 96,
                mode: Mode::Raster,
                visibility: Visibility::Rays,
                tracer,
                ..Default::default()
            };
            let (w, h) = (settings.width as usize, settings.height as usize);
            let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
            for _ in 1..frames {
                r.render_frame().unwrap();
            }
            let previous = r.read_dynamic_vertices().unwrap();
            let t = &r.lighting.gbuffer.out;
            let read_only = ash::vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            t.depth
                .write(bytemuck::cast_slice(&vec![0.25f32; w * h]), read_only)
                .unwrap();
            t.material
                .write(bytemuck::cast_slice(&vec![0xdead_beefu32; w * h]), read_only)
                .unwrap();
            let poison = speculum::cpu_ref::f32_to_rgba16f(&vec![[-1234.0, 567.0, -89.0, 4321.0]; w * h]);
            t.normal.write(&poison, read_only).unwrap();
            t.motion.write(&poison, read_only).unwrap();
            t.albedo.write(&vec![0x5au8; 4 * w * h], read_only).unwrap();
            r.render_frame().unwrap();
            let t = &r.lighting.gbuffer.out;
            let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.depth).unwrap());
            let material: Vec<u32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.material).unwrap());
            let normal = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.normal).unwrap());
            let motion = speculum::gpu_types::rgba16f_to_f32(&r.read_target(&t.motion).unwrap());
            let albedo = r.read_target(&t.albedo).unwrap();
            let frame = *r.uniforms();
            let current = r.read_dynamic_vertices().unwrap();
            let statics = CpuBvh::build(&scene.vertices, &scene.indices);
            let meshes = scene.dynamic_meshes();
            let dynamic_bvh = current.as_ref().map(|v| CpuBvh::build(v, &meshes.indices));
            let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
            let textures = TextureArray::new(&scene.textures, speculum::scene::texture::LAYER_MAX);
            let s = PrimaryScene {
                frame: &frame,
                statics: Triangles {
                    bvh: &statics,
                    vertices: &scene.vertices,
                    indices: &scene.indices,
                    uvs: &scene.uvs,
                },
                dynamic: dynamic_bvh.as_ref().map(|bvh| {
                    let tris = Triangles {
                        bvh,
                        vertices: current.as_deref().unwrap(),
                        indices: &meshes.indices,
                        uvs: &meshes.uvs,
                    };
                    (tris, previous.as_deref().unwrap())
                }),
                materials: &materials,
                textures: &textures,
            };
            let what = format!("{name} through {}", tracer.name());
            let (mut covered, mut parted, mut moving, mut textured) = (0usize, 0usize, 0usize, 0usize);
            let mut levels = std::collections::BTreeSet::new();
            for i in 0..w * h {
                let p = glam::IVec2::new((i % w) as i32, (i / w) as i32);
                let want = gbuffer_texel(&s, p);
                if want.material == MATERIAL_NONE && material[i] == MATERIAL_NONE {
                    assert_eq!(depth[i], 1.0, "{what} pixel {p}: a miss's depth");
                    assert_eq!(normal[i], [0.0; 4], "{what} pixel {p}: a miss's normal");
                    assert_eq!(motion[i], [0.0; 4], "{what} pixel {p}: a miss's motion");
                    assert_eq!(albedo[4 * i..4 * i + 4], [0; 4], "{what} pixel {p}: a miss's colour");
                    continue;
                }
                covered += 1;
                if material[i] != want.material || (depth[i] - want.depth).abs() > 2e-6 {
                    parted += 1;
                    continue;
                }
                check_traced_texel(
                    &what,
                    p,
                    (&normal[i], &motion[i], &albedo[4 * i..4 * i + 4]),
                    &want,
                    |layer| trilinear_bound(&textures, layer, want.uv, want.lod, &limits),
                    (&materials, frame.rough_roughness),
                );
                moving += (want.motion.length() > 1e-3) as usize;
                if materials[want.material as usize].texture_layer != speculum::shader_defines::TEXTURE_NONE {
                    textured += 1;
                    levels.insert(want.lod.clamp(0.0, 8.0).floor() as u32);
                }
            }
            assert!(covered > w * h / 3, "{what}: {covered} covered pixels");
            assert!(
                parted * 500 <= covered,
                "{what}: {parted} of {covered} pixels part from the CPU's hits"
            );
            match name {
                "traced" => assert!(
                    textured > w * h / 4 && levels.len() >= 4,
                    "{what}: {textured} textured pixels at levels {levels:?}"
                ),
                _ => assert!(moving > 50, "{what}: {moving} moving pixels"),
            }
        }
    }
}

/// One covered pixel's texels (`normal`, `motion`, `albedo` as read back) against the
/// CPU's, within the contract of `traced_gbuffer_matches_cpu_reference`; `bound` gives a
/// texture layer's filtering bound at the pixel's lookup.
fn check_traced_texel(
    what: &str,
    p: glam::IVec2,
    (normal, motion, albedo): (&[f32; 4], &[f32; 4], &[u8]),
    want: &speculum::cpu_ref::primary::Texel,
    bound: impl Fn(u32) -> glam::Vec4,
    (materials, rough_max): (&[speculum::gpu_types::GpuMaterial], f32),
) {
    use speculum::shader_defines::TEXTURE_NONE;
    let m = materials[want.material as usize];
    let n = Vec3::new(normal[0], normal[1], normal[2]);
    assert!(
        (n - want.normal).abs().max_element() <= 2e-3,
        "{what} pixel {p}: normal {n}, CPU {}",
        want.normal
    );
    let (base, roughness) = speculum::cpu_ref::albedo_texel(albedo);
    let colour = match m.texture_layer {
        TEXTURE_NONE => Vec3::ZERO,
        layer => Vec3::from(m.albedo) * bound(layer).truncate(),
    };
    for c in 0..3 {
        let b = albedo[c];
        let step = speculum::scene::texture::srgb_to_linear(b.saturating_add(1))
            - speculum::scene::texture::srgb_to_linear(b.saturating_sub(1));
        assert!(
            (base[c] - want.base[c]).abs() <= 0.5 * step + 1e-4 + colour[c],
            "{what} pixel {p}: base colour {base}, CPU {} (lod {})",
            want.base,
            want.lod
        );
    }
    let data = match m.roughness_layer {
        TEXTURE_NONE => glam::Vec4::ZERO,
        layer => bound(layer) + 1.0 / 255.0,
    };
    let roughness_bound = 0.5 / 255.0 + 1e-4 + m.roughness * data.y;
    assert!(
        (roughness - want.roughness).abs() <= roughness_bound,
        "{what} pixel {p}: roughness {roughness}, CPU {}",
        want.roughness
    );
    // The traced reflectivity is the material's below the rough cut-off and 0 from it:
    // either, where the roughness lies within its bound of the cut-off.
    let at_cut = (want.roughness - rough_max).abs() <= roughness_bound;
    let reflectivities: &[f32] = if at_cut {
        &[0.0, m.reflectivity]
    } else {
        &[want.reflectivity]
    };
    assert!(
        reflectivities
            .iter()
            .any(|&r| (normal[3] - r).abs() <= r * 2f32.powi(-10)),
        "{what} pixel {p}: reflectivity {}, CPU {} (roughness {})",
        normal[3],
        want.reflectivity,
        want.roughness
    );
    assert!(
        (motion[3] - want.metallic).abs() <= 5e-4 + 1e-4 + m.metallic * data.z,
        "{what} pixel {p}: metallic {}, CPU {}",
        motion[3],
        want.metallic
    );
    let mv = Vec3::new(motion[0], motion[1], motion[2]);
    assert!(
        (mv - want.motion).length() <= 1e-3 * want.motion.length() + 1e-4,
        "{what} pixel {p}: motion {mv}, CPU {}",
        want.motion
    );
}

/// Visibility by rays renders the frame raster renders: every later pass reads the
/// same targets, so the two frames differ only where a pixel's one sample differs
/// (the rasterizer's coverage and interpolation against the ray's exact hit, the
/// texture's level from a ray cone against screen derivatives). Per built-in scene
/// (static, textured, glossy, rigid bodies, cloth, several frames on the moving ones)
/// and the skinned walking figure,
/// every mode (the tracers in turn), the hybrid with a fixed exchange rate (a measured
/// one follows each run's timings): the frames' SSIM at least 0.995 (the filed floor)
/// and RMSE at most 0.01 (lavapipe, 128x80: at worst 0.99845 and 0.0053, `gallery`'s
/// `ssr`, isolated pixels where its walls meet; 0.9999+ on most). A wrong metallic
/// channel drops `room` to 0.83; a texture one level too blurred stays within (0.99998):
/// the texel contract is `traced_gbuffer_matches_cpu_reference`'s.
#[test]
fn visibility_by_rays_renders_the_raster_frame() {
    use speculum::settings::{Mode, Tracer, Visibility};
    let ctx = common::context();
    let tracers: Vec<Tracer> = Tracer::ALL
        .into_iter()
        .filter(|&t| t == Tracer::Lbvh || ctx.ray_tracing.is_some())
        .collect();
    // And the walking figure: a skinned, animated model.
    let names = speculum::scene::builtin::NAMES
        .into_iter()
        .chain(["assets/models/figure.glb"]);
    for name in names {
        let name = if name == "gallery" { "gallery:20000" } else { name };
        let scene = speculum::scene::load(name).unwrap();
        // The moving scenes over several frames: the motion and previous vertices.
        let frames = if scene.is_dynamic() { 4 } else { 1 };
        for (&tracer, mode) in tracers.iter().cycle().zip(Mode::ALL) {
            let render = |visibility| {
                let settings = Settings {
                    width: 128,
                    height: 80,
                    mode,
                    exchange_rate: 0.5,
                    visibility,
                    tracer,
                    ..Default::default()
                };
                let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
                for _ in 0..frames {
                    r.render_frame().unwrap();
                }
                r.read_output().unwrap()
            };
            let (raster, rays) = (render(Visibility::Raster), render(Visibility::Rays));
            let c = speculum::metrics::compare_rgba8(&raster, &rays, 128, 80).unwrap();
            assert!(
                c.ssim >= 0.998 && c.rmse <= 0.006,
                "{name} {mode:?} through {}: {c:?}",
                tracer.name()
            );
        }
    }
}
