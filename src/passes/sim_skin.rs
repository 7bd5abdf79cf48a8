//! `sim.skin`: linear blend skinning of skinned meshes' vertices into a world-space
//! vertex buffer (`glsl/sim_skin.comp`), from their bind-pose vertices, their
//! influences (`GpuInfluence`) and the joints' skinning matrices, which the host poses
//! (`scene::animation::Rig`). Issue 41's pass for animated glTF; not yet in the frame.
//! CPU reference: `scene::animation::skin_vertex` (tests/suite/sim.rs).

use crate::error::Result;
use crate::shader_defines::LBVH_WG;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource};
use std::sync::Arc;

pub const NAME: &str = "sim.skin";

/// The most skinned vertices one dispatch covers (65535 workgroups of `LBVH_WG`).
pub const MAX_VERTICES: u32 = 65535 * LBVH_WG;

pub struct SimSkinPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
}

impl SimSkinPass {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: Pipeline::compute::<u32>(ctx, NAME, shaders::SIM_SKIN_COMP)?,
        })
    }

    /// Records the skinning of `count` (at most `MAX_VERTICES`) vertices of `objects`
    /// (`GpuVertex`, bind pose) by their `influences` (`GpuInfluence`) and `joints`
    /// (one `Mat4` per joint, visible to compute reads) into `world`, which ends
    /// visible to its readers: the raster passes' vertex shaders and the compute passes.
    pub fn record(
        &self,
        cmd: ash::vk::CommandBuffer,
        (objects, influences, joints): (&Buffer, &Buffer, &Buffer),
        world: &Buffer,
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
                Resource::Buffer(objects),
                Resource::Buffer(influences),
                Resource::Buffer(joints),
                Resource::Buffer(world),
            ],
            &count,
            Groups::Cover([count, 1, 1]),
        );
        // RAW: the vertex shaders and the compute passes read the skinned vertices.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ANY_SHADER_READ);
    }
}
