//! `sim.cloth`: one time step of every cloth on the GPU (integrate, Jacobi iterations
//! with the colliders, then the cloth's vertices and normals into the dynamic vertex
//! buffer). Each cloth owns two particle buffers (ping-pong) and its colliders.
//! CPU reference: `cpu_ref::cloth` (`integrate`, `relax`, `vertices`; tests/suite/sim.rs).

use crate::error::Result;
use crate::scene::cloth::{Cloth, ClothPush, Particle};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource};
use ash::vk;
use std::sync::Arc;

pub const NAME: &str = "sim.cloth";

/// One cloth's state on the GPU.
pub struct ClothState {
    pub particles: [Buffer; 2],
    spheres: Buffer,
    pub push: ClothPush,
    passes: u32,
    initial: Vec<Particle>,
}

impl ClothState {
    /// `cloth` at rest; its vertices go to the dynamic buffer from `vertex_base`. It is
    /// simulated relative to `origin` (the renderer's), as the rest of the frame.
    pub fn new(ctx: &Arc<Context>, cloth: &Cloth, dt: f32, vertex_base: u32, origin: glam::Vec3) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let shift = |p: [f32; 3]| (glam::Vec3::from(p) - origin).to_array();
        let initial: Vec<Particle> = cloth
            .particles()
            .into_iter()
            .map(|p| Particle {
                pos: shift(p.pos),
                prev: shift(p.prev),
                ..p
            })
            .collect();
        let bytes: &[u8] = bytemuck::cast_slice(&initial);
        let spheres: Vec<[f32; 4]> = cloth
            .spheres
            .iter()
            .map(|s| (*s - origin.extend(0.0)).to_array())
            .collect();
        let mut push = cloth.push(dt, vertex_base);
        push.floor_y -= origin.y;
        Ok(Self {
            particles: [
                Buffer::with_data(ctx, "cloth.particles", usage, bytes)?,
                Buffer::with_data(ctx, "cloth.particles_b", usage, bytes)?,
            ],
            spheres: Buffer::with_data(ctx, "cloth.spheres", usage, bytemuck::cast_slice(&spheres))?,
            push,
            passes: cloth.passes(),
            initial,
        })
    }

    /// Back to rest (waits for the GPU through the upload).
    pub fn reset(&self) -> Result<()> {
        for b in &self.particles {
            b.write(bytemuck::cast_slice(&self.initial))?;
        }
        Ok(())
    }

    pub fn particle_count(&self) -> u32 {
        self.push.grid[0] * self.push.grid[1]
    }
}

pub struct ClothPass {
    ctx: Arc<Context>,
    integrate: Pipeline,
    relax: Pipeline,
    vertices: Pipeline,
}

impl ClothPass {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            integrate: Pipeline::compute::<ClothPush>(ctx, NAME, shaders::CLOTH_INTEGRATE_COMP)?,
            relax: Pipeline::compute::<ClothPush>(ctx, NAME, shaders::CLOTH_RELAX_COMP)?,
            vertices: Pipeline::compute::<ClothPush>(ctx, NAME, shaders::CLOTH_VERTICES_COMP)?,
        })
    }

    /// Records one step of `cloth` and writes its vertices into `world`. `world` ends
    /// visible to the raster passes and the compute passes.
    pub fn record(&self, cmd: vk::CommandBuffer, cloth: &ClothState, world: &Buffer) {
        let d = &self.ctx.device;
        let n = cloth.particle_count();
        let groups = Groups::Cover([n, 1, 1]);
        let [a, b] = &cloth.particles;
        // WAR: the previous frame's reads of the particles and vertices are done.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_READ_WRITE);
        self.integrate
            .dispatch(cmd, &[("particles", Resource::Buffer(a))], &cloth.push, groups);
        for _ in 0..cloth.passes / 2 {
            for (src, dst) in [(a, b), (b, a)] {
                // RAW: this iteration reads the last one's positions; WAR: ... and
                // overwrites what the one before read.
                barrier::global(d, cmd, access::COMPUTE_READ_WRITE, access::COMPUTE_READ_WRITE);
                self.relax.dispatch(
                    cmd,
                    &[
                        ("src", Resource::Buffer(src)),
                        ("dst", Resource::Buffer(dst)),
                        ("spheres", Resource::Buffer(&cloth.spheres)),
                    ],
                    &cloth.push,
                    groups,
                );
            }
        }
        // RAW: the vertices are made from the final positions.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
        self.vertices.dispatch(
            cmd,
            &[("particles", Resource::Buffer(a)), ("world", Resource::Buffer(world))],
            &cloth.push,
            groups,
        );
        // RAW: the raster passes and the BVH read the cloth's vertices.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ANY_SHADER_READ);
    }
}
