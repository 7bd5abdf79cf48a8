//! `gbuffer`: rasterizes the scene from the camera into depth, normal + reflectivity
//! (the normal clamped so its mirror direction stays above the facet), base colour
//! (textured, sRGB-encoded) + roughness, material id and motion (where each surface
//! point was the frame before: `SceneGeometry::previous`).
//! No CPU reference of its own (a raster pass): `tests/suite/gbuffer.rs` checks its targets
//! against analytic ray casts of a plane and a sphere, and texels against the CPU lookup.

use super::{set_viewport, GBuffer, SceneGeometry, Surfaces};
use crate::error::Result;
use crate::shader_defines::MATERIAL_NONE;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GraphicsDesc, Image, Pipeline, Resource};
use ash::vk;
use std::sync::Arc;

pub const NAME: &str = "gbuffer";
pub const DEPTH_FORMAT: vk::Format = crate::vk::device::DEPTH_FORMAT;
/// xyz: unit world normal facing the camera; w: reflectivity.
pub const NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// rgb: base colour (the albedo times its texture), sRGB-encoded by the shader so
/// that 8 bits keep dark textures free of banding (readers decode with
/// `gbuffer_base_color`; the encoding is the shader's, not the format's, so GPU and CPU
/// references decode alike); a: roughness (linear).
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// Material index, `MATERIAL_NONE` where no geometry covers the pixel.
pub const MATERIAL_FORMAT: vk::Format = vk::Format::R32_UINT;
/// xyz: the surface point's world position the frame before minus this frame's
/// (exactly 0 on geometry that did not move: half floats keep a millimetre of a
/// metre's motion); w: metallic (the material's, times its roughness texture's blue
/// channel: glTF's metallic-roughness layout).
pub const MOTION_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

impl GBuffer {
    /// Creates the targets: attachments of the raster, storage images of the primary
    /// rays (`gbuffer.trace`, which copies its depth in). They accept transfers too, so
    /// tests can fill and read them.
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let transfer = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
        let color = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | transfer;
        let depth = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | transfer;
        Ok(Self {
            depth: Image::new(ctx, "gbuffer.depth", extent, DEPTH_FORMAT, depth)?,
            normal: Image::new(ctx, "gbuffer.normal", extent, NORMAL_FORMAT, color)?,
            albedo: Image::new(ctx, "gbuffer.albedo", extent, ALBEDO_FORMAT, color)?,
            material: Image::new(ctx, "gbuffer.material", extent, MATERIAL_FORMAT, color)?,
            motion: Image::new(ctx, "gbuffer.motion", extent, MOTION_FORMAT, color)?,
        })
    }

    /// The colour targets, in attachment order.
    pub fn colors(&self) -> [&Image; 4] {
        [&self.normal, &self.albedo, &self.material, &self.motion]
    }
}

pub struct GBufferPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    pub out: GBuffer,
}

impl GBufferPass {
    pub fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        let pipeline = Pipeline::graphics::<()>(
            ctx,
            NAME,
            &GraphicsDesc {
                vertex: shaders::GBUFFER_VERT,
                fragment: Some(shaders::GBUFFER_FRAG),
                color_formats: &[NORMAL_FORMAT, ALBEDO_FORMAT, MATERIAL_FORMAT, MOTION_FORMAT],
                depth_format: DEPTH_FORMAT,
                depth_bias: None,
            },
        )?;
        Ok(Self {
            ctx: ctx.clone(),
            pipeline,
            out: GBuffer::new(ctx, extent)?,
        })
    }

    /// Recreates the targets at a new size.
    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.out = GBuffer::new(&self.ctx, extent)?;
        Ok(())
    }

    /// Records the raster. The targets end in `SHADER_READ_ONLY_OPTIMAL`, visible to
    /// their readers: every later pass of the frame (compute).
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        frame: &Buffer,
        surfaces: &Surfaces<'_>,
        geometries: &[SceneGeometry<'_>],
    ) {
        use vk::ImageLayout as L;
        let device = &self.ctx.device;
        let colors = self.out.colors();
        let depth_target = [&self.out.depth];
        // WAR: the previous frame's compute reads finish before the targets are cleared.
        barrier::transition(
            device,
            cmd,
            &colors,
            (access::COMPUTE_READ, access::COLOR_WRITE),
            (L::UNDEFINED, L::COLOR_ATTACHMENT_OPTIMAL),
        );
        barrier::transition(
            device,
            cmd,
            &depth_target,
            (access::COMPUTE_READ, access::DEPTH_WRITE),
            (L::UNDEFINED, L::DEPTH_ATTACHMENT_OPTIMAL),
        );
        let (attachments, depth) = self.attachments();
        let extent = self.out.depth.extent;
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(1)
            .color_attachments(&attachments)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording outside a render pass; the attachments are live and
        // in their attachment layouts (the transitions above).
        unsafe { device.cmd_begin_rendering(cmd, &info) };
        set_viewport(device, cmd, extent);
        for geometry in geometries {
            self.pipeline.bind(
                cmd,
                &[
                    ("frame", Resource::Buffer(frame)),
                    ("vertices", Resource::Buffer(geometry.vertices)),
                    ("materials", Resource::Buffer(surfaces.materials)),
                    ("uvs", Resource::Buffer(geometry.uvs)),
                    ("scene_textures", Resource::Sampled(surfaces.textures, surfaces.sampler)),
                    ("previous", Resource::Buffer(geometry.previous)),
                    (
                        "data_textures",
                        Resource::SampledData(surfaces.textures, surfaces.sampler),
                    ),
                ],
                &(),
            );
            // SAFETY: inside the rendering begun above, with the pipeline bound; the
            // index buffer is live and holds `index_count` indices.
            unsafe {
                device.cmd_bind_index_buffer(cmd, geometry.indices.raw, 0, vk::IndexType::UINT32);
                device.cmd_draw_indexed(cmd, geometry.index_count, 1, 0, 0, 0);
            }
        }
        // SAFETY: ends the rendering begun above, on the same command buffer.
        unsafe { device.cmd_end_rendering(cmd) };
        // RAW: the compute passes read the G-buffer written above.
        barrier::transition(
            device,
            cmd,
            &colors,
            (access::COLOR_WRITE, access::COMPUTE_READ),
            (L::COLOR_ATTACHMENT_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
        );
        barrier::transition(
            device,
            cmd,
            &depth_target,
            (access::DEPTH_WRITE, access::COMPUTE_READ),
            (L::DEPTH_ATTACHMENT_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
        );
    }

    /// The G-buffer's colour attachments (cleared to zero, the material to
    /// `MATERIAL_NONE`) and its depth attachment (cleared to 1), stored.
    fn attachments(
        &self,
    ) -> (
        Vec<vk::RenderingAttachmentInfo<'static>>,
        vk::RenderingAttachmentInfo<'static>,
    ) {
        let clear_float = vk::ClearValue {
            color: vk::ClearColorValue { float32: [0.0; 4] },
        };
        let clear_none = vk::ClearValue {
            color: vk::ClearColorValue {
                uint32: [MATERIAL_NONE; 4],
            },
        };
        let colors: Vec<_> = self
            .out
            .colors()
            .iter()
            .zip([clear_float, clear_float, clear_none, clear_float])
            .map(|(img, clear)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(clear)
            })
            .collect();
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.out.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 },
            });
        (colors, depth)
    }
}
