//! `sim.transform`: writes the dynamic geometry's world-space vertex buffer from its
//! object-space vertices and the bodies' poses, every frame of a dynamic scene. The
//! poses come from the host: `RigidBodies` keeps one staging buffer per frame slot (a
//! frame in flight still copies from its own while the next one's are written), and
//! `record_posed` copies the slot's poses in before the transform.
//! CPU reference: `cpu_ref::sim::transform` (tests/suite/sim.rs).

use crate::error::Result;
use crate::shader_defines::LBVH_WG;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource, Staged};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

pub const NAME: &str = "sim.transform";

/// The most dynamic vertices one dispatch covers (65535 workgroups of `LBVH_WG`).
pub const MAX_VERTICES: u32 = 65535 * LBVH_WG;

/// The rigid bodies on the GPU: their vertices in their own spaces (`GpuVertex`,
/// `object` = the body), and their poses, written by the host per frame slot.
pub struct RigidBodies {
    objects: Buffer,
    poses: Staged,
    /// Vertices the transform moves.
    pub vertex_count: u32,
}

impl RigidBodies {
    /// The first `count` of `vertices` (at most `MAX_VERTICES`), those of `bodies`
    /// bodies, with one frame slot.
    pub fn new(
        ctx: &Arc<Context>,
        vertices: &[crate::gpu_types::GpuVertex],
        count: u32,
        bodies: usize,
    ) -> Result<Self> {
        let bytes = (bodies * std::mem::size_of::<Mat4>()) as u64;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            objects: Buffer::with_data(
                ctx,
                "dynamic.objects",
                storage | crate::vk::accel::input_usage(ctx),
                bytemuck::cast_slice(vertices),
            )?,
            poses: Staged::new(ctx, "dynamic.poses", bytes, storage)?,
            vertex_count: count,
        })
    }

    /// Frame slots (one staging buffer each); the GPU must be idle.
    pub fn set_slots(&mut self, n: usize) -> Result<()> {
        self.poses.set_slots(n)
    }

    /// The bodies' vertices in their own spaces.
    pub fn objects(&self) -> &Buffer {
        &self.objects
    }

    /// The poses `record_posed` last copied (one `Mat4` per body), which a rigid
    /// rebuild of the BVH reads.
    pub fn poses(&self) -> &Buffer {
        &self.poses.device
    }

    pub fn slots(&self) -> usize {
        self.poses.slots()
    }

    /// Writes `poses` (one per body) for the next frame recorded with `slot`, whose
    /// previous frame must have finished.
    pub fn write(&mut self, slot: usize, poses: &[Mat4]) {
        self.poses.write(slot, bytemuck::cast_slice(poses));
    }
}

pub struct SimTransformPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
}

impl SimTransformPass {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<u32>(ctx, NAME, shaders::SIM_TRANSFORM_COMP)?,
        })
    }

    /// Records the copy of `slot`'s poses of `bodies` to the GPU, then the transform of
    /// their vertices into `world` (as `record`).
    pub fn record_posed(&self, cmd: vk::CommandBuffer, bodies: &RigidBodies, slot: usize, world: &Buffer) {
        // After the previous frame's compute reads; visible to this one's.
        bodies.poses.record_upload(cmd, slot);
        self.record(cmd, &bodies.objects, &bodies.poses.device, world, bodies.vertex_count);
    }

    /// Records the transform of `count` vertices of `objects` (`GpuVertex`, `object` =
    /// the body) by `poses` (one `Mat4` per body, visible to compute reads) into
    /// `world`. `world` ends visible to its readers: the raster passes' vertex shaders
    /// and the compute passes (BVH build, traversal).
    pub fn record(&self, cmd: vk::CommandBuffer, objects: &Buffer, poses: &Buffer, world: &Buffer, count: u32) {
        let d = &self.ctx.device;
        // WAR: the previous frame's reads of the world vertices (raster, BVH, traversal)
        // finish before they are overwritten.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_WRITE);
        self.pipeline.dispatch(
            cmd,
            &[
                ("objects", Resource::Buffer(objects)),
                ("poses", Resource::Buffer(poses)),
                ("world", Resource::Buffer(world)),
            ],
            &count,
            Groups::Cover([count, 1, 1]),
        );
        // RAW: the vertex shaders and the compute passes read the moved vertices.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ANY_SHADER_READ);
    }
}
