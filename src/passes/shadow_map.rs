//! `shadow.map`: depth-only raster of the scene from the directional light, into a
//! square D32 map that `light.direct` filters with PCF.
//! No CPU reference of its own (a raster pass): `cpu_ref::shading::shadow_visibility`
//! reads the map it writes, and the shadow tests check it against a control scene.

use super::{set_viewport, SceneGeometry};
use crate::error::Result;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GraphicsDesc, Image, Pipeline, Resource};
use ash::vk;
use std::sync::Arc;

pub const NAME: &str = "shadow.map";
pub const FORMAT: vk::Format = crate::vk::device::DEPTH_FORMAT;

pub struct ShadowMapPass {
    ctx: Arc<Context>,
    pipeline: Pipeline,
    /// The shadow map; `SHADER_READ_ONLY_OPTIMAL` between frames.
    pub out: Image,
}

impl ShadowMapPass {
    /// `size`: map edge in texels; `slope_bias`: raster slope-scaled depth bias.
    pub fn new(ctx: &Arc<Context>, size: u32, slope_bias: f32) -> Result<Self> {
        let pipeline = Pipeline::graphics::<()>(
            ctx,
            NAME,
            &GraphicsDesc {
                vertex: shaders::SHADOW_MAP_VERT,
                fragment: None,
                color_formats: &[],
                depth_format: FORMAT,
                depth_bias: Some((0.0, slope_bias)),
            },
        )?;
        let map = Image::new(
            ctx,
            "shadow.map",
            vk::Extent2D {
                width: size,
                height: size,
            },
            FORMAT,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST,
        )?;
        // Cleared to the far plane (nothing casts) and left readable: under `rays`
        // shadows no frame renders it, but the kernels that could read it bind it.
        ctx.one_shot(|cmd| {
            use vk::ImageLayout as L;
            let to_clear = (access::NONE, access::TRANSFER_WRITE);
            barrier::transition(
                &ctx.device,
                cmd,
                &[&map],
                to_clear,
                (L::UNDEFINED, L::TRANSFER_DST_OPTIMAL),
            );
            let range = vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::DEPTH)
                .level_count(1)
                .layer_count(1);
            let far = vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 };
            // SAFETY: `cmd` is recording; the map is live and in TRANSFER_DST_OPTIMAL
            // (the transition above).
            unsafe {
                ctx.device
                    .cmd_clear_depth_stencil_image(cmd, map.raw, L::TRANSFER_DST_OPTIMAL, &far, &[range])
            };
            let to_read = (access::TRANSFER_WRITE, access::ANY_SHADER_READ);
            barrier::transition(
                &ctx.device,
                cmd,
                &[&map],
                to_read,
                (L::TRANSFER_DST_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
            );
        })?;
        Ok(Self {
            ctx: ctx.clone(),
            pipeline,
            out: map,
        })
    }

    /// Records the depth pass. The map ends in `SHADER_READ_ONLY_OPTIMAL`, visible to
    /// its readers: `light.direct` and `rt.reflect` (compute).
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &Buffer, geometries: &[SceneGeometry<'_>]) {
        use vk::ImageLayout as L;
        let device = &self.ctx.device;
        // WAR: the previous frame's compute reads finish before the map is cleared (old
        // contents discarded).
        barrier::transition(
            device,
            cmd,
            &[&self.out],
            (access::COMPUTE_READ, access::DEPTH_WRITE),
            (L::UNDEFINED, L::DEPTH_ATTACHMENT_OPTIMAL),
        );
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.out.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 },
            });
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: self.out.extent,
            })
            .layer_count(1)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording outside a render pass; the attachment is live and
        // in DEPTH_ATTACHMENT_OPTIMAL (the transition above).
        unsafe { device.cmd_begin_rendering(cmd, &info) };
        set_viewport(device, cmd, self.out.extent);
        for geometry in geometries {
            self.pipeline.bind(
                cmd,
                &[
                    ("frame", Resource::Buffer(frame)),
                    ("vertices", Resource::Buffer(geometry.vertices)),
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
        // RAW: the compute passes sample the depth written above.
        barrier::transition(
            device,
            cmd,
            &[&self.out],
            (access::DEPTH_WRITE, access::COMPUTE_READ),
            (L::DEPTH_ATTACHMENT_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
        );
    }
}
