//! `rt.trace`: closest-hit or any-hit traversal of the static and the dynamic BVH for a
//! list of rays. Usable on its own (`TracePass::trace`) for tests and benchmarks;
//! `rt.reflect` walks the same BVHs with the same traversal (`glsl/shared/traverse.glsl`)
//! from its own kernel. `TracePass<Lbvh>` walks the own BVHs (`TraceScene`);
//! `TracePass<Khr>` sends the same rays through `glsl/rt_trace.rgen` and the scene's
//! acceleration structures (`KhrTrace`) instead.
//! CPU reference: `cpu_ref::trace` (`brute_force`, `CpuBvh`; tests/suite/trace.rs,
//! tests/suite/khr.rs).

use crate::error::{Error, Result};
use crate::gpu_types::{Hit, Ray};
use crate::shaders;
use crate::tracers::lbvh::StaticLayout;
use crate::tracers::{Lbvh, Rays, TraceKernel, Tracer};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Resource, TimerReadout};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const NAME: &str = "rt.trace";

/// The shape of the refilled walk (`TracePass::<Lbvh>::refilled`): a subgroup's idle
/// lanes take new rays once they are at least 1/`share` of its lanes (1: all of them),
/// and an invocation takes `rays_per_lane` rays on average (its dispatch covers the
/// rays over this many). Made by `new` (or `DEFAULT`) alone, so its values are in
/// range: a share of 0 would never refill.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Refill {
    share: u32,
    rays_per_lane: u32,
}

impl Refill {
    /// A quarter of the lanes idle, four rays a lane.
    pub const DEFAULT: Refill = Refill {
        share: 4,
        rays_per_lane: 4,
    };
    /// The largest `share` (one idle lane of 64 refills) and `rays_per_lane`.
    pub const MAX_SHARE: u32 = 64;
    pub const MAX_RAYS_PER_LANE: u32 = 1024;

    /// The shape, its values checked (`SHARE:RAYS` in `bench lbvh --refill`).
    pub fn new(share: u32, rays_per_lane: u32) -> Result<Self> {
        if !(1..=Self::MAX_SHARE).contains(&share) || !(1..=Self::MAX_RAYS_PER_LANE).contains(&rays_per_lane) {
            return Err(Error::Input(format!(
                "{share}:{rays_per_lane}: a refill's idle share is 1 to {} (the lanes refill once 1/SHARE of them idle), its rays a lane 1 to {}",
                Self::MAX_SHARE,
                Self::MAX_RAYS_PER_LANE
            )));
        }
        Ok(Self { share, rays_per_lane })
    }

    /// Idle lanes refill once they are 1/`share` of their subgroup's.
    pub fn share(self) -> u32 {
        self.share
    }

    /// Rays an invocation takes on average.
    pub fn rays_per_lane(self) -> u32 {
        self.rays_per_lane
    }
}

impl std::str::FromStr for Refill {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad = || Error::Input(format!("{s}: a refill's shape is SHARE:RAYS, e.g. 4:4"));
        let (share, rays) = s.split_once(':').ok_or_else(bad)?;
        Self::new(share.parse().map_err(|_| bad())?, rays.parse().map_err(|_| bad())?)
    }
}

impl std::fmt::Display for Refill {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.share, self.rays_per_lane)
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TracePush {
    ray_count: u32,
    static_tris: u32,
    dynamic_tris: u32,
    any_hit: u32,
}

/// Rays on the GPU and where their hits go.
#[derive(Clone, Copy)]
pub struct RayBatch<'a> {
    pub rays: &'a Buffer,
    pub hits: &'a Buffer,
    pub count: u32,
    /// Stop at the first hit (shadow rays) instead of finding the closest.
    pub any_hit: bool,
}

/// The trace kernel for tracer `T` (`TracePass::<Lbvh>::new`, `TracePass::<Khr>::new`:
/// the vendor tracer needs a context with ray tracing).
pub struct TracePass<T: Tracer> {
    ctx: Arc<Context>,
    kernel: TraceKernel<T>,
    /// The refilled walk's queue head and rays a lane (`TracePass::<Lbvh>::refilled`);
    /// `None`: one ray an invocation.
    queue: Option<(Buffer, u32)>,
}

