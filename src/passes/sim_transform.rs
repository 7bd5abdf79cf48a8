//! `sim.transform`: writes the dynamic geometry's world-space vertex buffer from its
//! object-space vertices and the bodies' poses, every frame of a dynamic scene.

use crate::error::Result;
use crate::shader_defines::LBVH_WG;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource};
use std::sync::Arc;

pub const NAME: &str = "sim.transform";

/// The most dynamic vertices one dispatch covers (65535 workgroups of `LBVH_WG`).
pub const MAX_VERTICES: u32 = 65535 * LBVH_WG;

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

    /// Records the transform of `count` vertices of `objects` (`GpuVertex`, `object` =
    /// the body) by `poses` (one `Mat4` per body, visible to compute reads) into
    /// `world`. `world` ends visible to its readers: the raster passes' vertex shaders
    /// and the compute passes (BVH build, traversal).
    pub fn record(&self, cmd: ash::vk::CommandBuffer, objects: &Buffer, poses: &Buffer, world: &Buffer, count: u32) {
        let d = &self.ctx.device;
        // WAR: the previous frame's reads of the world vertices (raster, BVH, traversal)
        // finish before they are overwritten.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::COMPUTE_WRITE);
        self.pipeline.dispatch(
            cmd,
            &[
                Resource::Buffer(objects),
                Resource::Buffer(poses),
                Resource::Buffer(world),
            ],
            &count,
            Groups::Cover([count, 1, 1]),
        );
        // RAW: the vertex shaders and the compute passes read the moved vertices.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::ANY_SHADER_READ);
    }
}
