//! A window's swapchain: images a frame is blitted into and an overlay drawn over, one
//! "rendering done" semaphore per image (a present may still wait on an image's
//! semaphore when its frame slot comes round again, so they cannot be per slot), and
//! the commands that move an image from acquire to present: `record_blit` (a frame
//! into it), `record_overlay` (dynamic rendering on it), `record_finish` (to the
//! present layout, copied out first for a window shot). `FrameSync` (frame_sync.rs)
//! acquires, submits and presents.

use super::barrier;
use super::buffer::Buffer;
use super::context::Context;
use super::image::Image;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// (stage, access, layout) of one use of a swapchain image.
type Use = (vk::PipelineStageFlags2, vk::AccessFlags2, vk::ImageLayout);

/// To be drawn on as a colour attachment (the overlay loads and stores it).
const TO_DRAW: Use = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw() | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw(),
    ),
    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
);

/// Drawn on (the overlay's writes, or none after `TO_DRAW`).
const DRAWN: Use = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
);

/// Records one whole-image colour barrier from one use to another.
fn image_barrier(d: &ash::Device, cmd: vk::CommandBuffer, image: vk::Image, from: Use, to: Use) {
    let color = vk::ImageAspectFlags::COLOR;
    let b = barrier::image(image, color, (from.0, from.1), (to.0, to.1), from.2, to.2);
    barrier::record(d, cmd, &[], &[b]);
}

/// Present modes in the order the demo cycles through them.
pub const PRESENT_MODES: [vk::PresentModeKHR; 3] = [
    vk::PresentModeKHR::FIFO,
    vk::PresentModeKHR::MAILBOX,
    vk::PresentModeKHR::IMMEDIATE,
];

/// A present mode's name, as the HUD and the screenshot JSON show it.
pub fn present_mode_name(mode: vk::PresentModeKHR) -> &'static str {
    match mode {
        vk::PresentModeKHR::FIFO => "fifo",
        vk::PresentModeKHR::MAILBOX => "mailbox",
        vk::PresentModeKHR::IMMEDIATE => "immediate",
        vk::PresentModeKHR::FIFO_RELAXED => "fifo_relaxed",
        _ => "other",
    }
}

pub struct Swapchain {
    ctx: Arc<Context>,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub views: Vec<vk::ImageView>,
    /// Signalled by the frame that draws image i, waited for by its present.
    pub rendered: Vec<vk::Semaphore>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    /// The images can be copied from (`window-shot`).
    pub readable: bool,
}

/// The formats the demo presents in, best first: UNORM, because the frame is already
/// sRGB-encoded by `compose` and the blit copies it unchanged.
const FORMATS: [vk::Format; 2] = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];

/// The present modes the surface offers, in `PRESENT_MODES` order.
pub fn supported_present_modes(ctx: &Context) -> Result<Vec<vk::PresentModeKHR>> {
    let s = ctx.surface.as_ref().expect("the demo's context has a surface");
    let modes = unsafe {
        s.loader
            .get_physical_device_surface_present_modes(ctx.physical_device, s.raw)
    }
    .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
    Ok(PRESENT_MODES.into_iter().filter(|m| modes.contains(m)).collect())
}

