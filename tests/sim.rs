//! The dynamic scene's GPU side against its CPU references: `sim.transform` on random
//! vertices and poses.
//!
//! Tolerance: positions within 1e-5 of their magnitude plus 1e-5 (one matrix-vector
//! product in f32, FMA-contracted or not), normals within 1e-5; material and object
//! ids exactly.

mod common;

use glam::{Mat4, Quat, Vec3};
use rand::Rng;
use speculum::gpu_types::GpuVertex;
use speculum::passes::sim_transform::SimTransformPass;
use speculum::vk::Buffer;

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
    let poison = vec![
        GpuVertex {
            position: [f32::NAN; 3],
            material: 0xdead,
            normal: [-7.0; 3],
            object: 0xbeef,
        };
        count + 5
    ];
    let readable = storage | ash::vk::BufferUsageFlags::TRANSFER_SRC;
    let world = Buffer::with_data(&ctx, "test.world", readable, bytemuck::cast_slice(&poison)).unwrap();
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
        assert_eq!((v.material, v.object), (0xdead, 0xbeef));
    }
    common::assert_no_validation_messages(&ctx);
}
