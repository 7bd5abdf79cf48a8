//! Cloth: a square grid of particles, pinned or free, stepped on the GPU by
//! position-based dynamics (`sim.cloth`: Verlet, then Jacobi iterations of its
//! structural, shear and bend constraints with the colliders after each); its
//! triangles keep their topology, so its BVH can be refit. The CPU reference is
//! `cpu_ref::cloth`.

use crate::gpu_types::GpuVertex;
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// One particle (std430, 32 bytes; `glsl/shared/cloth.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Particle {
    pub pos: [f32; 3],
    /// 0: pinned.
    pub inv_mass: f32,
    /// The position one step ago.
    pub prev: [f32; 3],
    pub _pad0: f32,
}

/// The constants of one step (`CLOTH_PUSH_BLOCK`, 48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClothPush {
    pub grid: [u32; 2],
    pub dt: f32,
    pub gravity: f32,
    pub damping: f32,
    pub spacing: f32,
    pub stiffness: f32,
    pub floor_y: f32,
    pub margin: f32,
    pub sphere_count: u32,
    pub vertex_base: u32,
    pub material: u32,
}

const _: () = assert!(std::mem::size_of::<Particle>() == 32);
const _: () = assert!(std::mem::size_of::<ClothPush>() == 48);

/// Which particles hold still.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pins {
    None,
    /// The two corners of the first row.
    Corners,
    /// The whole first row.
    Edge,
}

/// A cloth of the scene: a square sheet, horizontal at first.
#[derive(Clone, Debug, PartialEq)]
pub struct Cloth {
    /// Side length in world units.
    pub size: f32,
    /// Particles per side (at least 2).
    pub resolution: u32,
    /// Where the sheet's centre starts.
    pub center: Vec3,
    pub pins: Pins,
    /// Jacobi relaxation factor in (0, 1].
    pub stiffness: f32,
    /// Constraint iterations per step (rounded up to even).
    pub iterations: u32,
    pub material: u32,
    /// Spheres it collides with (xyz centre, w radius) and a floor plane.
    pub spheres: Vec<Vec4>,
    pub floor_y: f32,
}

/// Most particles per side.
pub const MAX_RESOLUTION: u32 = 512;

impl Cloth {
    pub fn spacing(&self) -> f32 {
        self.size / (self.resolution - 1) as f32
    }

    /// The particles at rest, row by row (u along x, v along z).
    pub fn particles(&self) -> Vec<Particle> {
        let n = self.resolution;
        (0..n * n)
            .map(|i| {
                let (x, y) = (i % n, i / n);
                let p = self.center
                    + Vec3::new(
                        (x as f32 / (n - 1) as f32 - 0.5) * self.size,
                        0.0,
                        (y as f32 / (n - 1) as f32 - 0.5) * self.size,
                    );
                let pinned = match self.pins {
                    Pins::None => false,
                    Pins::Corners => y == 0 && (x == 0 || x == n - 1),
                    Pins::Edge => y == 0,
                };
                Particle {
                    pos: p.to_array(),
                    inv_mass: if pinned { 0.0 } else { 1.0 },
                    prev: p.to_array(),
                    _pad0: 0.0,
                }
            })
            .collect()
    }

    /// Two triangles per grid cell, indices from 0; texture coordinates per particle.
    pub fn mesh(&self) -> (Vec<u32>, Vec<[f32; 2]>) {
        let n = self.resolution;
        let mut indices = Vec::with_capacity(((n - 1) * (n - 1) * 6) as usize);
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let a = y * n + x;
                let (b, c, d) = (a + 1, a + n, a + n + 1);
                indices.extend([a, c, b, b, c, d]);
            }
        }
        let uvs = (0..n * n)
            .map(|i| [(i % n) as f32 / (n - 1) as f32, (i / n) as f32 / (n - 1) as f32])
            .collect();
        (indices, uvs)
    }

    /// The step constants at time step `dt`, the vertices starting at `vertex_base`.
    pub fn push(&self, dt: f32, vertex_base: u32) -> ClothPush {
        ClothPush {
            grid: [self.resolution; 2],
            dt,
            gravity: 9.81,
            damping: 0.995,
            spacing: self.spacing(),
            stiffness: self.stiffness,
            floor_y: self.floor_y,
            // Keeps the sheet off the colliders' tessellated surfaces.
            margin: 0.3 * self.spacing(),
            sphere_count: self.spheres.len() as u32,
            vertex_base,
            material: self.material,
        }
    }

    /// Jacobi iterations per step: an even count, so the result ends where it began.
    pub fn passes(&self) -> u32 {
        self.iterations.max(1).next_multiple_of(2)
    }

    /// The flat sheet's vertices (normal +y) in the dynamic vertex layout.
    pub fn rest_vertices(&self) -> Vec<GpuVertex> {
        self.particles()
            .iter()
            .map(|p| GpuVertex {
                position: p.pos,
                material: self.material,
                normal: [0.0, 1.0, 0.0],
                object: 0,
            })
            .collect()
    }
}