impl Swapchain {
    /// A swapchain for a window whose drawable area is `size`, presenting with `mode`
    /// (FIFO when the surface lacks it), replacing `old` if given (which the caller
    /// destroys once no frame uses it). `None` when the surface has no area (a
    /// minimized window): frames are skipped until it has.
    pub fn new(
        ctx: &Arc<Context>,
        size: (u32, u32),
        mode: vk::PresentModeKHR,
        old: Option<&Swapchain>,
    ) -> Result<Option<Self>> {
        let s = ctx.surface.as_ref().expect("the demo's context has a surface");
        let pd = ctx.physical_device;
        let caps = unsafe { s.loader.get_physical_device_surface_capabilities(pd, s.raw) }
            .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        // current_extent is u32::MAX when the window's size decides.
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        let format = surface_format(s, pd)?;
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(usage) {
            return Err(Error::NoDevice(
                "the window's swapchain images cannot be blit targets and colour attachments".into(),
            ));
        }
        // Copies out of the shown frame (HUD included) for window shots, where offered.
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let modes = supported_present_modes(ctx)?;
        let present_mode = if modes.contains(&mode) {
            mode
        } else {
            vk::PresentModeKHR::FIFO
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = composite_alpha(caps.supported_composite_alpha);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(s.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let raw = unsafe { s.swapchain.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        let mut chain = Self {
            ctx: ctx.clone(),
            raw,
            images: Vec::new(),
            views: Vec::new(),
            rendered: Vec::new(),
            format: format.format,
            extent,
            present_mode,
            readable,
        };
        // From here on, Drop cleans up whatever was made.
        chain.images = unsafe { s.swapchain.get_swapchain_images(raw) }.vk("vkGetSwapchainImagesKHR")?;
        chain.make_views()?;
        Ok(Some(chain))
    }

    /// A view and a "rendered" semaphore per swapchain image.
    fn make_views(&mut self) -> Result<()> {
        for (i, &image) in self.images.clone().iter().enumerate() {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.format)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .level_count(1)
                        .layer_count(1),
                );
            let view = unsafe { self.ctx.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
            self.views.push(view);
            let sem = unsafe {
                self.ctx
                    .device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }
            .vk("vkCreateSemaphore")?;
            self.ctx.set_name(sem, &format!("swapself.rendered[{i}]"));
            self.rendered.push(sem);
        }
        Ok(())
    }

    /// Records the blit of `frame` (a colour image left in `GENERAL` by compute writes)
    /// into image `i`, scaled to it; leaves image `i` ready to be drawn on (`TO_DRAW`) and
    /// `frame` in `GENERAL` again. The acquire semaphore must be waited for at the
    /// transfer stage (the first transition waits there too).
    pub fn record_blit(&self, cmd: vk::CommandBuffer, i: usize, frame: &Image) {
        let (d, dst, dst_extent) = (&self.ctx.device, self.images[i], self.extent);
        let (src, src_extent) = (frame.raw, frame.extent);
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        // WAW: the acquired image's previous contents are dropped after the acquire.
        image_barrier(
            d,
            cmd,
            dst,
            (S::ALL_TRANSFER, A::NONE, L::UNDEFINED),
            (S::BLIT, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
        );
        // RAW: the blit reads the frame in TRANSFER_SRC_OPTIMAL (the layout a driver may
        // prefer), after the compute pass's writes.
        image_barrier(
            d,
            cmd,
            src,
            (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE, L::GENERAL),
            (S::BLIT, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL),
        );
        let corner = |e: vk::Extent2D| vk::Offset3D {
            x: e.width as i32,
            y: e.height as i32,
            z: 1,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = [vk::ImageBlit2::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner(src_extent)])
            .dst_subresource(layers)
            .dst_offsets([vk::Offset3D::default(), corner(dst_extent)])];
        let filter = if src_extent == dst_extent {
            vk::Filter::NEAREST
        } else {
            vk::Filter::LINEAR
        };
        let info = vk::BlitImageInfo2::default()
            .src_image(src)
            .src_image_layout(L::TRANSFER_SRC_OPTIMAL)
            .dst_image(dst)
            .dst_image_layout(L::TRANSFER_DST_OPTIMAL)
            .regions(&region)
            .filter(filter);
        unsafe { d.cmd_blit_image2(cmd, &info) };
        // WAR: the frame goes back to GENERAL once read, before anything else (the
        // next frame's writes, a readback) touches it.
        image_barrier(
            d,
            cmd,
            src,
            (S::BLIT, A::NONE, L::TRANSFER_SRC_OPTIMAL),
            (S::ALL_COMMANDS, A::MEMORY_READ | A::MEMORY_WRITE, L::GENERAL),
        );
        // RAW: the overlay draws over the blitted image.
        image_barrier(
            d,
            cmd,
            dst,
            (S::BLIT, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
            TO_DRAW,
        );
    }

    /// Records `draw` inside dynamic rendering on image `i` (loaded and stored, as
    /// `record_blit` left it).
    pub fn record_overlay<R>(&self, cmd: vk::CommandBuffer, i: usize, draw: impl FnOnce() -> R) -> R {
        let d = &self.ctx.device;
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(self.views[i])
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent: self.extent,
            })
            .layer_count(1)
            .color_attachments(&color);
        unsafe { d.cmd_begin_rendering(cmd, &rendering) };
        let r = draw();
        unsafe { d.cmd_end_rendering(cmd) };
        r
    }

    /// A host-readable buffer for a copy of one image (`record_finish`), or an error
    /// naming `what` when this swapchain's images cannot be copied from.
    pub fn shot_buffer(&self, what: &str) -> Result<Buffer> {
        if !self.readable {
            return Err(Error::Window(format!(
                "cannot save {what}: this window's swapchain images cannot be copied from"
            )));
        }
        let bytes = self.extent.width as u64 * self.extent.height as u64 * 4;
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        Buffer::new(&self.ctx, "swapchain.shot", bytes, usage, MemoryLocation::GpuToCpu)
    }

    /// Records the move of image `i` (drawn on) to the present layout, copying it into
    /// `copy` first when given (a `shot_buffer`; the host reads it after the frame's
    /// fence, as `rgba_of_shot` does).
    pub fn record_finish(&self, cmd: vk::CommandBuffer, i: usize, copy: Option<&Buffer>) {
        let (d, image) = (&self.ctx.device, self.images[i]);
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        // The present waits on the frame's semaphore; no stage of this queue follows.
        let present = (S::NONE, A::NONE, L::PRESENT_SRC_KHR);
        let Some(buffer) = copy else {
            // RAW: the present reads what was drawn.
            return image_barrier(d, cmd, image, DRAWN, present);
        };
        let copying = (S::COPY, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL);
        // RAW: the copy reads what was drawn.
        image_barrier(d, cmd, image, DRAWN, copying);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: self.extent.width,
                height: self.extent.height,
                depth: 1,
            });
        unsafe { d.cmd_copy_image_to_buffer(cmd, image, L::TRANSFER_SRC_OPTIMAL, buffer.raw, &[region]) };
        // RAW: the host reads the copy after the frame's fence.
        barrier::global(d, cmd, (S::COPY, A::TRANSFER_WRITE), (S::HOST, A::HOST_READ));
        // WAR: the present reads the image after the copy.
        image_barrier(d, cmd, image, copying, present);
    }

    /// A finished `record_finish` copy as tightly packed RGBA8, opaque.
    pub fn rgba_of_shot(&self, copy: &Buffer) -> Vec<u8> {
        // The same host read of GpuToCpu memory as Buffer::read's staging copy.
        let mut rgba = copy.mapped().expect("GpuToCpu is mapped").to_vec();
        if self.format == vk::Format::B8G8R8A8_UNORM {
            for px in rgba.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        for px in rgba.chunks_exact_mut(4) {
            px[3] = 255;
        }
        rgba
    }
}

