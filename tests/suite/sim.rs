//! The dynamic scene's GPU side against its CPU references: `sim.transform` on random
//! vertices and poses.
//!
//! Tolerance: positions within 1e-5 of their magnitude plus 1e-5 (one matrix-vector
//! product in f32, FMA-contracted or not), normals within 1e-5; material and object
//! ids exactly.

use crate::common;

use glam::{Mat4, Quat, Vec3};
use rand::Rng;
use speculum::gpu_types::GpuVertex;
use speculum::passes::sim_transform::SimTransformPass;
use speculum::vk::Buffer;

/// What a vertex no kernel wrote reads as.
const POISON: GpuVertex = GpuVertex {
    position: [f32::NAN; 3],
    material: 0xdead,
    normal: [-7.0; 3],
    object: 0xbeef,
};

/// A world-space vertex buffer of `len` vertices, all `POISON`, that tests read back.
fn poisoned_world(ctx: &std::sync::Arc<speculum::vk::Context>, len: usize) -> Buffer {
    let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER | ash::vk::BufferUsageFlags::TRANSFER_SRC;
    Buffer::with_data(ctx, "test.world", usage, bytemuck::cast_slice(&vec![POISON; len])).unwrap()
}

#[test]
fn transform_matches_cpu_reference() {
    let ctx = common::context();
    let mut rng = common::rng(21);
    let bodies = 37;
    let poses: Vec<Mat4> = (0..bodies)
        .map(|_| {
            let axis = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::Y);
            let rotation = Quat::from_axis_angle(axis, rng.random_range(-3.2..3.2));
            let t = Vec3::new(
                rng.random_range(-50.0..50.0),
                rng.random_range(-5.0..20.0),
                rng.random_range(-50.0..50.0),
            );
            Mat4::from_rotation_translation(rotation, t)
        })
        .collect();
    let count = 3001; // not a multiple of the workgroup
    let vertices: Vec<GpuVertex> = (0..count)
        .map(|_| {
            let n = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::X);
            GpuVertex {
                position: [
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-2.0..2.0),
                ],
                material: rng.random_range(0..9),
                normal: n.to_array(),
                object: rng.random_range(0..bodies as u32),
            }
        })
        .collect();
    let storage = ash::vk::BufferUsageFlags::STORAGE_BUFFER;
    let objects = Buffer::with_data(&ctx, "test.objects", storage, bytemuck::cast_slice(&vertices)).unwrap();
    let pose_buffer = Buffer::with_data(&ctx, "test.poses", storage, bytemuck::cast_slice(&poses)).unwrap();
    let world = poisoned_world(&ctx, count + 5);
    let pass = SimTransformPass::new(&ctx).unwrap();
    ctx.one_shot(|cmd| pass.record(cmd, &objects, &pose_buffer, &world, count as u32))
        .unwrap();
    let gpu: Vec<GpuVertex> = bytemuck::pod_collect_to_vec(&world.read().unwrap());
    for (i, v) in vertices.iter().enumerate() {
        let want = speculum::cpu_ref::sim::transform(v, &poses);
        let got = &gpu[i];
        assert_eq!((got.material, got.object), (want.material, want.object), "vertex {i}");
        let (p, q) = (Vec3::from(got.position), Vec3::from(want.position));
        assert!((p - q).length() <= 1e-5 * q.length() + 1e-5, "vertex {i}: {p} vs {q}");
        let (n, m) = (Vec3::from(got.normal), Vec3::from(want.normal));
        assert!((n - m).length() <= 1e-5, "vertex {i}: normal {n} vs {m}");
    }
    // Past the count nothing is written.
    for v in &gpu[count..count + 5] {
        assert_eq!((v.material, v.object), (POISON.material, POISON.object));
    }
}

