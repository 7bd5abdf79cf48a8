//! `rt.trace`: closest-hit or any-hit traversal of the static and the dynamic BVH for a
//! list of rays. Usable on its own (`TracePass::trace`) for tests and benchmarks;
//! `rt.reflect` walks the same BVHs with the same traversal (`glsl/shared/traverse.glsl`)
//! from its own kernel, and binds them through `TraceScene::bindings`.
//! With the vendor tracer (`TracePass::new_khr`) the same rays go through
//! `glsl/rt_trace.rgen` and the scene's acceleration structures instead.
//! CPU reference: `cpu_ref::trace` (`brute_force`, `CpuBvh`; tests/suite/trace.rs,
//! tests/suite/khr.rs).

use super::{with_trace, TraceKernel, Tracing};
use crate::error::{Error, Result};
use crate::gpu_types::{Hit, Ray};
use crate::settings::Tracer;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Resource, TimerReadout};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const NAME: &str = "rt.trace";

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

pub struct TracePass {
    ctx: Arc<Context>,
    kernel: TraceKernel,
}

impl TracePass {
    /// Through Speculum's own BVHs (`TraceScene`).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Self::for_tracer(ctx, Tracer::Lbvh)
    }

    /// Through the driver's acceleration structures (`KhrTrace`); the context must have
    /// ray tracing.
    pub fn new_khr(ctx: &Arc<Context>) -> Result<Self> {
        Self::for_tracer(ctx, Tracer::Khr)
    }

    pub fn for_tracer(ctx: &Arc<Context>, tracer: Tracer) -> Result<Self> {
        let (comp, rgen) = (shaders::RT_TRACE_COMP, shaders::RT_TRACE_RGEN);
        Ok(Self {
            ctx: ctx.clone(),
            kernel: TraceKernel::new::<TracePush>(ctx, NAME, tracer, comp, rgen)?,
        })
    }

    /// Records the traversal of a batch of rays through the tracer the pass was made
    /// for. At least one BVH must be given; rays, nodes and geometry must be visible to
    /// the kernel's reads (compute, or ray-tracing shaders).
    pub fn record<'a>(&self, cmd: vk::CommandBuffer, batch: RayBatch<'_>, scene: impl Into<Tracing<'a>>) {
        let scene = scene.into();
        let (trace, static_tris, dynamic_tris) = scene.bindings();
        let push = TracePush {
            ray_count: batch.count,
            static_tris,
            dynamic_tris,
            any_hit: batch.any_hit as u32,
        };
        let lists = [
            ("rays", Resource::Buffer(batch.rays)),
            ("hits", Resource::Buffer(batch.hits)),
        ];
        let resources = with_trace(&lists, &trace);
        self.kernel
            .over_count(NAME, cmd, &resources, &push, batch.count, &scene);
    }

    /// Uploads `rays`, traces them, and returns the hits and the GPU time of the
    /// traversal (scope `NAME`, self-checked).
    pub fn trace<'a>(
        &self,
        rays: &[Ray],
        scene: impl Into<Tracing<'a>>,
        any_hit: bool,
    ) -> Result<(Vec<Hit>, TimerReadout)> {
        let scene = scene.into();
        if rays.is_empty() {
            return Ok((Vec::new(), TimerReadout::default()));
        }
        if scene.is_empty() {
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
                &[barrier::memory(access::TRANSFER_WRITE, self.kernel.runs())],
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
