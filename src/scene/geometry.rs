//! Procedural triangle meshes: quads, boxes and UV spheres, with outward normals and
//! counter-clockwise winding seen from outside.

use glam::{Mat4, Vec3};

/// An indexed triangle mesh in its own space.
#[derive(Clone, Debug, Default)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub indices: Vec<u32>,
}

impl TriMesh {
    /// A w×h rectangle centred at the origin in the xz-plane, facing +y.
    pub fn quad(width: f32, depth: f32) -> Self {
        let (x, z) = (0.5 * width, 0.5 * depth);
        Self {
            positions: vec![
                Vec3::new(-x, 0.0, -z),
                Vec3::new(-x, 0.0, z),
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 0.0, -z),
            ],
            normals: vec![Vec3::Y; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    /// An axis-aligned box of the given full extents centred at the origin, with flat
    /// faces (24 vertices).
    pub fn cuboid(size: Vec3) -> Self {
        let h = 0.5 * size;
        let mut mesh = Self::default();
        // Each face: its normal and two tangent axes (u × v = normal, so CCW from outside).
        let faces = [
            (Vec3::X, Vec3::NEG_Z, Vec3::Y),
            (Vec3::NEG_X, Vec3::Z, Vec3::Y),
            (Vec3::Y, Vec3::X, Vec3::NEG_Z),
            (Vec3::NEG_Y, Vec3::X, Vec3::Z),
            (Vec3::Z, Vec3::X, Vec3::Y),
            (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
        ];
        for (n, u, v) in faces {
            let base = mesh.positions.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push((n + u * su + v * sv) * h);
                mesh.normals.push(n);
            }
            mesh.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        mesh
    }

    /// A UV sphere of `radius` with `segments` around and `rings` from pole to pole.
    pub fn sphere(radius: f32, segments: u32, rings: u32) -> Self {
        let mut mesh = Self::default();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
                mesh.positions.push(n * radius);
                mesh.normals.push(n);
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, (r + 1) * row + s);
                // Skip the degenerate triangles at the poles.
                if r != 0 {
                    mesh.indices.extend([a, b, a + 1]);
                }
                if r != rings - 1 {
                    mesh.indices.extend([a + 1, b, b + 1]);
                }
            }
        }
        mesh
    }

    /// The mesh moved by `m` (normals by its inverse transpose).
    pub fn transformed(mut self, m: Mat4) -> Self {
        let nm = m.inverse().transpose();
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = nm.transform_vector3(*n).normalize_or(Vec3::Y);
        }
        self
    }
}