impl<T: Tracer> TracePass<T> {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let (comp, rgen) = (shaders::RT_TRACE_COMP, shaders::RT_TRACE_RGEN);
        Ok(Self {
            ctx: ctx.clone(),
            kernel: TraceKernel::new::<TracePush>(ctx, NAME, comp, rgen)?,
            queue: None,
        })
    }

    /// Records the traversal of a batch of rays. At least one BVH (or geometry) must be
    /// given; rays, nodes and geometry must be visible to the kernel's reads
    /// (`T::RUNS`). The refilled walk also clears its queue, after any earlier trace
    /// of this pass has used it.
    pub fn record(&self, cmd: vk::CommandBuffer, batch: RayBatch<'_>, scene: T::Scene<'_>) {
        let push = |static_tris, dynamic_tris| TracePush {
            ray_count: batch.count,
            static_tris,
            dynamic_tris,
            any_hit: batch.any_hit as u32,
        };
        let (rays, hits) = (Resource::Buffer(batch.rays), Resource::Buffer(batch.hits));
        let Some((queue, rays_per_lane)) = &self.queue else {
            let own = [("rays", rays), ("hits", hits)];
            return self.kernel.run(cmd, &own, &scene, push, Rays::Count(batch.count));
        };
        let device = &self.ctx.device;
        // WAR: an earlier trace's atomics on the queue before the clear.
        barrier::record(device, cmd, &[barrier::memory(T::RUNS, access::TRANSFER_WRITE)], &[]);
        // SAFETY: `cmd` is recording; the queue lives as long as the pass.
        unsafe { device.cmd_fill_buffer(cmd, queue.raw, 0, vk::WHOLE_SIZE, 0) };
        // RAW: the kernel's atomics read the cleared head.
        barrier::record(device, cmd, &[barrier::memory(access::TRANSFER_WRITE, T::RUNS)], &[]);
        let own = [("rays", rays), ("hits", hits), ("queue", Resource::Buffer(queue))];
        let lanes = batch.count.div_ceil(*rays_per_lane);
        self.kernel.run(cmd, &own, &scene, push, Rays::Count(lanes));
    }

    /// Uploads `rays`, traces them, and returns the hits and the GPU time of the
    /// traversal (scope `NAME`, self-checked).
    pub fn trace(&self, rays: &[Ray], scene: T::Scene<'_>, any_hit: bool) -> Result<(Vec<Hit>, TimerReadout)> {
        if rays.is_empty() {
            return Ok((Vec::new(), TimerReadout::default()));
        }
        if T::is_empty(&scene) {
            return Err(Error::Bvh("tracing needs at least one BVH".into()));
        }
        let ctx = &self.ctx;
        let rays_buf = Buffer::with_data(
            ctx,
            "trace.rays",
            vk::BufferUsageFlags::STORAGE_BUFFER,
            bytemuck::cast_slice(rays),
        )?;
        let hits_buf = Buffer::new(
            ctx,
            "trace.hits",
            (rays.len() * std::mem::size_of::<Hit>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let mut timer = GpuTimer::new(ctx, 1)?;
        let readout = timer.one_shot(|cmd, timer| {
            // Poison: a hit the kernel fails to write cannot pass as a result.
            // SAFETY: `cmd` is recording; the hits buffer was made above and lives on.
            unsafe {
                ctx.device
                    .cmd_fill_buffer(cmd, hits_buf.raw, 0, vk::WHOLE_SIZE, 0x7fc0_dead)
            };
            // RAW/WAW: the kernel overwrites the poison after the fill.
            barrier::record(
                &ctx.device,
                cmd,
                &[barrier::memory(access::TRANSFER_WRITE, T::RUNS)],
                &[],
            );
            timer.begin(cmd, NAME);
            let batch = RayBatch {
                rays: &rays_buf,
                hits: &hits_buf,
                count: rays.len() as u32,
                any_hit,
            };
            self.record(cmd, batch, scene);
            timer.end(cmd, NAME);
        })?;
        Ok((bytemuck::pod_collect_to_vec(&hits_buf.read()?), readout))
    }
}

impl TracePass<Lbvh> {
    /// The walk with its lanes refilled (`glsl/rt_trace_refill.comp`): each invocation
    /// walks a step a pass and takes a new ray from a queue when its walk ends, so a
    /// SIMD group's lanes do not idle behind its longest walk. The same hits as `new`'s,
    /// bit for bit, whatever the `shape`. It walks the static BVH alone, in `layout`; a
    /// trace with a dynamic BVH, or a static one in another layout, returns every ray
    /// as a failed walk (t = -1).
    pub fn refilled(ctx: &Arc<Context>, layout: StaticLayout, shape: Refill) -> Result<Self> {
        let comp = shaders::RT_TRACE_REFILL_COMP;
        let queue = Buffer::new(
            ctx,
            "trace.queue",
            4,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            ctx: ctx.clone(),
            kernel: TraceKernel::specialized::<TracePush>(ctx, NAME, comp, &[layout.slots(), shape.share])?,
            queue: Some((queue, shape.rays_per_lane)),
        })
    }
}
