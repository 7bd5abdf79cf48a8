//! The two tracers (`settings::Tracer`): Speculum's own BVHs (`lbvh/`: the LBVH and
//! PLOC builders, the dynamic tree, walked by a compute kernel) and the driver's
//! acceleration structures (`khr.rs`, traced by a ray-tracing pipeline). Each is a type
//! (`Lbvh`, `Khr`) implementing `Tracer`: what a trace goes through (`Tracer::Scene`)
//! and the kernel that walks it (`TraceKernel<T>`) name the same tracer, so a kernel
//! made for one cannot be handed the other's scene — that does not compile. A pass
//! that traces records a `TraceKernel<T>` with a `T::Scene`; the two kernels share
//! their GLSL but for the tracer (`traverse.glsl` / `trace_khr.glsl`), so they shade
//! every hit alike.

pub mod khr;
pub mod lbvh;

use crate::error::Result;
use crate::settings;
use crate::shaders;
use crate::vk::barrier::{access, Scope};
use crate::vk::rt_pipeline::{Launch, RtPipeline, RtShaders};
use crate::vk::{Bind, Buffer, Context, Groups, Pipeline, Resource, Shader};
use ash::vk;
use bytemuck::Pod;
use lbvh::Bvh;
use std::sync::Arc;

/// A mesh's triangles on the GPU (what the builders and both tracers read).
pub use lbvh::Geometry;

/// Byte offset of the trace-rays arguments in a list's indirect buffer
/// (`passes::CompactOutputs::indirect`): the vendor tracer launches from there, the
/// compute kernel dispatches from byte 0.
pub const TRACE_RAYS_ARGS: u64 = 16;

/// How many rays a trace launches: one per entry of a list sized on the GPU (its
/// indirect buffer, `passes::CompactOutputs::indirect`), a count known here, or one per
/// cell of a width x height grid (a compute kernel's `WG_2D` x `WG_2D` tiles covering it,
/// or a launch of that size).
#[derive(Clone, Copy)]
pub enum Rays<'a> {
    Listed(&'a Buffer),
    Count(u32),
    Grid(u32, u32),
}

/// One tracer, as a type: its setting, what a trace goes through, and how its kernel
/// is made and run.
pub trait Tracer: 'static {
    /// The setting that chooses it.
    const SETTING: settings::Tracer;
    /// The stage and accesses its kernels read their inputs and write their outputs
    /// with (a barrier's destination before one runs).
    const RUNS: Scope;
    /// The stage and access of its kernels' writes (a barrier's source after one).
    const WRITES: Scope;
    /// Whether its kernels are compute shaders: they see what a compute pass made
    /// visible to compute reads (a ray-tracing pipeline needs its own barrier).
    const COMPUTE: bool;
    /// What a trace goes through.
    type Scene<'a>: Copy;
    /// The pipeline a kernel runs in.
    type Pipeline;

    /// `compute` for the own tracer, `raygen` (with the shared miss and closest hit)
    /// for the vendor's, both with push constants `P`.
    fn pipeline<P: Pod>(
        ctx: &Arc<Context>,
        name: &'static str,
        compute: Shader,
        raygen: Shader,
    ) -> Result<Self::Pipeline>;

    /// The traversal's bindings and the static and dynamic triangle counts.
    fn bindings<'a>(scene: &Self::Scene<'a>) -> (Vec<Bind<'a>>, u32, u32);

    /// Whether there is nothing to trace.
    fn is_empty(scene: &Self::Scene<'_>) -> bool;

    /// Binds, pushes and runs `pipeline` once per ray of `rays`.
    fn run<P: Pod>(pipeline: &Self::Pipeline, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P, rays: Rays<'_>);
}

/// Speculum's own tracer: its BVHs (`lbvh/`), walked by a compute kernel.
pub enum Lbvh {}

/// The driver's tracer: its acceleration structures (`khr.rs`), traced by a
/// ray-tracing pipeline; needs a context with ray tracing.
pub enum Khr {}

impl Tracer for Lbvh {
    const SETTING: settings::Tracer = settings::Tracer::Lbvh;
    const RUNS: Scope = access::COMPUTE_ANY;
    const WRITES: Scope = access::COMPUTE_WRITE;
    const COMPUTE: bool = true;
    type Scene<'a> = TraceScene<'a>;
    type Pipeline = Pipeline;

    fn pipeline<P: Pod>(ctx: &Arc<Context>, name: &'static str, compute: Shader, _: Shader) -> Result<Pipeline> {
        Pipeline::compute::<P>(ctx, name, compute)
    }

    fn bindings<'a>(scene: &Self::Scene<'a>) -> (Vec<Bind<'a>>, u32, u32) {
        scene.bindings()
    }

    fn is_empty(scene: &TraceScene<'_>) -> bool {
        scene.static_bvh.is_none() && scene.dynamic_bvh.is_none()
    }

    fn run<P: Pod>(pipeline: &Pipeline, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P, rays: Rays<'_>) {
        let groups = match rays {
            Rays::Listed(indirect) => Groups::Indirect(indirect),
            Rays::Count(n) => Groups::Cover([n, 1, 1]),
            Rays::Grid(w, h) => Groups::Cover([w, h, 1]),
        };
        pipeline.dispatch(cmd, resources, push, groups)
    }
}

impl Tracer for Khr {
    const SETTING: settings::Tracer = settings::Tracer::Khr;
    const RUNS: Scope = access::RT_ANY;
    const WRITES: Scope = access::RT_WRITE;
    const COMPUTE: bool = false;
    type Scene<'a> = KhrTrace<'a>;
    type Pipeline = RtPipeline;

    fn pipeline<P: Pod>(ctx: &Arc<Context>, name: &'static str, _: Shader, raygen: Shader) -> Result<RtPipeline> {
        let shaders = RtShaders {
            raygen,
            misses: &[shaders::KHR_MISS_RMISS],
            closest_hit: shaders::KHR_HIT_RCHIT,
        };
        RtPipeline::new::<P>(ctx, name, &shaders)
    }

    fn bindings<'a>(scene: &Self::Scene<'a>) -> (Vec<Bind<'a>>, u32, u32) {
        scene.bindings()
    }

    fn is_empty(scene: &KhrTrace<'_>) -> bool {
        scene.static_geometry.is_none() && scene.dynamic_geometry.is_none()
    }

    fn run<P: Pod>(pipeline: &RtPipeline, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P, rays: Rays<'_>) {
        let launch = match rays {
            Rays::Listed(indirect) => Launch::Indirect(indirect, TRACE_RAYS_ARGS),
            Rays::Count(n) => Launch::Exact(n),
            Rays::Grid(w, h) => Launch::Grid(w, h),
        };
        pipeline.trace(cmd, resources, push, launch)
    }
}