/// `sim.cloth` against `cpu_ref::cloth`: a 23x23 sheet with its corners pinned, its
/// particles randomly displaced (and moving), pressed onto a sphere and the floor, six
/// steps of 8 iterations; the particles after every step and the vertices (normals)
/// after the last. Tolerance: 1e-4 absolute on positions (1e-3 of the sheet's
/// spacing; each iteration's lengths and divisions round differently in f32), 1e-3 on
/// normals; outputs poisoned first.
#[test]
fn cloth_steps_match_cpu_reference() {
    use speculum::passes::sim_cloth::{ClothPass, ClothState};
    use speculum::scene::cloth::{Cloth, Particle, Pins};
    let ctx = common::context();
    let mut rng = common::rng(23);
    let cloth = Cloth {
        size: 2.0,
        resolution: 23,
        // Just above the sphere's top and the floor: both collide from the first step.
        center: Vec3::new(0.1, 1.23, -0.2),
        pins: Pins::Corners,
        stiffness: 0.8,
        iterations: 8,
        material: 3,
        spheres: vec![glam::Vec4::new(0.0, 0.7, 0.0, 0.5), glam::Vec4::new(0.8, 0.2, 0.6, 0.3)],
        floor_y: 1.16,
    };
    let dt = 1.0 / 60.0;
    let base = 17;
    let mut state = ClothState::new(&ctx, &cloth, dt, base, Vec3::ZERO).unwrap();
    // Random displacements and velocities (pinned particles too: they just do not move).
    let mut cpu: Vec<Particle> = cloth
        .particles()
        .into_iter()
        .map(|mut p| {
            let j = Vec3::new(
                rng.random_range(-0.03..0.03),
                rng.random_range(-0.05..0.05),
                rng.random_range(-0.03..0.03),
            );
            let v = Vec3::new(
                rng.random_range(-0.01..0.01),
                rng.random_range(-0.02..0.0),
                rng.random_range(-0.01..0.01),
            );
            p.pos = (Vec3::from(p.pos) + j).to_array();
            p.prev = (Vec3::from(p.pos) - v).to_array();
            p
        })
        .collect();
    for b in &state.particles {
        b.write(bytemuck::cast_slice(&cpu)).unwrap();
    }
    state.push.stiffness = 0.8;
    let n = cpu.len();
    let world = poisoned_world(&ctx, base as usize + n + 3);
    let pass = ClothPass::new(&ctx).unwrap();
    let spheres = cloth.spheres.clone();
    for step in 0..6 {
        ctx.one_shot(|cmd| pass.record(cmd, &state, &world)).unwrap();
        speculum::cpu_ref::cloth::integrate(&mut cpu, &state.push);
        for _ in 0..cloth.passes() {
            cpu = speculum::cpu_ref::cloth::relax(&cpu, &state.push, &spheres);
        }
        let gpu: Vec<Particle> = bytemuck::pod_collect_to_vec(&state.particles[0].read().unwrap());
        for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            let d = (Vec3::from(g.pos) - Vec3::from(c.pos)).length();
            assert!(d <= 1e-4, "step {step} particle {i}: {:?} vs {:?}", g.pos, c.pos);
            assert_eq!(g.inv_mass, c.inv_mass);
        }
    }
    let want = speculum::cpu_ref::cloth::vertices(&cpu, &state.push);
    let got: Vec<GpuVertex> = bytemuck::pod_collect_to_vec(&world.read().unwrap());
    for v in &got[..base as usize] {
        assert_eq!(
            v.material, POISON.material,
            "nothing before the cloth's vertices is written"
        );
    }
    for (i, (g, w)) in got[base as usize..base as usize + n].iter().zip(&want).enumerate() {
        assert_eq!(g.material, 3, "vertex {i}");
        assert!(
            (Vec3::from(g.normal) - Vec3::from(w.normal)).length() <= 1e-3,
            "vertex {i}: {:?} vs {:?}",
            g.normal,
            w.normal
        );
    }
    assert_eq!(got[base as usize + n].material, POISON.material);
    // The sheet moved.
    let start = cloth.particles();
    assert!((Vec3::from(cpu[n / 2].pos) - Vec3::from(start[n / 2].pos)).length() > 0.01);
}

