//! Reference of `glsl/sim_transform.comp`.

use crate::gpu_types::GpuVertex;
use glam::{Mat3, Mat4, Vec3};

/// The world-space vertex of object-space `v` under its body's pose.
pub fn transform(v: &GpuVertex, poses: &[Mat4]) -> GpuVertex {
    let m = poses[v.object as usize];
    GpuVertex {
        position: m.transform_point3(Vec3::from(v.position)).to_array(),
        normal: (Mat3::from_mat4(m) * Vec3::from(v.normal)).normalize().to_array(),
        ..*v
    }
}
