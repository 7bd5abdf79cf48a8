//! What a trace goes through and the kernel that runs it, for either tracer
//! (`settings::Tracer`): Speculum's own BVHs walked by a compute kernel, or the
//! driver's acceleration structures traced by a ray-tracing pipeline. A pass that
//! traces holds a `TraceKernel` made for the renderer's tracer and records it with the
//! scene as `Tracing`; the two kernels share their GLSL but for the tracer
//! (`traverse.glsl` / `trace_khr.glsl`), so they shade every hit alike.

use super::{CompactOutputs, Geometry, TraceScene, TRACE_RAYS_ARGS};
use crate::error::Result;
use crate::settings::Tracer;
use crate::shaders;
use crate::vk::barrier::{access, Scope};
use crate::vk::rt_pipeline::{Launch, RtPipeline, RtShaders};
use crate::vk::{Bind, Groups, Pipeline, Resource, Shader};
use ash::vk;
use bytemuck::Pod;
use std::sync::Arc;

/// The vendor tracer's view of a scene (`tracer = khr`): its top-level acceleration
/// structure and the geometry the hits' attributes are read from.
#[derive(Clone, Copy)]
pub struct KhrTrace<'a> {
    pub tlas: &'a crate::vk::accel::Accel,
    /// Each static primitive's scene triangle id (`khr::StaticOrder`).
    pub static_perm: &'a crate::vk::Buffer,
    pub static_geometry: Option<Geometry<'a>>,
    pub dynamic_geometry: Option<Geometry<'a>>,
}

/// What a trace goes through: Speculum's own BVHs or the driver's acceleration
/// structures (`settings::Tracer`).
#[derive(Clone, Copy)]
pub enum Tracing<'a> {
    Lbvh(TraceScene<'a>),
    Khr(KhrTrace<'a>),
}

impl<'a> From<TraceScene<'a>> for Tracing<'a> {
    fn from(s: TraceScene<'a>) -> Self {
        Tracing::Lbvh(s)
    }
}

impl<'a> From<KhrTrace<'a>> for Tracing<'a> {
    fn from(s: KhrTrace<'a>) -> Self {
        Tracing::Khr(s)
    }
}

impl<'a> Tracing<'a> {
    /// The traversal bindings and the two triangle counts: `TraceScene::bindings`, or
    /// for the vendor tracer those of `glsl/shared/trace_khr.glsl` (the top level, the
    /// static vertices, indices and permutation, the dynamic vertices and indices).
    pub fn bindings(&self) -> (Vec<Bind<'a>>, u32, u32) {
        match self {
            Tracing::Lbvh(s) => s.bindings(),
            Tracing::Khr(k) => {
                let any = k
                    .static_geometry
                    .or(k.dynamic_geometry)
                    .expect("tracing needs geometry");
                let s = k.static_geometry.unwrap_or(any);
                let d = k.dynamic_geometry.unwrap_or(any);
                let resources = vec![
                    ("scene_tlas", Resource::Accel(k.tlas)),
                    ("static_vertices", Resource::Buffer(s.vertices)),
                    ("static_indices", Resource::Buffer(s.indices)),
                    ("static_perm", Resource::Buffer(k.static_perm)),
                    ("dynamic_vertices", Resource::Buffer(d.vertices)),
                    ("dynamic_indices", Resource::Buffer(d.indices)),
                ];
                let count = |g: Option<Geometry<'_>>| g.map_or(0, |g| g.tri_count);
                (resources, count(k.static_geometry), count(k.dynamic_geometry))
            }
        }
    }

    /// Whether there is anything to trace.
    pub fn is_empty(&self) -> bool {
        match self {
            Tracing::Lbvh(s) => s.static_bvh.is_none() && s.dynamic_bvh.is_none(),
            Tracing::Khr(k) => k.static_geometry.is_none() && k.dynamic_geometry.is_none(),
        }
    }
}

/// A tracing kernel's resources: its own and the trace's (`Tracing::bindings`).
pub fn with_trace<'r>(own: &[Bind<'r>], trace: &[Bind<'r>]) -> Vec<Bind<'r>> {
    [own, trace].concat()
}

/// A tracing pass's kernel, for one tracer.
pub enum TraceKernel {
    Lbvh(Pipeline),
    Khr(RtPipeline),
}

/// The vendor tracer's shaders: `raygen` and the shared miss and closest hit.
pub fn khr_shaders(raygen: Shader) -> RtShaders<'static> {
    RtShaders {
        raygen,
        misses: &[shaders::KHR_MISS_RMISS],
        closest_hit: shaders::KHR_HIT_RCHIT,
    }
}

impl TraceKernel {
    /// `compute` for `lbvh`, `raygen` for `khr` (which needs a context with ray
    /// tracing), both with push constants `P`.
    pub fn new<P: Pod>(
        ctx: &Arc<crate::vk::Context>,
        name: &'static str,
        tracer: Tracer,
        compute: Shader,
        raygen: Shader,
    ) -> Result<Self> {
        Ok(match tracer {
            Tracer::Lbvh => TraceKernel::Lbvh(Pipeline::compute::<P>(ctx, name, compute)?),
            Tracer::Khr => TraceKernel::Khr(RtPipeline::new::<P>(ctx, name, &khr_shaders(raygen))?),
        })
    }

    /// The stage and accesses the kernel reads its inputs and writes its outputs with
    /// (a barrier's destination before it runs).
    pub fn runs(&self) -> Scope {
        match self {
            TraceKernel::Lbvh(_) => access::COMPUTE_ANY,
            TraceKernel::Khr(_) => access::RT_ANY,
        }
    }

    /// The stage and access of its writes (a barrier's source after it).
    pub fn writes(&self) -> Scope {
        match self {
            TraceKernel::Lbvh(_) => access::COMPUTE_WRITE,
            TraceKernel::Khr(_) => access::RT_WRITE,
        }
    }

    /// Runs the kernel once per entry of `list` (sized on the GPU), through `scene`.
    pub fn over_list<P: Pod>(
        &self,
        name: &str,
        cmd: vk::CommandBuffer,
        resources: &[Bind<'_>],
        push: &P,
        list: &CompactOutputs,
        scene: &Tracing<'_>,
    ) {
        match (self, scene) {
            (TraceKernel::Lbvh(p), Tracing::Lbvh(_)) => {
                p.dispatch(cmd, resources, push, Groups::Indirect(&list.indirect))
            }
            (TraceKernel::Khr(p), Tracing::Khr(_)) => {
                p.trace(cmd, resources, push, Launch::Indirect(&list.indirect, TRACE_RAYS_ARGS))
            }
            _ => panic!("{name}: a trace through another tracer than the pass was made for"),
        }
    }

    /// Runs the kernel once per ray of `count`, through `scene`.
    pub fn over_count<P: Pod>(
        &self,
        name: &str,
        cmd: vk::CommandBuffer,
        resources: &[Bind<'_>],
        push: &P,
        count: u32,
        scene: &Tracing<'_>,
    ) {
        match (self, scene) {
            (TraceKernel::Lbvh(p), Tracing::Lbvh(_)) => p.dispatch(cmd, resources, push, Groups::Cover([count, 1, 1])),
            (TraceKernel::Khr(p), Tracing::Khr(_)) => p.trace(cmd, resources, push, Launch::Exact(count)),
            _ => panic!("{name}: a trace through another tracer than the pass was made for"),
        }
    }
}
