//! The frame's tracer (`settings::Tracer`), held as one value: the tracing kernels
//! (`gbuffer.trace`, `rt.reflect`, `shadow.trace`) made for one tracer, and, for the vendor tracer, its
//! acceleration structures. The kernels' type names the tracer (`tracers::Tracer`), so
//! the frame cannot trace one tracer's structures with the other's kernels; the
//! renderer stores the choice nowhere else (`Renderer::tracer` reads it back).

use super::gpu_scene::{DynamicGeometry, SceneBuffers};
use crate::error::Result;
use crate::gpu_types::GpuVertex;
use crate::passes::{gbuffer_trace, rt_reflect, shadow_trace};
use crate::settings::{self, Settings};
use crate::tracers::khr::{KhrScene, StaticInput, StaticOrder};
use crate::tracers::{Khr, Lbvh, Tracer};
use crate::vk::Context;
use std::sync::Arc;

/// The frame's tracing kernels for tracer `T`.
pub(super) struct Kernels<T: Tracer> {
    pub primary: gbuffer_trace::Kernel<T>,
    pub reflect: rt_reflect::Kernel<T>,
    pub shadow: shadow_trace::Kernel<T>,
}

impl<T: Tracer> Kernels<T> {
    fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            primary: gbuffer_trace::Kernel::new(ctx)?,
            reflect: rt_reflect::Kernel::new(ctx)?,
            shadow: shadow_trace::Kernel::new(ctx)?,
        })
    }
}

/// The tracer a frame traces with: the own BVHs (the renderer's static BVH and the
/// dynamic geometry's), or the driver's structures over the same triangles.
// One, held by the renderer: the variants' sizes (a ray-tracing pipeline is larger than
// a compute one) do not matter.
#[allow(clippy::large_enum_variant)]
pub(super) enum FrameTracer {
    Lbvh(Kernels<Lbvh>),
    Khr(Kernels<Khr>, KhrScene),
}

impl FrameTracer {
    /// The kernels and structures for `settings.tracer` (the vendor tracer's over the
    /// scene, with the bodies where the simulation has them now and as many instance
    /// buffers as `slots`).
    pub fn new(
        ctx: &Arc<Context>,
        scene: &SceneBuffers,
        dynamic: Option<&DynamicGeometry>,
        settings: &Settings,
        slots: usize,
    ) -> Result<Self> {
        Ok(match settings.tracer {
            settings::Tracer::Lbvh => FrameTracer::Lbvh(Kernels::new(ctx)?),
            settings::Tracer::Khr => {
                let mut structures = khr_scene(ctx, scene, dynamic)?;
                structures.set_slots(slots)?;
                FrameTracer::Khr(Kernels::new(ctx)?, structures)
            }
        })
    }

    /// Which tracer this is.
    pub fn setting(&self) -> settings::Tracer {
        match self {
            FrameTracer::Lbvh(_) => Lbvh::SETTING,
            FrameTracer::Khr(..) => Khr::SETTING,
        }
    }

    /// The vendor tracer's structures, when it is the tracer.
    pub fn khr_mut(&mut self) -> Option<&mut KhrScene> {
        match self {
            FrameTracer::Lbvh(_) => None,
            FrameTracer::Khr(_, k) => Some(k),
        }
    }
}

/// Whether the renderer can trace with `settings.tracer`: the vendor tracer needs the
/// device's ray-tracing extensions (the error names what it lacks). Checked before any
/// GPU work.
pub(super) fn check(ctx: &Context, settings: &Settings) -> Result<()> {
    if settings.tracer != settings::Tracer::Khr {
        return Ok(());
    }
    if let Some(missing) = &ctx.ray_tracing_missing {
        return Err(crate::Error::NoDevice(format!(
            "tracer khr needs ray tracing, and device '{}' lacks {missing} (tracer lbvh runs anywhere)",
            ctx.device_name
        )));
    }
    Ok(())
}

/// The vendor tracer's structures over the scene (the bodies where the simulation has
/// them now; the static triangles, read back, in Morton order).
fn khr_scene(ctx: &Arc<Context>, scene: &SceneBuffers, dynamic: Option<&DynamicGeometry>) -> Result<KhrScene> {
    let geometry = scene.mesh.triangles();
    let vertices: Vec<GpuVertex> = bytemuck::pod_collect_to_vec(&geometry.vertices.read()?);
    let mut indices: Vec<u32> = bytemuck::pod_collect_to_vec(&geometry.indices.read()?);
    indices.truncate(3 * geometry.tri_count as usize);
    let input = StaticInput::new(geometry, &vertices, &indices, StaticOrder::Morton);
    let layout = dynamic.map(|d| d.khr_layout());
    let poses = dynamic.map(|d| d.world.poses()).unwrap_or_default();
    KhrScene::new(ctx, &input, layout.as_ref(), &poses)
}
