//! Random triangle soups for BVH tests and benchmarks.

use crate::gpu_types::GpuVertex;
use glam::Vec3;
use rand::{Rng, SeedableRng};

/// `n` triangles with centres uniform in the cube [-scale, scale]^3 and corners within
/// `size` of their centre (per axis), as a vertex buffer of 3n vertices with indices
/// 0..3n. Deterministic for a seed.
pub fn random_soup(n: usize, scale: f32, size: f32, seed: u64) -> (Vec<GpuVertex>, Vec<u32>) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut vertices = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let c = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * scale;
        for _ in 0..3 {
            let o = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * size;
            vertices.push(GpuVertex {
                position: (c + o).to_array(),
                material: 0,
                normal: [0.0, 1.0, 0.0],
                object: 0,
            });
        }
    }
    (vertices, (0..3 * n as u32).collect())
}

/// Triangle size that makes a soup of `n` triangles in [-1, 1]^3 about as dense as a
/// typical scene: corners within ~half the mean spacing of the centres.
pub fn default_size(n: usize) -> f32 {
    (8.0 / n.max(1) as f32).cbrt() * 0.5
}
