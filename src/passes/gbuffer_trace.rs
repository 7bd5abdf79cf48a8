//! `gbuffer.trace`: the G-buffer by one primary ray a pixel through the frame's tracer
//! (the `visibility` setting's `rays`), instead of the raster (`gbuffer`): the same
//! targets with the same meaning (`glsl/shared/primary.glsl`), so every later pass
//! runs unchanged. Storage images take the colour targets; a depth image cannot be one,
//! so the kernel writes the depth to a buffer, copied into the depth image after it. As
//! `rt.reflect`'s, the kernel is made for one tracer (`Kernel<T>`).
//! CPU reference: `cpu_ref::primary::gbuffer_texel` (tests/suite/gbuffer.rs).

use super::{GBuffer, Surfaces};
use crate::error::Result;
use crate::shaders;
use crate::tracers::{Rays, TraceKernel, Tracer};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Resource};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "gbuffer.trace";

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PrimaryPush {
    static_tris: u32,
    dynamic_tris: u32,
}

/// `gbuffer.trace`'s kernel for tracer `T`.
pub struct Kernel<T: Tracer>(TraceKernel<T>);

impl<T: Tracer> Kernel<T> {
    /// The kernel (the vendor tracer's needs a context with ray tracing).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let (comp, rgen) = (shaders::GBUFFER_TRACE_COMP, shaders::GBUFFER_TRACE_RGEN);
        Ok(Self(TraceKernel::new::<PrimaryPush>(ctx, NAME, comp, rgen)?))
    }
}

/// What the primary rays read besides the traced scene.
pub struct PrimaryInputs<'a, T: Tracer> {
    pub frame: &'a Buffer,
    pub surfaces: Surfaces<'a>,
    /// The dynamic vertices as the frame before saw them (`SceneGeometry::previous`);
    /// without dynamic geometry any vertex buffer (never read).
    pub previous: &'a Buffer,
    pub scene: T::Scene<'a>,
}

pub struct GBufferTracePass {
    ctx: Arc<Context>,
    /// The hits' depth, a float a pixel, row by row: the depth image's copy source.
    depth: Buffer,
}

impl GBufferTracePass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            depth: Self::depth_buffer(ctx, extent)?,
        })
    }

    fn depth_buffer(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Buffer> {
        let bytes = 4 * extent.width as u64 * extent.height as u64;
        Buffer::device_list(ctx, "gbuffer.trace.depth", bytes)
    }

    /// Resizes the depth's buffer.
    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.depth = Self::depth_buffer(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the rays into `out` (sized as this pass). The targets end in
    /// `SHADER_READ_ONLY_OPTIMAL`, visible to their readers, as the raster leaves them.
    pub fn record<T: Tracer>(
        &self,
        cmd: vk::CommandBuffer,
        kernel: &Kernel<T>,
        inputs: &PrimaryInputs<'_, T>,
        out: &GBuffer,
    ) {
        use vk::ImageLayout as L;
        let d = &self.ctx.device;
        let colors = out.colors();
        let extent = out.depth.extent;
        assert_eq!(
            self.depth.size,
            4 * extent.width as u64 * extent.height as u64,
            "gbuffer.trace sized as its G-buffer"
        );
        // WAR: the previous frame's reads of the targets (and the depth copy's read of
        // the buffer) finish before the rays write them.
        barrier::global(d, cmd, access::TRANSFER_READ, T::RUNS);
        barrier::transition(
            d,
            cmd,
            &colors,
            (access::COMPUTE_READ, T::RUNS),
            (L::UNDEFINED, L::GENERAL),
        );
        let s = inputs.surfaces;
        let own = [
            ("frame", Resource::Buffer(inputs.frame)),
            ("materials", Resource::Buffer(s.materials)),
            ("scene_textures", Resource::Sampled(s.textures, s.sampler)),
            ("data_textures", Resource::SampledData(s.textures, s.sampler)),
            ("dynamic_previous", Resource::Buffer(inputs.previous)),
            ("depth_out", Resource::Buffer(&self.depth)),
            ("normal_out", Resource::StorageImage(&out.normal)),
            ("albedo_out", Resource::StorageImage(&out.albedo)),
            ("static_uvs", Resource::Buffer(s.uvs[0])),
            ("dynamic_uvs", Resource::Buffer(s.uvs[1])),
            ("material_out", Resource::StorageImage(&out.material)),
            ("motion_out", Resource::StorageImage(&out.motion)),
        ];
        let push = |static_tris, dynamic_tris| PrimaryPush {
            static_tris,
            dynamic_tris,
        };
        kernel
            .0
            .run(cmd, &own, &inputs.scene, push, Rays::Grid(extent.width, extent.height));
        // RAW: the copy reads the depths the rays wrote; WAR: the previous frame's
        // compute reads of the depth image finish before the copy replaces it.
        barrier::global(d, cmd, T::WRITES, access::TRANSFER_READ);
        let depth = [&out.depth];
        let to_copy = (L::UNDEFINED, L::TRANSFER_DST_OPTIMAL);
        barrier::transition(d, cmd, &depth, (access::COMPUTE_READ, access::TRANSFER_WRITE), to_copy);
        let region = out.depth.copy_region();
        // SAFETY: `cmd` is recording outside a render pass; the buffer holds a float per
        // pixel of the depth image (asserted above), which is in TRANSFER_DST_OPTIMAL;
        // the kernel clamps every depth to 0..1, as a D32_SFLOAT copy requires.
        unsafe {
            d.cmd_copy_buffer_to_image(cmd, self.depth.raw, out.depth.raw, L::TRANSFER_DST_OPTIMAL, &[region]);
        }
        // RAW: the compute passes read the G-buffer written above.
        barrier::transition(
            d,
            cmd,
            &depth,
            (access::TRANSFER_WRITE, access::COMPUTE_READ),
            (L::TRANSFER_DST_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
        );
        barrier::transition(
            d,
            cmd,
            &colors,
            (T::WRITES, access::COMPUTE_READ),
            (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL),
        );
    }
}
