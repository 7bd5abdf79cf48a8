//! The window's swapchain: images the frame is blitted into and the HUD drawn over,
//! one "rendering done" semaphore per image (a present may still wait on an image's
//! semaphore when its frame slot comes round again, so they cannot be per slot).

use crate::error::{Error, Result, VkContext};
use crate::vk::Context;
use ash::vk;
use std::sync::Arc;

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
        let formats = unsafe { s.loader.get_physical_device_surface_formats(pd, s.raw) }
            .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = FORMATS
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
            })?;
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
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
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
        for (i, &image) in chain.images.clone().iter().enumerate() {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(chain.format)
                .subresource_range(color_range());
            let view = unsafe { ctx.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
            chain.views.push(view);
            let sem = unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .vk("vkCreateSemaphore")?;
            ctx.set_name(sem, &format!("swapchain.rendered[{i}]"));
            chain.rendered.push(sem);
        }
        Ok(Some(chain))
    }
}

/// The colour aspect's single mip level and layer.
pub fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
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
