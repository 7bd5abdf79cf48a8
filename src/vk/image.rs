//! 2D images with a view and a debug name, 2D array textures with mip chains,
//! samplers, and readback for tests and PNGs.

use super::barrier::{self, access};
use super::buffer::Buffer;
use super::context::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A 2D image with one view over all its layers and mips (single-mip, single-layer
/// unless made by `texture_array`); freed on drop.
pub struct Image {
    ctx: Arc<Context>,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    /// `texture_array`'s second view of the same texels, as `R8G8B8A8_UNORM` (data
    /// textures: no sRGB decode); null for every other image.
    pub data_view: vk::ImageView,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub aspect: vk::ImageAspectFlags,
    pub layers: u32,
    pub mips: u32,
    allocation: Option<Allocation>,
}

impl barrier::WholeImage for Image {
    fn handle_and_aspect(&self) -> (vk::Image, vk::ImageAspectFlags) {
        (self.raw, self.aspect)
    }
}

/// Bytes per texel of the formats Speculum uses.
pub fn texel_bytes(format: vk::Format) -> u64 {
    match format {
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_UNORM => 4,
        vk::Format::R32_UINT | vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => 4,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        other => panic!("texel_bytes: format {other:?} is not used by Speculum"),
    }
}

impl Image {
    /// Creates a device-local image. Depth formats get the DEPTH aspect.
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        extent: vk::Extent2D,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        Self::create(ctx, name, extent, format, usage, (1, 1), vk::ImageViewType::TYPE_2D)
    }

    /// `new` with (array layers, mip levels) and the view's type.
    fn create(
        ctx: &Arc<Context>,
        name: &str,
        extent: vk::Extent2D,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        (layers, mips): (u32, u32),
        view_type: vk::ImageViewType,
    ) -> Result<Self> {
        Self::create_with(ctx, name, extent, (format, None), usage, (layers, mips), view_type)
    }

    /// `create` with a second view of another (compatible) format: the image is made
    /// with `MUTABLE_FORMAT`, and `data_view` reads it as `data_format`.
    fn create_with(
        ctx: &Arc<Context>,
        name: &str,
        extent: vk::Extent2D,
        (format, data_format): (vk::Format, Option<vk::Format>),
        usage: vk::ImageUsageFlags,
        (layers, mips): (u32, u32),
        view_type: vk::ImageViewType,
    ) -> Result<Self> {
        if extent.width == 0 || extent.height == 0 {
            return Err(Error::Settings(format!(
                "image '{name}' of {}x{} has no texels",
                extent.width, extent.height
            )));
        }
        ctx.check_limit(
            || format!("image '{name}' of {}x{}", extent.width, extent.height),
            extent.width.max(extent.height) as u64,
            "texels per side",
            "maxImageDimension2D",
            ctx.limits.max_image_dimension2_d as u64,
        )?;
        ctx.check_limit(
            || format!("image '{name}'"),
            layers as u64,
            "array layers",
            "maxImageArrayLayers",
            ctx.limits.max_image_array_layers as u64,
        )?;
        let aspect = if format == vk::Format::D32_SFLOAT {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        };
        let flags = match data_format {
            Some(_) => vk::ImageCreateFlags::MUTABLE_FORMAT,
            None => vk::ImageCreateFlags::empty(),
        };
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width: extent.width,
                height: extent.height,
                depth: 1,
            })
            .mip_levels(mips)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { ctx.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = ctx
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| {
                unsafe { ctx.device.destroy_image(raw, None) };
                Error::Allocation {
                    name: name.into(),
                    source,
                }
            })?;
        let mut image = Self {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            data_view: vk::ImageView::null(),
            format,
            extent,
            aspect,
            layers,
            mips,
            allocation: Some(allocation),
        };
        let a = image.allocation.as_ref().expect("just set");
        unsafe { ctx.device.bind_image_memory(raw, a.memory(), a.offset()) }.vk("vkBindImageMemory")?;
        ctx.set_name(raw, name);
        image.view = image.make_view(view_type, format, name)?;
        if let Some(data_format) = data_format {
            image.data_view = image.make_view(view_type, data_format, &format!("{name}.data"))?;
        }
        Ok(image)
    }

    /// A view of every layer and mip of this image as `format`, named `name`.
    fn make_view(&self, view_type: vk::ImageViewType, format: vk::Format, name: &str) -> Result<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(format)
            .subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(self.aspect)
                    .level_count(self.mips)
                    .layer_count(self.layers),
            );
        let view = unsafe { self.ctx.device.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        self.ctx.set_name(view, name);
        Ok(view)
    }

    /// A device-local storage image that compute passes write and read, tests fill and
    /// read back. It is moved to `GENERAL` once, here, and stays there for its whole
    /// life: a frame orders its uses with memory barriers alone.
    pub fn storage(ctx: &Arc<Context>, name: &str, extent: vk::Extent2D, format: vk::Format) -> Result<Self> {
        let usage =
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
        let image = Self::new(ctx, name, extent, format, usage)?;
        ctx.one_shot(|cmd| {
            // Layout: GENERAL before any use (nothing has touched the image yet).
            barrier::transition(
                &ctx.device,
                cmd,
                &[&image],
                (access::NONE, access::ALL_READ_WRITE),
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
            )
        })?;
        Ok(image)
    }

    /// A sampled `R8G8B8A8_SRGB` 2D array texture of `size`² layers, each given as its
    /// full mip chain (largest first, tightly packed RGBA8 rows; `scene::texture::
    /// mip_chain`), uploaded and left in `SHADER_READ_ONLY_OPTIMAL`, with a second,
    /// `R8G8B8A8_UNORM` view (`data_view`) for data textures. The views are 2D arrays
    /// even for one layer, as `sampler2DArray` needs.
    pub fn texture_array(ctx: &Arc<Context>, name: &str, size: u32, layers: &[Vec<&[u8]>]) -> Result<Self> {
        let mips = size.ilog2() + 1;
        let extent = vk::Extent2D {
            width: size,
            height: size,
        };
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let formats = (vk::Format::R8G8B8A8_SRGB, Some(vk::Format::R8G8B8A8_UNORM));
        let image = Self::create_with(
            ctx,
            name,
            extent,
            formats,
            usage,
            (layers.len().max(1) as u32, mips),
            vk::ImageViewType::TYPE_2D_ARRAY,
        )?;
        let mut data = Vec::new();
        let mut regions = Vec::new();
        for (layer, chain) in layers.iter().enumerate() {
            assert_eq!(
                chain.len() as u32,
                mips,
                "texture_array: layer {layer} is not a full mip chain"
            );
            for (mip, texels) in chain.iter().enumerate() {
                let edge = (size >> mip).max(1);
                assert_eq!(
                    texels.len() as u64,
                    4 * edge as u64 * edge as u64,
                    "texture_array: level size"
                );
                regions.push(
                    vk::BufferImageCopy::default()
                        .buffer_offset(data.len() as u64)
                        .image_subresource(
                            vk::ImageSubresourceLayers::default()
                                .aspect_mask(image.aspect)
                                .mip_level(mip as u32)
                                .base_array_layer(layer as u32)
                                .layer_count(1),
                        )
                        .image_extent(vk::Extent3D {
                            width: edge,
                            height: edge,
                            depth: 1,
                        }),
                );
                data.extend_from_slice(texels);
            }
        }
        let mut staging = Buffer::new(
            ctx,
            "staging.texture_upload",
            data.len().max(4) as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.mapped_mut().expect("CpuToGpu is mapped")[..data.len()].copy_from_slice(&data);
        let device = &ctx.device;
        ctx.one_shot(|cmd| {
            let to_dst = barrier::image(
                image.raw,
                image.aspect,
                access::NONE,
                access::TRANSFER_WRITE,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            );
            barrier::record(device, cmd, &[], &[to_dst]);
            if !regions.is_empty() {
                unsafe {
                    device.cmd_copy_buffer_to_image(
                        cmd,
                        staging.raw,
                        image.raw,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &regions,
                    )
                };
            }
            // RAW: every later shader read sees the uploaded texels.
            let done = barrier::image(
                image.raw,
                image.aspect,
                access::TRANSFER_WRITE,
                access::ANY_SHADER_READ,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            );
            barrier::record(device, cmd, &[], &[done]);
        })?;
        Ok(image)
    }

    /// Size in bytes of the tightly packed texels.
    pub fn byte_size(&self) -> u64 {
        self.extent.width as u64 * self.extent.height as u64 * texel_bytes(self.format)
    }

    /// The whole image (its first level and layer) as one tightly packed buffer copy.
    pub fn copy_region(&self) -> vk::BufferImageCopy {
        vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(self.aspect)
                    .layer_count(1),
            )
            .image_extent(vk::Extent3D {
                width: self.extent.width,
                height: self.extent.height,
                depth: 1,
            })
    }

    /// Copies the texels to the host (tightly packed rows). The image is in `layout`
    /// before and after; all earlier GPU work on it is waited for.
    pub fn read(&self, layout: vk::ImageLayout) -> Result<Vec<u8>> {
        let staging = Buffer::new(
            &self.ctx,
            "staging.image_readback",
            self.byte_size(),
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let device = &self.ctx.device;
        self.ctx.one_shot(|cmd| {
            // RAW: earlier writes to the image finish before the copy reads it.
            let to_src = barrier::image(
                self.raw,
                self.aspect,
                access::ALL_READ_WRITE,
                access::TRANSFER_READ,
                layout,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            );
            barrier::record(device, cmd, &[], &[to_src]);
            unsafe {
                device.cmd_copy_image_to_buffer(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    staging.raw,
                    &[self.copy_region()],
                )
            };
            // WAR: later users wait for the copy; the image returns to its layout.
            let back = barrier::image(
                self.raw,
                self.aspect,
                access::TRANSFER_READ,
                access::ALL_READ_WRITE,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                layout,
            );
            // RAW: the host reads the staging buffer after the copy wrote it.
            barrier::record(
                device,
                cmd,
                &[barrier::memory(access::TRANSFER_WRITE, access::HOST_READ)],
                &[back],
            );
        })?;
        Ok(staging.mapped().expect("GpuToCpu is mapped").to_vec())
    }

    /// Fills the image with tightly packed texels and leaves it in `layout`.
    pub fn write(&self, data: &[u8], layout: vk::ImageLayout) -> Result<()> {
        assert_eq!(
            data.len() as u64,
            self.byte_size(),
            "Image::write: data size does not match the image"
        );
        let staging = Buffer::new(
            &self.ctx,
            "staging.image_upload",
            self.byte_size(),
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let mut staging = staging;
        staging.mapped_mut().expect("CpuToGpu is mapped").copy_from_slice(data);
        let device = &self.ctx.device;
        self.ctx.one_shot(|cmd| {
            // WAR: earlier users of the image finish before the copy overwrites it.
            let to_dst = barrier::image(
                self.raw,
                self.aspect,
                access::ALL_READ_WRITE,
                access::TRANSFER_WRITE,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            );
            barrier::record(device, cmd, &[], &[to_dst]);
            unsafe {
                device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[self.copy_region()],
                )
            };
            // RAW: later commands read the uploaded texels.
            let done = barrier::image(
                self.raw,
                self.aspect,
                access::TRANSFER_WRITE,
                access::ALL_READ_WRITE,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                layout,
            );
            barrier::record(device, cmd, &[], &[done]);
        })
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_image_view(self.view, None);
            self.ctx.device.destroy_image_view(self.data_view, None); // null: ignored
            self.ctx.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}

/// A sampler; freed on drop.
pub struct Sampler {
    ctx: Arc<Context>,
    pub raw: vk::Sampler,
}

impl Sampler {
    /// Nearest-texel, clamp-to-edge: for `texelFetch`-style reads and exact kernels.
    pub fn nearest_clamp(ctx: &Arc<Context>, name: &str) -> Result<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        Self::create(ctx, name, &info)
    }

    /// Trilinear (linear texels, linear between mips), repeating: for textures.
    pub fn trilinear_repeat(ctx: &Arc<Context>, name: &str) -> Result<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        Self::create(ctx, name, &info)
    }

    fn create(ctx: &Arc<Context>, name: &str, info: &vk::SamplerCreateInfo<'_>) -> Result<Self> {
        let raw = unsafe { ctx.device.create_sampler(info, None) }.vk("vkCreateSampler")?;
        ctx.set_name(raw, name);
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}