/// A tracing pass's kernel, made for tracer `T`: it runs only with a `T::Scene`. A pass
/// made for the own tracer records with its BVHs:
///
/// ```no_run
/// use speculum::passes::rt_trace::{RayBatch, TracePass};
/// use speculum::tracers::{Lbvh, TraceScene};
/// fn record(pass: &TracePass<Lbvh>, cmd: ash::vk::CommandBuffer, rays: RayBatch<'_>, scene: TraceScene<'_>) {
///     pass.record(cmd, rays, scene);
/// }
/// ```
///
/// and handed the driver's structures instead, does not compile:
///
/// ```compile_fail
/// use speculum::passes::rt_trace::{RayBatch, TracePass};
/// use speculum::tracers::{KhrTrace, Lbvh};
/// fn record(pass: &TracePass<Lbvh>, cmd: ash::vk::CommandBuffer, rays: RayBatch<'_>, scene: KhrTrace<'_>) {
///     pass.record(cmd, rays, scene);
/// }
/// ```
pub struct TraceKernel<T: Tracer> {
    pipeline: T::Pipeline,
}

impl<T: Tracer> TraceKernel<T> {
    /// The kernel `name` from `compute` (the own tracer) or `raygen` (the vendor's),
    /// with push constants `P`.
    pub fn new<P: Pod>(ctx: &Arc<Context>, name: &'static str, compute: Shader, raygen: Shader) -> Result<Self> {
        Ok(Self {
            pipeline: T::pipeline::<P>(ctx, name, compute, raygen)?,
        })
    }

    /// Runs the kernel through `scene` with its own resources `own` and the push
    /// constants `push` makes from the static and dynamic triangle counts.
    pub fn run<P: Pod>(
        &self,
        cmd: vk::CommandBuffer,
        own: &[Bind<'_>],
        scene: &T::Scene<'_>,
        push: impl FnOnce(u32, u32) -> P,
        rays: Rays<'_>,
    ) {
        let (trace, static_tris, dynamic_tris) = T::bindings(scene);
        let resources = [own, &trace].concat();
        T::run(&self.pipeline, cmd, &resources, &push(static_tris, dynamic_tris), rays);
    }
}

impl TraceKernel<Lbvh> {
    /// The own tracer's kernel `name` from `compute`, its specialization constants
    /// `constant_id = i` set to `constants[i]` (`Pipeline::compute_specialized`).
    pub fn specialized<P: Pod>(
        ctx: &Arc<Context>,
        name: &'static str,
        compute: Shader,
        constants: &[u32],
    ) -> Result<Self> {
        Ok(Self {
            pipeline: Pipeline::compute_specialized::<P>(ctx, name, compute, constants)?,
        })
    }
}

/// One BVH and the triangles it was built over.
#[derive(Clone, Copy)]
pub struct Traceable<'a> {
    pub bvh: &'a Bvh,
    pub geometry: Geometry<'a>,
}

