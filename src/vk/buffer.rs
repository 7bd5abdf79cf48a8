//! Buffers with debug names, allocated through gpu-allocator, plus staged upload and
//! readback. Device-local memory is never mapped: real GPUs may not allow it.

use super::barrier::{self, access};
use super::context::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A buffer and its memory; freed on drop.
pub struct Buffer {
    ctx: Arc<Context>,
    pub raw: vk::Buffer,
    /// Size in bytes.
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    /// Creates a buffer of `size` bytes (at least 4, so empty data still binds).
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        // Every buffer is bound whole (`info()`), so its size must fit the range limit of
        // each descriptor kind it may be bound as.
        let what = || format!("buffer '{name}'");
        if usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) {
            let limit = ctx.limits.max_storage_buffer_range as u64;
            ctx.check_limit(what, size, "bytes", "maxStorageBufferRange", limit)?;
        }
        if usage.contains(vk::BufferUsageFlags::UNIFORM_BUFFER) {
            let limit = ctx.limits.max_uniform_buffer_range as u64;
            ctx.check_limit(what, size, "bytes", "maxUniformBufferRange", limit)?;
        }
        if usage.contains(vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER) {
            // Viewed whole as 16-byte texels (`TexelView`).
            let limit = ctx.limits.max_texel_buffer_elements as u64;
            ctx.check_limit(
                what,
                size.div_ceil(16),
                "16-byte texels",
                "maxTexelBufferElements",
                limit,
            )?;
        }
        Self::unbound(ctx, name, size, usage, location)
    }

    /// A buffer no descriptor binds (acceleration-structure storage, build scratch): no
    /// descriptor range limit applies to it.
    pub fn unbound(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        let raw = unsafe { ctx.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = ctx
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| {
                unsafe { ctx.device.destroy_buffer(raw, None) };
                Error::Allocation {
                    name: name.into(),
                    source,
                }
            })?;
        let buffer = Self {
            ctx: ctx.clone(),
            raw,
            size,
            allocation: Some(allocation),
        };
        let a = buffer.allocation.as_ref().expect("just set");
        unsafe { ctx.device.bind_buffer_memory(raw, a.memory(), a.offset()) }.vk("vkBindBufferMemory")?;
        ctx.set_name(raw, name);
        Ok(buffer)
    }

    /// A device-local buffer that compute passes write and read, that indirect
    /// dispatches read their arguments from, and that tests fill and read back: pixel
    /// and tile lists, per-tile data, dispatch arguments.
    pub fn device_list(ctx: &Arc<Context>, name: &str, size: u64) -> Result<Self> {
        Self::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::INDIRECT_BUFFER,
            MemoryLocation::GpuOnly,
        )
    }

    /// A device-local buffer filled with `data` through a staging copy.
    pub fn with_data(ctx: &Arc<Context>, name: &str, usage: vk::BufferUsageFlags, data: &[u8]) -> Result<Self> {
        let buffer = Self::new(
            ctx,
            name,
            data.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        buffer.write(data)?;
        Ok(buffer)
    }

    /// Host-visible bytes, for buffers created `CpuToGpu` or `GpuToCpu`.
    pub fn mapped(&self) -> Option<&[u8]> {
        let a = self.allocation.as_ref()?;
        a.mapped_slice().map(|s| &s[..self.size as usize])
    }

    /// Mutable host-visible bytes, for buffers created `CpuToGpu`.
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        let a = self.allocation.as_mut()?;
        a.mapped_slice_mut().map(|s| &mut s[..size])
    }

    /// Overwrites the start of the buffer with `data` through a staging buffer, then
    /// makes the write visible to every later command.
    pub fn write(&self, data: &[u8]) -> Result<()> {
        if data.is_empty() {
            return Ok(());
        }
        let mut staging = Self::new(
            &self.ctx,
            "staging.upload",
            data.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.mapped_mut().expect("CpuToGpu is mapped")[..data.len()].copy_from_slice(data);
        let device = &self.ctx.device;
        self.ctx.one_shot(|cmd| {
            // WAR/WAW: earlier GPU work on this buffer finishes before the copy overwrites it.
            barrier::record(
                device,
                cmd,
                &[barrier::memory(access::ALL_READ_WRITE, access::TRANSFER_WRITE)],
                &[],
            );
            let region = vk::BufferCopy::default().size(data.len() as u64);
            unsafe { device.cmd_copy_buffer(cmd, staging.raw, self.raw, &[region]) };
            // RAW: the uploaded bytes are visible to every later command.
            barrier::record(
                device,
                cmd,
                &[barrier::memory(access::TRANSFER_WRITE, access::ALL_READ_WRITE)],
                &[],
            );
        })
    }

    /// Copies the whole buffer back to the host.
    pub fn read(&self) -> Result<Vec<u8>> {
        let staging = Self::new(
            &self.ctx,
            "staging.readback",
            self.size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let device = &self.ctx.device;
        self.ctx.one_shot(|cmd| {
            // RAW: earlier GPU writes to this buffer land before the copy reads it.
            barrier::record(
                device,
                cmd,
                &[barrier::memory(access::ALL_READ_WRITE, access::TRANSFER_READ)],
                &[],
            );
            let region = vk::BufferCopy::default().size(self.size);
            unsafe { device.cmd_copy_buffer(cmd, self.raw, staging.raw, &[region]) };
            // RAW: the copy is visible to the host before it maps the staging buffer.
            barrier::record(
                device,
                cmd,
                &[barrier::memory(access::TRANSFER_WRITE, access::HOST_READ)],
                &[],
            );
        })?;
        Ok(staging.mapped().expect("GpuToCpu is mapped").to_vec())
    }

    /// The buffer's device address (it was made with `SHADER_DEVICE_ADDRESS` usage, on a
    /// context with `bufferDeviceAddress`: `Context::ray_tracing`).
    pub fn address(&self) -> vk::DeviceAddress {
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        unsafe { self.ctx.device.get_buffer_device_address(&info) }
    }

    /// The whole buffer as a descriptor range.
    pub fn info(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default()
            .buffer(self.raw)
            .range(vk::WHOLE_SIZE)
    }
}

/// A whole buffer seen as a uniform texel buffer of `R32G32B32A32_UINT` texels (its
/// size a multiple of 16 bytes, its usage with `UNIFORM_TEXEL_BUFFER`): what kernels
/// read with `texelFetch` on a `utextureBuffer`. Destroyed on drop.
pub struct TexelView {
    ctx: Arc<Context>,
    pub raw: vk::BufferView,
}

impl TexelView {
    pub fn new(ctx: &Arc<Context>, buffer: &Buffer) -> Result<Self> {
        debug_assert!(buffer.size.is_multiple_of(16));
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(vk::Format::R32G32B32A32_UINT)
            .offset(0)
            .range(vk::WHOLE_SIZE);
        let raw = unsafe { ctx.device.create_buffer_view(&info, None) }.vk("vkCreateBufferView")?;
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

/// A device-local buffer the host rewrites every frame: one mapped staging buffer per
/// frame slot (a slot's frame has finished before the host writes it again), copied
/// into the device buffer when the slot's frame is recorded.
pub struct Staged {
    ctx: Arc<Context>,
    name: String,
    pub device: Buffer,
    staging: Vec<Buffer>,
}

impl Staged {
    /// `size` bytes on the device (with `usage` and as a copy's destination), with one
    /// staging slot.
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64, usage: vk::BufferUsageFlags) -> Result<Self> {
        let usage = usage | vk::BufferUsageFlags::TRANSFER_DST;
        Ok(Self {
            ctx: ctx.clone(),
            name: name.into(),
            device: Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?,
            staging: vec![Self::staging(ctx, name, size)?],
        })
    }

    fn staging(ctx: &Arc<Context>, name: &str, size: u64) -> Result<Buffer> {
        let usage = vk::BufferUsageFlags::TRANSFER_SRC;
        Buffer::new(ctx, &format!("{name}_staging"), size, usage, MemoryLocation::CpuToGpu)
    }

    /// One staging buffer per frame slot.
    pub fn set_slots(&mut self, n: usize) -> Result<()> {
        self.staging.truncate(n.max(1));
        while self.staging.len() < n {
            self.staging
                .push(Self::staging(&self.ctx, &self.name, self.device.size)?);
        }
        Ok(())
    }

    pub fn slots(&self) -> usize {
        self.staging.len()
    }

    /// Writes `bytes` (at most the buffer's size) into slot `slot`'s staging.
    pub fn write(&mut self, slot: usize, bytes: &[u8]) {
        self.staging[slot].mapped_mut().expect("CpuToGpu is mapped")[..bytes.len()].copy_from_slice(bytes);
    }

    /// Records the copy of slot `slot`'s staging into the device buffer, after the
    /// compute reads of the last frame and visible to this frame's compute reads.
    pub fn record_upload(&self, cmd: vk::CommandBuffer, slot: usize) {
        let d = &self.ctx.device;
        barrier::global(d, cmd, access::COMPUTE_READ, access::TRANSFER_WRITE);
        let region = vk::BufferCopy::default().size(self.device.size);
        unsafe { d.cmd_copy_buffer(cmd, self.staging[slot].raw, self.device.raw, &[region]) };
        barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ);
    }
}

impl Drop for TexelView {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_buffer_view(self.raw, None) };
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            // A free can only fail on a foreign allocation; nothing to do about it here.
            let _ = self.ctx.allocator().free(a);
        }
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}
