//! Acceleration structures (`VK_KHR_acceleration_structure`), the vendor tracer's
//! BVHs: a bottom level (BLAS) over triangles in a vertex and an index buffer, a top
//! level (TLAS) over instances of bottom levels. The driver builds them, on the GPU or
//! (lavapipe) on the CPU; its tree is its own.
//!
//! Needs `Context::ray_tracing`. Sizes and the scratch alignment are the device's; a
//! build beyond the device's primitive or instance count is refused with
//! `Error::DeviceLimit` before anything is recorded.

use super::barrier::{self, access};
use super::buffer::Buffer;
use super::context::Context;
use super::rt::RayTracing;
use super::timing::{GpuTimer, TimerReadout};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

fn rt(ctx: &Context) -> &RayTracing {
    ctx.ray_tracing
        .as_ref()
        .expect("acceleration structures need a context with ray tracing (Context::ray_tracing)")
}

/// One acceleration structure and the buffer that holds it; freed on drop.
pub struct Accel {
    ctx: Arc<Context>,
    pub raw: vk::AccelerationStructureKHR,
    pub buffer: Buffer,
    /// Its device address (what a TLAS instance names its BLAS by).
    pub address: vk::DeviceAddress,
}

impl Accel {
    /// An acceleration structure of `size` bytes (from `Build::sizes`) at `level`.
    pub fn new(ctx: &Arc<Context>, name: &str, level: vk::AccelerationStructureTypeKHR, size: u64) -> Result<Self> {
        let usage =
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let buffer = Buffer::unbound(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
        let info = vk::AccelerationStructureCreateInfoKHR::default()
            .buffer(buffer.raw)
            .size(size)
            .ty(level);
        let rt = rt(ctx);
        let raw =
            unsafe { rt.accel.create_acceleration_structure(&info, None) }.vk("vkCreateAccelerationStructureKHR")?;
        ctx.set_name(raw, name);
        let info = vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw);
        let address = unsafe { rt.accel.get_acceleration_structure_device_address(&info) };
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            buffer,
            address,
        })
    }
}

impl Drop for Accel {
    fn drop(&mut self) {
        unsafe { rt(&self.ctx).accel.destroy_acceleration_structure(self.raw, None) };
    }
}

/// Build scratch memory, its address aligned as the device asks.
pub struct Scratch {
    /// The memory (`address` is inside it).
    _buffer: Buffer,
    address: vk::DeviceAddress,
    pub size: u64,
}

impl Scratch {
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64) -> Result<Self> {
        let align = rt(ctx).limits.min_scratch_offset_alignment.max(1) as u64;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let buffer = Buffer::unbound(ctx, name, size + align, usage, MemoryLocation::GpuOnly)?;
        let address = buffer.address().next_multiple_of(align);
        Ok(Self {
            _buffer: buffer,
            address,
            size,
        })
    }
}

/// Triangles for a bottom level: each vertex's position is its first three floats of
/// `stride` bytes; indices are `u32`, three per triangle, from byte `index_offset` of
/// `indices` (a multiple of 4).
#[derive(Clone, Copy)]
pub struct Triangles<'a> {
    pub vertices: &'a Buffer,
    pub stride: u64,
    pub vertex_count: u32,
    pub indices: &'a Buffer,
    pub index_offset: u64,
    pub tri_count: u32,
}

/// What one build makes: the level, its flags and its one geometry (triangles or
/// instances) with its primitive count. Geometry is opaque (no any-hit shader runs)
/// and double-sided (nothing culls it): as the LBVH walk treats triangles.
pub struct Build {
    level: vk::AccelerationStructureTypeKHR,
    flags: vk::BuildAccelerationStructureFlagsKHR,
    geometry: vk::AccelerationStructureGeometryKHR<'static>,
    count: u32,
}