/// `sim.skin` against `scene::animation::skin_vertex` on a random skin: 3,001 vertices
/// (not a multiple of the workgroup), 40 joints of random rotation, non-uniform scale
/// and translation, up to four influences a vertex (repeated joints, zero weights, and
/// some vertices with none, which keep their bind pose). Tolerance: positions 1e-5 of
/// their size + 1e-5 (the blend's sums round in another order on a GPU); normals 2e-3
/// where the blend is well conditioned (|det| > 0.05 of its 3x3: a blend of opposed
/// rotations nearly flattens it, and the inverse transpose then amplifies rounding).
/// Outputs poisoned; nothing past the count is written.
#[test]
fn skin_matches_cpu_reference() {
    use speculum::gpu_types::GpuInfluence;
    use speculum::passes::sim_skin::SimSkinPass;
    use speculum::scene::animation::skin_vertex;
    let ctx = common::context();
    let mut rng = common::rng(41);
    let random_vec = |rng: &mut rand::rngs::StdRng, r: f32| {
        Vec3::new(
            rng.random_range(-r..r),
            rng.random_range(-r..r),
            rng.random_range(-r..r),
        )
    };
    let joints: Vec<Mat4> = (0..40)
        .map(|_| {
            let axis = random_vec(&mut rng, 1.0).normalize_or(Vec3::Y);
            let scale = Vec3::new(
                rng.random_range(0.5..2.0),
                rng.random_range(0.5..2.0),
                rng.random_range(0.5..2.0),
            );
            Mat4::from_scale_rotation_translation(
                scale,
                Quat::from_axis_angle(axis, rng.random_range(-3.2..3.2)),
                random_vec(&mut rng, 5.0),
            )
        })
        .collect();
    let count = 3001;
    let vertices: Vec<GpuVertex> = (0..count)
        .map(|_| GpuVertex {
            position: random_vec(&mut rng, 2.0).to_array(),
            material: rng.random_range(0..9),
            normal: random_vec(&mut rng, 1.0).normalize_or(Vec3::X).to_array(),
            object: 0,
        })
        .collect();
    let influences: Vec<GpuInfluence> = (0..count)
        .map(|_| {
            let j: [u16; 4] = std::array::from_fn(|_| rng.random_range(0..40));
            let none = rng.random_bool(0.05);
            let w: [f32; 4] = std::array::from_fn(|_| {
                if none || rng.random_bool(0.3) {
                    0.0
                } else {
                    rng.random_range(0.0..1.0)
                }
            });
            GpuInfluence::new(j, w)
        })
        .collect();
    let storage = ash::vk::BufferUsageFlags::STORAGE_BUFFER;
    let buffer = |name: &str, bytes: &[u8]| Buffer::with_data(&ctx, name, storage, bytes).unwrap();
    let objects = buffer("test.objects", bytemuck::cast_slice(&vertices));
    let influence_buffer = buffer("test.influences", bytemuck::cast_slice(&influences));
    let joint_buffer = buffer("test.joints", bytemuck::cast_slice(&joints));
    // The model's vertices start at `first` in the world vertices (after others').
    let first = 3;
    let world = poisoned_world(&ctx, first + count + 5);
    let pass = SimSkinPass::new(&ctx).unwrap();
    let buffers = (&objects, &influence_buffer, &joint_buffer);
    ctx.one_shot(|cmd| pass.record(cmd, buffers, &world, first as u32, count as u32))
        .unwrap();
    let all: Vec<GpuVertex> = bytemuck::pod_collect_to_vec(&world.read().unwrap());
    let gpu = &all[first..];
    let (mut normals, mut still) = (0, 0);
    for (i, (v, f)) in vertices.iter().zip(&influences).enumerate() {
        let (p, n) = (Vec3::from(v.position), Vec3::from(v.normal));
        let (q, m) = skin_vertex(p, n, f.joint_indices(), f.weights, &joints);
        let got = &gpu[i];
        assert_eq!((got.material, got.object), (v.material, v.object), "vertex {i}");
        let gp = Vec3::from(got.position);
        assert!((gp - q).length() <= 1e-5 * q.length() + 1e-5, "vertex {i}: {gp} vs {q}");
        still += (q == p) as usize;
        let total: f32 = f.weights.iter().sum();
        let blend: Mat4 = (0..4)
            .filter(|&k| f.weights[k] != 0.0)
            .map(|k| joints[f.joint_indices()[k] as usize] * (f.weights[k] / total.max(1e-30)))
            .fold(Mat4::ZERO, |a, b| a + b);
        if total == 0.0 || glam::Mat3::from_mat4(blend).determinant().abs() > 0.05 {
            let gn = Vec3::from(got.normal);
            assert!((gn - m).length() <= 2e-3, "vertex {i}: normal {gn} vs {m}");
            normals += 1;
        }
    }
    assert!(normals > count * 4 / 5, "only {normals} normals compared");
    assert!(
        still > count / 50 && still < count / 10,
        "{still} vertices in their bind pose"
    );
    for v in all[..first].iter().chain(&gpu[count..count + 5]) {
        assert_eq!(
            (v.material, v.object),
            (POISON.material, POISON.object),
            "written outside the model's range"
        );
    }
    assert_eq!(ctx.validation_messages(), 0);
}