/// What the own tracer walks: the static BVH, the dynamic one, or both.
#[derive(Clone, Copy, Default)]
pub struct TraceScene<'a> {
    pub static_bvh: Option<Traceable<'a>>,
    pub dynamic_bvh: Option<Traceable<'a>>,
}

impl<'a> TraceScene<'a> {
    /// The static BVH `bvh` over `geometry` alone.
    pub fn of_static(bvh: &'a Bvh, geometry: Geometry<'a>) -> Self {
        Self {
            static_bvh: Some(Traceable { bvh, geometry }),
            dynamic_bvh: None,
        }
    }

    /// `bvh` over `geometry` alone, walked as the dynamic BVH (its own nodes; hits
    /// carry the dynamic BVH's id bit).
    pub fn of_dynamic(bvh: &'a Bvh, geometry: Geometry<'a>) -> Self {
        Self {
            static_bvh: None,
            dynamic_bvh: Some(Traceable { bvh, geometry }),
        }
    }

    /// The traversal bindings of `glsl/shared/traverse.glsl` (the static and dynamic
    /// compact nodes, vertices, indices and triangles in leaf order) and the two
    /// triangle counts. A missing BVH is bound to the other's buffers with a triangle
    /// count of 0. Panics when the static BVH has no compact nodes, or older ones than
    /// its last build or refit.
    pub fn bindings(&self) -> (Vec<Bind<'a>>, u32, u32) {
        let any = self.static_bvh.or(self.dynamic_bvh).expect("tracing needs a BVH");
        if let Some(s) = self.static_bvh {
            assert!(
                s.bvh.compact_current(),
                "the static BVH needs compact nodes (Bvh::new_static) recorded after its last build or refit"
            );
        }
        let s = self.static_bvh.unwrap_or(any);
        let d = self.dynamic_bvh.unwrap_or(any);
        // Without a static BVH its slot is never read: any texel view fills it.
        let s_nodes = s.bvh.compact.as_ref().map_or(&s.bvh.node_texels, |c| &c.texels);
        let resources = vec![
            ("s_nodes", Resource::Texels(s_nodes)),
            ("static_vertices", Resource::Buffer(s.geometry.vertices)),
            ("static_indices", Resource::Buffer(s.geometry.indices)),
            ("d_nodes", Resource::Texels(&d.bvh.node_texels)),
            ("dynamic_vertices", Resource::Buffer(d.geometry.vertices)),
            ("dynamic_indices", Resource::Buffer(d.geometry.indices)),
            ("s_tris", Resource::Texels(&s.bvh.tri_texels)),
            ("d_tris", Resource::Texels(&d.bvh.tri_texels)),
        ];
        let count = |b: Option<Traceable<'_>>| b.map_or(0, |b| b.geometry.tri_count);
        (resources, count(self.static_bvh), count(self.dynamic_bvh))
    }
}

/// What the vendor tracer traces: its top-level acceleration structure and the
/// geometry the hits' attributes are read from (`khr::KhrScene::trace`).
#[derive(Clone, Copy)]
pub struct KhrTrace<'a> {
    pub tlas: &'a crate::vk::accel::Accel,
    /// Each static primitive's scene triangle id (`khr::StaticOrder`).
    pub static_perm: &'a Buffer,
    pub static_geometry: Option<Geometry<'a>>,
    pub dynamic_geometry: Option<Geometry<'a>>,
}

impl<'a> KhrTrace<'a> {
    /// The bindings of `glsl/shared/trace_khr.glsl` (the top level, the static
    /// vertices, indices and permutation, the dynamic vertices and indices) and the two
    /// triangle counts; missing geometry is bound to the other's buffers with a count
    /// of 0.
    pub fn bindings(&self) -> (Vec<Bind<'a>>, u32, u32) {
        let any = self
            .static_geometry
            .or(self.dynamic_geometry)
            .expect("tracing needs geometry");
        let s = self.static_geometry.unwrap_or(any);
        let d = self.dynamic_geometry.unwrap_or(any);
        let resources = vec![
            ("scene_tlas", Resource::Accel(self.tlas)),
            ("static_vertices", Resource::Buffer(s.vertices)),
            ("static_indices", Resource::Buffer(s.indices)),
            ("static_perm", Resource::Buffer(self.static_perm)),
            ("dynamic_vertices", Resource::Buffer(d.vertices)),
            ("dynamic_indices", Resource::Buffer(d.indices)),
        ];
        let count = |g: Option<Geometry<'_>>| g.map_or(0, |g| g.tri_count);
        (resources, count(self.static_geometry), count(self.dynamic_geometry))
    }
}