impl Build {
    /// A bottom level over `t`.
    pub fn triangles(ctx: &Context, t: &Triangles<'_>, flags: vk::BuildAccelerationStructureFlagsKHR) -> Result<Self> {
        let limit = rt(ctx).limits.max_primitive_count;
        let what = || "a bottom-level acceleration structure".to_string();
        ctx.check_limit(what, t.tri_count as u64, "triangles", "maxPrimitiveCount", limit)?;
        let data = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR {
                device_address: t.vertices.address(),
            })
            .vertex_stride(t.stride)
            .max_vertex(t.vertex_count.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR {
                device_address: t.indices.address() + t.index_offset,
            });
        Ok(Self {
            level: vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            flags,
            geometry: vk::AccelerationStructureGeometryKHR::default()
                .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
                .geometry(vk::AccelerationStructureGeometryDataKHR { triangles: data })
                .flags(vk::GeometryFlagsKHR::OPAQUE),
            count: t.tri_count,
        })
    }

    /// A top level over `count` `VkAccelerationStructureInstanceKHR`s in `instances`.
    pub fn instances(
        ctx: &Context,
        instances: &Buffer,
        count: u32,
        flags: vk::BuildAccelerationStructureFlagsKHR,
    ) -> Result<Self> {
        let limit = rt(ctx).limits.max_instance_count;
        let what = || "a top-level acceleration structure".to_string();
        ctx.check_limit(what, count as u64, "instances", "maxInstanceCount", limit)?;
        let data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR {
                device_address: instances.address(),
            });
        Ok(Self {
            level: vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            flags,
            geometry: vk::AccelerationStructureGeometryKHR::default()
                .geometry_type(vk::GeometryTypeKHR::INSTANCES)
                .geometry(vk::AccelerationStructureGeometryDataKHR { instances: data })
                .flags(vk::GeometryFlagsKHR::OPAQUE),
            count,
        })
    }

    fn info(&self, mode: vk::BuildAccelerationStructureModeKHR) -> vk::AccelerationStructureBuildGeometryInfoKHR<'_> {
        vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(self.level)
            .flags(self.flags)
            .mode(mode)
            .geometries(std::slice::from_ref(&self.geometry))
    }

    /// The device's sizes for this build: the structure, a build's and an update's
    /// scratch.
    pub fn sizes(&self, ctx: &Context) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        let info = self.info(vk::BuildAccelerationStructureModeKHR::BUILD);
        unsafe {
            rt(ctx).accel.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[self.count],
                &mut sizes,
            )
        };
        sizes
    }

    /// A new structure of the size this build needs.
    pub fn create(&self, ctx: &Arc<Context>, name: &str) -> Result<Accel> {
        Accel::new(ctx, name, self.level, self.sizes(ctx).acceleration_structure_size)
    }

    /// Records the build into `dst` (from nothing, or an update of `src`, which may be
    /// `dst` itself: the build needs `ALLOW_UPDATE`). The caller orders the inputs'
    /// writes before it (`access::AS_BUILD_INPUT`) and its result before the readers.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, dst: &Accel, src: Option<&Accel>, scratch: &Scratch) {
        let mode = if src.is_some() {
            vk::BuildAccelerationStructureModeKHR::UPDATE
        } else {
            vk::BuildAccelerationStructureModeKHR::BUILD
        };
        let mut info = self
            .info(mode)
            .dst_acceleration_structure(dst.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: scratch.address,
            });
        if let Some(src) = src {
            info = info.src_acceleration_structure(src.raw);
        }
        let range = vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(self.count);
        let ranges = [range];
        unsafe {
            rt(ctx)
                .accel
                .cmd_build_acceleration_structures(cmd, std::slice::from_ref(&info), &[&ranges[..]])
        };
    }
}

/// Timer scopes of `static_blas_timed`: the build, and the compacting copy.
pub const BUILD_SCOPE: &str = "as.build";
pub const COMPACT_SCOPE: &str = "as.compact";

/// Builds a bottom level over `t` once, for fast tracing, and compacts it: the
/// structure a static scene keeps.
pub fn static_blas(ctx: &Arc<Context>, name: &str, t: &Triangles<'_>) -> Result<Accel> {
    let mut timer = GpuTimer::new(ctx, 1)?;
    Ok(static_blas_timed(ctx, name, t, &mut timer)?.0)
}

