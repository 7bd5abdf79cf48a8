//! The BVH over geometry that moves every frame, and its policy: rebuilt each frame,
//! or refit (new boxes, same tree) while the topology holds — deforming cloth — and
//! rebuilt all the same every `rebuild_every` frames, since a refit tree's boxes grow
//! looser as the geometry drifts from where the tree was built.
//! Over rigid bodies alone, a rebuild orders the bodies and keeps each body's own order
//! of its triangles (`rigid`) instead of sorting every triangle.
//! No kernel of its own: a policy over `LbvhBuilder`'s builds and refit.

use super::rigid::RigidKeys;
use super::{Bvh, Geometry, LbvhBuilder, MortonBits, RefitSchedule};
use super::{BvhKind, REFIT};
use crate::error::Result;
use crate::vk::barrier::{self, access};
use crate::vk::{Context, GpuTimer};
use ash::vk;
use std::sync::Arc;

pub struct DynamicBvh {
    ctx: Arc<Context>,
    pub bvh: Bvh,
    /// Refit instead of rebuilding (same triangles, moved vertices).
    refit: bool,
    rebuild_every: u32,
    /// Frames since the BVH was last built (0: build in the next frame).
    since_build: u32,
    /// The refit order of the tree as last built (`after_frame` makes it).
    schedule: Option<RefitSchedule>,
    /// Rebuild from the bodies' order (`with_rigid`), whose poses `record` gets.
    rigid: Option<RigidKeys>,
}

impl DynamicBvh {
    /// Every timer scope `record` may open, in order.
    pub const SCOPES: [&'static str; 5] = {
        let [bounds, morton, sort, fit] = BvhKind::Lbvh.stages();
        [bounds, morton, sort, fit, REFIT]
    };

    /// A BVH over `tri_count` triangles, refit between builds when `refit` is set (the
    /// triangles' topology never changes), rebuilt at least every `rebuild_every`
    /// frames all the same.
    pub fn new(ctx: &Arc<Context>, tri_count: u32, refit: bool, rebuild_every: u32) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            bvh: Bvh::new(ctx, tri_count, MortonBits::Bits30)?,
            refit,
            rebuild_every,
            since_build: 0,
            schedule: None,
            rigid: None,
        })
    }

    /// Rebuilds from the bodies' order and their own (`rigid::RigidKeys`, over these
    /// triangles): `record` then needs the bodies' poses.
    pub fn with_rigid(mut self, rigid: RigidKeys) -> Self {
        self.rigid = Some(rigid);
        self
    }

    /// The next frame builds the tree afresh.
    pub fn reset(&mut self) {
        self.since_build = 0;
        self.schedule = None;
    }

    /// Records this frame's update of the tree over `geom` (visible to compute reads):
    /// a refit by the schedule when the policy allows one, else a full build (whose
    /// schedule `after_frame` then makes). Each stage under its `lbvh.*` scope; the
    /// nodes end visible to all later reads.
    /// A rigid rebuild (`with_rigid`) reads `poses` (one `Mat4` per body, visible to
    /// compute reads); other trees ignore it.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        timer: &mut GpuTimer,
        builder: &LbvhBuilder,
        geom: Geometry<'_>,
        poses: &crate::vk::Buffer,
    ) {
        // WAR: the previous frame's traversal of the dynamic BVH is done before it changes.
        barrier::global(&self.ctx.device, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        match &self.schedule {
            Some(schedule) if self.refit && self.since_build < self.rebuild_every => {
                builder.record_refit_scheduled(cmd, timer, geom, &self.bvh, schedule);
                self.since_build += 1;
            }
            _ => {
                match &self.rigid {
                    Some(rigid) => builder.record_build_rigid(cmd, timer, geom, &self.bvh, rigid, poses),
                    None => builder.record_build(cmd, timer, geom, &self.bvh),
                }
                self.since_build = 1;
                self.schedule = None;
            }
        }
    }

    /// After a frame has finished on the GPU: a refit tree that was just built gets
    /// its refit schedule, made from the tree (waits for the GPU: every frame recorded
    /// without a schedule rebuilds, so the tree then is the last one built).
    pub fn after_frame(&mut self) -> Result<()> {
        if self.refit && self.schedule.is_none() {
            self.ctx.wait_idle()?;
            self.schedule = Some(RefitSchedule::of(&self.ctx, &self.bvh)?);
        }
        Ok(())
    }
}
