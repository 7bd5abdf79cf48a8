//! Reference of the cloth kernels (`glsl/cloth_*.comp`, `glsl/shared/cloth.glsl`).

use crate::gpu_types::GpuVertex;
use crate::scene::cloth::{ClothPush, Particle};
use glam::{IVec2, Vec3, Vec4};

const NEIGHBOURS: [(i32, i32); 12] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (-1, -1),
    (1, -1),
    (-1, 1),
    (2, 0),
    (-2, 0),
    (0, 2),
    (0, -2),
];
/// The shader's `1.41421356` is the f32 nearest sqrt(2), as this is.
const D: f32 = std::f32::consts::SQRT_2;
const REST: [f32; 12] = [1.0, 1.0, 1.0, 1.0, D, D, D, D, 2.0, 2.0, 2.0, 2.0];

/// `cloth_integrate`.
pub fn integrate(particles: &mut [Particle], pc: &ClothPush) {
    for p in particles.iter_mut() {
        if p.inv_mass > 0.0 {
            let (pos, prev) = (Vec3::from(p.pos), Vec3::from(p.prev));
            let velocity = (pos - prev) * pc.damping;
            p.prev = p.pos;
            p.pos = (pos + velocity + Vec3::new(0.0, -pc.gravity * pc.dt * pc.dt, 0.0)).to_array();
        }
    }
}

/// `cloth_relax`: one Jacobi iteration from `src`.
pub fn relax(src: &[Particle], pc: &ClothPush, spheres: &[Vec4]) -> Vec<Particle> {
    let g = IVec2::new(pc.grid[0] as i32, pc.grid[1] as i32);
    (0..src.len())
        .map(|i| {
            let mut p = src[i];
            if p.inv_mass <= 0.0 {
                return p;
            }
            let at = IVec2::new(i as i32 % g.x, i as i32 / g.x);
            let mut pos = Vec3::from(p.pos);
            let (mut sum, mut count) = (Vec3::ZERO, 0.0f32);
            for (k, (dx, dy)) in NEIGHBOURS.iter().enumerate() {
                let q = at + IVec2::new(*dx, *dy);
                if q.x < 0 || q.y < 0 || q.x >= g.x || q.y >= g.y {
                    continue;
                }
                let o = &src[(q.y * g.x + q.x) as usize];
                let d = Vec3::from(o.pos) - pos;
                let len = d.length();
                let w = p.inv_mass / (p.inv_mass + o.inv_mass);
                if len > 1e-9 {
                    sum += d * ((len - REST[k] * pc.spacing) / len * w);
                }
                count += 1.0;
            }
            if count > 0.0 {
                pos += sum * (pc.stiffness / count);
            }
            for s in &spheres[..pc.sphere_count as usize] {
                let c = s.truncate();
                let r = s.w + pc.margin;
                let d = pos - c;
                let len = d.length();
                if len < r && len > 1e-9 {
                    pos = c + d * (r / len);
                }
            }
            pos.y = pos.y.max(pc.floor_y + pc.margin);
            p.pos = pos.to_array();
            p
        })
        .collect()
}

/// `cloth_vertices`: the cloth's vertices (written at `vertex_base`).
pub fn vertices(particles: &[Particle], pc: &ClothPush) -> Vec<GpuVertex> {
    let (n, m) = (pc.grid[0] as i32, pc.grid[1] as i32);
    let at = |x: i32, y: i32| Vec3::from(particles[(y * n + x) as usize].pos);
    (0..particles.len() as i32)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let du = at((x + 1).min(n - 1), y) - at((x - 1).max(0), y);
            let dv = at(x, (y + 1).min(m - 1)) - at(x, (y - 1).max(0));
            let nrm = dv.cross(du);
            let len = nrm.length();
            GpuVertex {
                position: particles[i as usize].pos,
                material: pc.material,
                normal: if len > 1e-12 {
                    (nrm / len).to_array()
                } else {
                    [0.0, 1.0, 0.0]
                },
                object: 0,
            }
        })
        .collect()
}