/// `static_blas`, its two submissions timed on `timer`: the build (`BUILD_SCOPE`) and
/// the compacting copy (`COMPACT_SCOPE`); also returns the uncompacted size in bytes.
pub fn static_blas_timed(
    ctx: &Arc<Context>,
    name: &str,
    t: &Triangles<'_>,
    timer: &mut GpuTimer,
) -> Result<(Accel, [TimerReadout; 2], u64)> {
    let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
        | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION;
    let build = Build::triangles(ctx, t, flags)?;
    let sizes = build.sizes(ctx);
    let full_size = sizes.acceleration_structure_size;
    let full = Accel::new(
        ctx,
        &format!("{name}.uncompacted"),
        vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
        full_size,
    )?;
    let scratch = Scratch::new(ctx, &format!("{name}.scratch"), sizes.build_scratch_size)?;
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
        .query_count(1);
    let pool = unsafe { ctx.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
    let result = (|| {
        let built = timer.one_shot(|cmd, timer| {
            unsafe { ctx.device.cmd_reset_query_pool(cmd, pool, 0, 1) };
            timer.scope(cmd, BUILD_SCOPE, || build.record(ctx, cmd, &full, None, &scratch));
            // RAW: the size query reads the built structure.
            barrier::global(&ctx.device, cmd, access::AS_BUILD, access::AS_BUILD);
            unsafe {
                rt(ctx).accel.cmd_write_acceleration_structures_properties(
                    cmd,
                    &[full.raw],
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    pool,
                    0,
                )
            };
        })?;
        let mut size = [0u64];
        unsafe {
            ctx.device.get_query_pool_results(
                pool,
                0,
                &mut size,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        if size[0] == 0 || size[0] > full_size {
            return Err(Error::Pipeline(format!(
                "{name}: the driver reported a compacted size of {} B for a {full_size} B structure",
                size[0]
            )));
        }
        let compact = Accel::new(ctx, name, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, size[0])?;
        let copied = timer.one_shot(|cmd, timer| {
            let copy = vk::CopyAccelerationStructureInfoKHR::default()
                .src(full.raw)
                .dst(compact.raw)
                .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
            timer.scope(cmd, COMPACT_SCOPE, || unsafe {
                rt(ctx).accel.cmd_copy_acceleration_structure(cmd, &copy)
            });
        })?;
        Ok((compact, [built, copied], full_size))
    })();
    unsafe { ctx.device.destroy_query_pool(pool, None) };
    result
}

/// One instance of a bottom level in a top level: its 3x4 row-major object-to-world
/// transform, its custom index (24 bits, what `gl_InstanceCustomIndexEXT` reads), its
/// mask (a trace's cull mask selects it) and its bottom level's address. Triangles of
/// either facing are hit.
pub fn instance(
    transform: [[f32; 4]; 3],
    custom_index: u32,
    mask: u8,
    blas: vk::DeviceAddress,
) -> vk::AccelerationStructureInstanceKHR {
    debug_assert!(custom_index < 1 << 24);
    vk::AccelerationStructureInstanceKHR {
        transform: vk::TransformMatrixKHR {
            matrix: bytemuck::cast(transform),
        },
        instance_custom_index_and_mask: vk::Packed24_8::new(custom_index, mask),
        instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
            0,
            vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
        ),
        acceleration_structure_reference: vk::AccelerationStructureReferenceKHR { device_handle: blas },
    }
}

/// `VkAccelerationStructureInstanceKHR` as bytes (it is 64 bytes, packed).
pub fn instance_bytes(instances: &[vk::AccelerationStructureInstanceKHR]) -> Vec<u8> {
    let size = std::mem::size_of::<vk::AccelerationStructureInstanceKHR>();
    debug_assert_eq!(size, 64);
    // SAFETY: the struct is plain data of `size` bytes with no padding.
    unsafe { std::slice::from_raw_parts(instances.as_ptr() as *const u8, std::mem::size_of_val(instances)) }.to_vec()
}

/// The usage an instance buffer needs.
pub const INSTANCE_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR.as_raw()
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
);

/// `SHADER_DEVICE_ADDRESS` on a context with ray tracing (none otherwise): for buffers
/// the vendor tracer reads by address (trace-rays arguments).
pub fn address_usage(ctx: &Context) -> vk::BufferUsageFlags {
    if ctx.ray_tracing.is_some() {
        vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
    } else {
        vk::BufferUsageFlags::empty()
    }
}

/// The usage vertex and index buffers need to be a build's input, on a context with
/// ray tracing (none otherwise); and to be read back (the vendor tracer orders the
/// static triangles on the host).
pub fn input_usage(ctx: &Context) -> vk::BufferUsageFlags {
    if ctx.ray_tracing.is_some() {
        INSTANCE_USAGE | vk::BufferUsageFlags::TRANSFER_SRC
    } else {
        vk::BufferUsageFlags::empty()
    }
}
