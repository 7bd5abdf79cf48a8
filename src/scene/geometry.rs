//! Procedural triangle meshes: quads, boxes and UV spheres, with outward normals,
//! texture coordinates and counter-clockwise winding seen from outside.

use glam::{Mat4, Vec2, Vec3};

/// An indexed triangle mesh in its own space.
#[derive(Clone, Debug, Default)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex (u right, v down the image: glTF's and Vulkan's
    /// convention), or empty when the mesh has none (all (0, 0)).
    pub uvs: Vec<Vec2>,
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
            // The image upright seen from above, +z towards the viewer.
            uvs: vec![Vec2::ZERO, Vec2::Y, Vec2::ONE, Vec2::X],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    /// An axis-aligned box of the given full extents centred at the origin, with flat
    /// faces (24 vertices), each face mapped to the whole texture.
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
                mesh.uvs.push(Vec2::new(0.5 + 0.5 * su, 0.5 - 0.5 * sv));
            }
            mesh.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        mesh
    }

    /// A UV sphere of `radius` with `segments` around and `rings` from pole to pole;
    /// u runs once around (east from +x), v from the north pole (0) to the south (1).
    pub fn sphere(radius: f32, segments: u32, rings: u32) -> Self {
        let mut mesh = Self::default();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
                mesh.positions.push(n * radius);
                mesh.normals.push(n);
                mesh.uvs
                    .push(Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
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

/// Faces meeting at a smaller angle than this share a smoothed normal in
/// `smooth_normals`; a sharper edge stays a crease (a cube keeps flat faces).
pub const CREASE_ANGLE_DEG: f32 = 60.0;

/// Vertex normals for a mesh that has none: equal positions are welded first, then
/// each corner of a triangle gets the angle-weighted mean of the normals of the faces
/// around its vertex that meet its own face at less than `crease_deg` (Thürmer & Wüthrich
/// 1998, "Computing vertex normals from polygonal facets"). Corners whose normals or
/// texture coordinates (`uvs`, per input vertex, or empty) differ get vertices of their
/// own. Degenerate triangles keep their corners' normals from their neighbours (or +y
/// alone).
pub fn smooth_normals(positions: &[Vec3], uvs: &[Vec2], indices: &[u32], crease_deg: f32) -> TriMesh {
    use std::collections::HashMap;
    // Weld: one id per distinct position (bitwise; -0 and 0 alike).
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let welded: Vec<u32> = positions
        .iter()
        .map(|&p| {
            let n = ids.len() as u32;
            *ids.entry(key(p)).or_insert(n)
        })
        .collect();
    let tris: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let face: Vec<Vec3> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    // The interior angle of each corner (radians).
    let corner_angle = |t: &[u32; 3], k: usize| {
        let p = t.map(|i| positions[i as usize]);
        let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        e1.angle_between(e2)
    };
    let mut around: Vec<Vec<(usize, usize)>> = vec![Vec::new(); ids.len()];
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            around[welded[t[k] as usize] as usize].push((ti, k));
        }
    }
    let cos_crease = crease_deg.to_radians().cos();
    let mut out = TriMesh::default();
    let mut made: HashMap<(u32, [u32; 3], [u32; 2]), u32> = HashMap::new();
    let uv_of = |i: u32| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO);
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let w = welded[t[k] as usize];
            let mut n = Vec3::ZERO;
            for &(tj, kj) in &around[w as usize] {
                let nj = face[tj];
                if face[ti] == Vec3::ZERO || face[ti].dot(nj) >= cos_crease {
                    let a = corner_angle(&tris[tj], kj);
                    if a.is_finite() {
                        n += a * nj;
                    }
                }
            }
            let n = n.normalize_or(if face[ti] == Vec3::ZERO { Vec3::Y } else { face[ti] });
            let p = positions[t[k] as usize];
            let uv = uv_of(t[k]);
            let key = (w, n.to_array().map(f32::to_bits), uv.to_array().map(f32::to_bits));
            let index = *made.entry(key).or_insert_with(|| {
                out.positions.push(p);
                out.normals.push(n);
                if !uvs.is_empty() {
                    out.uvs.push(uv);
                }
                out.positions.len() as u32 - 1
            });
            out.indices.push(index);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box given with 8 shared corners keeps flat faces: 24 vertices, each normal one
    /// of the six axes, equal to its face's.
    #[test]
    fn a_shared_corner_cube_keeps_flat_faces() {
        let p: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let indices: Vec<u32> = quads
            .iter()
            .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
            .collect();
        let m = smooth_normals(&p, &[], &indices, CREASE_ANGLE_DEG);
        assert_eq!(m.positions.len(), 24);
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
            let face = (b - a).cross(c - a).normalize();
            for &i in t {
                assert!((m.normals[i as usize] - face).length() < 1e-6);
            }
        }
    }

    /// A finely tessellated sphere with duplicated seam vertices is smoothed across the
    /// seam: welded, every normal points outwards, and no vertex is split.
    #[test]
    fn a_sphere_is_smooth_across_its_seam() {
        let s = TriMesh::sphere(2.0, 24, 12);
        let m = smooth_normals(&s.positions, &[], &s.indices, CREASE_ANGLE_DEG);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(n.dot(p.normalize()) > 0.99, "{p} {n}");
        }
        let distinct: std::collections::HashSet<[u32; 3]> = s
            .indices
            .iter()
            .map(|&i| (s.positions[i as usize] + Vec3::ZERO).to_array().map(f32::to_bits))
            .collect();
        assert_eq!(m.positions.len(), distinct.len(), "one vertex per welded position");
        // With texture coordinates the seam's vertices stay apart (u = 0 and u = 1) but
        // share the smoothed normal, and each keeps its own coordinates.
        let m = smooth_normals(&s.positions, &s.uvs, &s.indices, CREASE_ANGLE_DEG);
        assert_eq!(m.uvs.len(), m.positions.len());
        assert!(m.positions.len() > distinct.len());
        for ((p, n), uv) in m.positions.iter().zip(&m.normals).zip(&m.uvs) {
            assert!(n.dot(p.normalize()) > 0.99, "{p} {n}");
            let k = s.positions.iter().zip(&s.uvs).position(|(q, w)| q == p && w == uv);
            assert!(k.is_some(), "vertex {p} {uv} is one of the input's");
        }
    }
}
