//! Random triangle soups, and a dense closed surface, for BVH tests and benchmarks.

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

/// Triangles of the smallest `bumpy_torus`: a grid of 3 x 3 quads.
pub const BUMPY_TORUS_MIN: usize = 18;

/// A closed, bumpy surface of about `n` triangles (at least `BUMPY_TORUS_MIN`): a torus
/// (major radius 1, minor 0.35) whose minor radius carries a few sine bumps, tilted off
/// the axes, as a grid of `nu` x `nv` quads (`nu` about 2.5 `nv`) of two triangles
/// each over shared vertices, so exactly `2 nu nv` triangles. A scanned model's class:
/// small, even, connected triangles on one surface, where a soup's are scattered
/// through a volume. Deterministic.
pub fn bumpy_torus(n: usize) -> (Vec<GpuVertex>, Vec<u32>) {
    use std::f32::consts::TAU;
    let nv = ((n as f64 / 5.0).sqrt().round() as usize).max(3);
    let nu = ((n as f64 / (2.0 * nv as f64)).round() as usize).max(3);
    let tilt = glam::Quat::from_rotation_x(0.4) * glam::Quat::from_rotation_z(0.3);
    let mut vertices = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = TAU * i as f32 / nu as f32;
        let ring = Vec3::new(u.cos(), u.sin(), 0.0);
        for j in 0..nv {
            let v = TAU * j as f32 / nv as f32;
            let bumps = 0.12 * (5.0 * u).sin() * (3.0 * v).sin()
                + 0.04 * (17.0 * u + 4.0 * v).sin()
                + 0.02 * (41.0 * u - 7.0 * v).sin();
            let out = ring * v.cos() + Vec3::Z * v.sin();
            vertices.push(GpuVertex {
                position: (tilt * (ring + out * 0.35 * (1.0 + bumps))).to_array(),
                material: 0,
                normal: (tilt * out).to_array(),
                object: 0,
            });
        }
    }
    let at = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut indices = Vec::with_capacity(6 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// The surface has the triangles asked for within its grid's rounding, none of
    /// zero area, and is closed: every edge is two triangles', once in each direction.
    #[test]
    fn bumpy_torus_is_closed_and_near_its_count() {
        for n in [BUMPY_TORUS_MIN, 100, 20_000, 871_000] {
            let (v, i) = bumpy_torus(n);
            let tris = i.len() / 3;
            let nv = ((n as f64 / 5.0).sqrt().round() as usize).max(3);
            assert!(tris.abs_diff(n) <= nv, "{n}: {tris} triangles");
            let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
            for t in i.chunks(3) {
                let p = [t[0], t[1], t[2]].map(|k| Vec3::from(v[k as usize].position));
                assert!(
                    (p[1] - p[0]).cross(p[2] - p[0]).length() > 0.0,
                    "{n}: a degenerate triangle"
                );
                for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    *edges.entry((a, b)).or_default() += 1;
                }
            }
            assert!(
                edges
                    .iter()
                    .all(|(&(a, b), &k)| k == 1 && edges.get(&(b, a)) == Some(&1)),
                "{n}: not closed"
            );
        }
    }
}