impl Drop for Swapchain {
    /// The caller has waited for every frame that used the swapchain.
    fn drop(&mut self) {
        let d = &self.ctx.device;
        unsafe {
            for &v in &self.views {
                d.destroy_image_view(v, None);
            }
            for &s in &self.rendered {
                d.destroy_semaphore(s, None);
            }
            if let Some(s) = &self.ctx.surface {
                s.swapchain.destroy_swapchain(self.raw, None);
            }
        }
    }
}

/// The first of `FORMATS` the surface offers in sRGB colour space.
fn surface_format(s: &super::context::Surface, pd: vk::PhysicalDevice) -> Result<vk::SurfaceFormatKHR> {
    let formats = unsafe { s.loader.get_physical_device_surface_formats(pd, s.raw) }
        .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
    FORMATS
        .iter()
        .find_map(|f| {
            formats
                .iter()
                .find(|sf| sf.format == *f && sf.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        })
        .copied()
        .ok_or_else(|| {
            Error::NoDevice(format!(
                "the window offers no B8G8R8A8_UNORM or R8G8B8A8_UNORM sRGB surface format (it offers {:?})",
                formats.iter().map(|f| f.format).collect::<Vec<_>>()
            ))
        })
}

/// The first composite alpha the surface supports, opaque preferred.
fn composite_alpha(supported: vk::CompositeAlphaFlagsKHR) -> vk::CompositeAlphaFlagsKHR {
    [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|a| supported.contains(*a))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE)
}
