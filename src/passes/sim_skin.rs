//! `sim.skin`: linear blend skinning of skinned meshes' vertices into a world-space
//! vertex buffer (`glsl/sim_skin.comp`), from their bind-pose vertices, their
//! influences (`GpuInfluence`) and the joints' skinning matrices, which the host poses
//! (`scene::animated::Animated::matrices`) and `Skinned` stages per frame slot.
//! CPU reference: `scene::animation::skin_vertex` (tests/suite/sim.rs).

use crate::error::Result;
use crate::gpu_types::{GpuInfluence, GpuVertex};
use crate::shader_defines::LBVH_WG;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource, Staged};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

pub const NAME: &str = "sim.skin";

/// The most skinned vertices one dispatch covers (65535 workgroups of `LBVH_WG`).
pub const MAX_VERTICES: u32 = 65535 * LBVH_WG;

/// An animated model's vertices on the GPU: bind pose (`GpuVertex`), influences
/// (`GpuInfluence`), its joint palette's matrices (written by the host per frame slot),
/// and where its vertices start in the world-space vertex buffer.
pub struct Skinned {
    objects: Buffer,
    influences: Buffer,
    joints: Staged,
    pub vertex_count: u32,
    pub first: u32,
}

impl Skinned {
    /// `vertices` (at most `MAX_VERTICES`) with their `influences`, `joints` palette
    /// entries, written to the world vertices from `first` on; one frame slot.
    pub fn new(
        ctx: &Arc<Context>,
        vertices: &[GpuVertex],
        influences: &[GpuInfluence],
        joints: usize,
        first: u32,
    ) -> Result<Self> {
        assert_eq!(vertices.len(), influences.len(), "one influence per vertex");
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let bytes = (joints * std::mem::size_of::<Mat4>()) as u64;
        Ok(Self {
            objects: Buffer::with_data(ctx, "skinned.objects", storage, bytemuck::cast_slice(vertices))?,
            influences: Buffer::with_data(ctx, "skinned.influences", storage, bytemuck::cast_slice(influences))?,
            joints: Staged::new(ctx, "skinned.joints", bytes, storage)?,
            vertex_count: vertices.len() as u32,
            first,
        })
    }

    /// Frame slots (one staging buffer each); the GPU must be idle.
    pub fn set_slots(&mut self, n: usize) -> Result<()> {
        self.joints.set_slots(n)
    }

    /// Writes the palette's `matrices` for the next frame recorded with `slot`, whose
    /// previous frame must have finished.
    pub fn write(&mut self, slot: usize, matrices: &[Mat4]) {
        self.joints.write(slot, bytemuck::cast_slice(matrices));
    }
}

pub struct SimSkinPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
}

impl SimSkinPass {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<[u32; 2]>(ctx, NAME, shaders::SIM_SKIN_COMP)?,
        })
    }

    /// Records the copy of `slot`'s matrices of `model` to the GPU, then the skinning
    /// of its vertices into `world` (as `record`).
    pub fn record_posed(&self, cmd: vk::CommandBuffer, model: &Skinned, slot: usize, world: &Buffer) {
        model.joints.record_upload(cmd, slot);
        let buffers = (&model.objects, &model.influences, &model.joints.device);
        self.record(cmd, buffers, world, model.first, model.vertex_count);
    }

    /// Records the skinning of `count` (at most `MAX_VERTICES`) vertices of `objects`
    /// (`GpuVertex`, bind pose) by their `influences` (`GpuInfluence`) and `joints`
    /// (one `Mat4` per joint, visible to compute reads) into `world` from vertex
    /// `first` on; `world` ends visible to its readers: the raster passes' vertex
    /// shaders and the compute passes.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        (objects, influences, joints): (&Buffer, &Buffer, &Buffer),
        world: &Buffer,
        first: u32,
        count: u32,
    ) {
        assert!(count <= MAX_VERTICES, "{count} skinned vertices in one dispatch");
        let d = &self.ctx.device;
        // WAR: the previous frame's reads of the world vertices finish before they are
        // overwritten.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_WRITE);
        self.pipeline.dispatch(
            cmd,
            &[
                ("objects", Resource::Buffer(objects)),
                ("influences", Resource::Buffer(influences)),
                ("joints", Resource::Buffer(joints)),
                ("world", Resource::Buffer(world)),
            ],
            &[count, first],
            Groups::Cover([count, 1, 1]),
        );
        // RAW: the vertex shaders and the compute passes read the skinned vertices.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ANY_SHADER_READ);
    }
}
