//! Ray-tracing pipelines (`VK_KHR_ray_tracing_pipeline`): a ray-generation shader, miss
//! shaders and one closest-hit group over opaque triangles, with push descriptors as
//! every other pipeline (`Pipeline::bind`), and their shader binding table laid out
//! with the device's handle size and alignments.

use super::buffer::Buffer;
use super::context::Context;
use super::pipeline::{merge, module, push_size, Bind, Pipeline, Shader};
use crate::error::{Result, VkContext};
use ash::vk;
use bytemuck::Pod;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// The shaders of a ray-tracing pipeline: group 0 is the ray generation, groups
/// 1..=misses.len() the miss shaders (`traceRayEXT`'s miss index i is group 1 + i), the
/// last group the triangles' closest hit.
pub struct RtShaders<'a> {
    pub raygen: Shader,
    pub misses: &'a [Shader],
    pub closest_hit: Shader,
}

/// How many rays a trace launches (one dimension).
pub enum Launch<'a> {
    /// Exactly this many.
    Exact(u32),
    /// A grid of this width and height (`gl_LaunchIDEXT.xy`).
    Grid(u32, u32),
    /// A `VkTraceRaysIndirectCommandKHR` (width, height, depth) at this byte offset of
    /// this buffer, written on the GPU.
    Indirect(&'a Buffer, u64),
}

/// A ray-tracing pipeline and its shader binding table.
pub struct RtPipeline {
    pub pipeline: Pipeline,
    sbt: Buffer,
    regions: [vk::StridedDeviceAddressRegionKHR; 3],
}

const STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::RAYGEN_KHR.as_raw()
        | vk::ShaderStageFlags::MISS_KHR.as_raw()
        | vk::ShaderStageFlags::CLOSEST_HIT_KHR.as_raw(),
);

impl RtPipeline {
    /// A pipeline of `shaders` with push constants `P`, recursion depth 1 (shaders
    /// trace from the ray generation only).
    pub fn new<P: Pod>(ctx: &Arc<Context>, name: &'static str, shaders: &RtShaders<'_>) -> Result<Self> {
        let rt = ctx
            .ray_tracing
            .as_ref()
            .expect("ray-tracing pipelines need a context with ray tracing (Context::ray_tracing)");
        let mut all = vec![(vk::ShaderStageFlags::RAYGEN_KHR, shaders.raygen)];
        all.extend(shaders.misses.iter().map(|&m| (vk::ShaderStageFlags::MISS_KHR, m)));
        all.push((vk::ShaderStageFlags::CLOSEST_HIT_KHR, shaders.closest_hit));
        let mut modules = Vec::new();
        for (stage, shader) in &all {
            match module(ctx, *shader) {
                Ok(m) => modules.push((*stage, m)),
                Err(e) => {
                    modules
                        .iter()
                        .for_each(|(_, m)| unsafe { ctx.device.destroy_shader_module(m.raw, None) });
                    return Err(e);
                }
            }
        }
        let result = Self::with_modules::<P>(ctx, name, rt, &modules);
        for (_, m) in &modules {
            unsafe { ctx.device.destroy_shader_module(m.raw, None) };
        }
        result
    }

    fn with_modules<P: Pod>(
        ctx: &Arc<Context>,
        name: &'static str,
        rt: &super::rt::RayTracing,
        modules: &[(vk::ShaderStageFlags, super::pipeline::Module)],
    ) -> Result<Self> {
        let reflections: Vec<_> = modules.iter().map(|(s, m)| (*s, &m.reflection)).collect();
        let push = push_size::<P>(ctx, name, &reflections.iter().map(|r| r.1).collect::<Vec<_>>())?;
        let bindings = merge(name, &reflections)?;
        let layouts = Pipeline::layouts(ctx, name, &bindings, STAGES, push)?;
        let stages: Vec<_> = modules
            .iter()
            .map(|(stage, m)| {
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(*stage)
                    .module(m.raw)
                    .name(c"main")
            })
            .collect();
        let last = modules.len() as u32 - 1;
        let groups: Vec<_> = (0..modules.len() as u32)
            .map(|i| {
                let g = vk::RayTracingShaderGroupCreateInfoKHR::default()
                    .general_shader(vk::SHADER_UNUSED_KHR)
                    .closest_hit_shader(vk::SHADER_UNUSED_KHR)
                    .any_hit_shader(vk::SHADER_UNUSED_KHR)
                    .intersection_shader(vk::SHADER_UNUSED_KHR);
                if i == last {
                    g.ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                        .closest_hit_shader(i)
                } else {
                    g.ty(vk::RayTracingShaderGroupTypeKHR::GENERAL).general_shader(i)
                }
            })
            .collect();
        let info = vk::RayTracingPipelineCreateInfoKHR::default()
            .stages(&stages)
            .groups(&groups)
            .max_pipeline_ray_recursion_depth(1)
            .layout(layouts.1);
        let created = unsafe {
            rt.pipeline.create_ray_tracing_pipelines(
                vk::DeferredOperationKHR::null(),
                vk::PipelineCache::null(),
                &[info],
                None,
            )
        };
        let raw = match created.map_err(|(_, r)| r).vk("vkCreateRayTracingPipelinesKHR") {
            Ok(p) => p[0],
            Err(e) => {
                unsafe {
                    ctx.device.destroy_pipeline_layout(layouts.1, None);
                    ctx.device.destroy_descriptor_set_layout(layouts.0, None);
                }
                return Err(e);
            }
        };
        ctx.set_name(raw, name);
        let pipeline = Pipeline::from_parts::<P>(
            (ctx, name),
            raw,
            layouts,
            &bindings,
            vk::PipelineBindPoint::RAY_TRACING_KHR,
            STAGES,
            push,
        );
        let (sbt, regions) = shader_binding_table(ctx, name, rt, raw, modules.len() as u32)?;
        Ok(Self { pipeline, sbt, regions })
    }

    /// Binds, pushes and launches the rays: one per entry, `gl_LaunchIDEXT.x` (the
    /// launch's width; height and depth 1), or one per cell of a grid
    /// (`gl_LaunchIDEXT.xy`).
    pub fn trace<P: Pod>(&self, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P, launch: Launch<'_>) {
        self.pipeline.bind(cmd, resources, push);
        let rt = self.pipeline.ctx().ray_tracing.as_ref().expect("made with ray tracing");
        let [raygen, miss, hit] = &self.regions;
        let callable = vk::StridedDeviceAddressRegionKHR::default();
        debug_assert!(self.sbt.size > 0);
        // SAFETY: `cmd` is recording with this pipeline bound; the table lives as long
        // as the pipeline.
        unsafe {
            match launch {
                Launch::Exact(n) => rt.pipeline.cmd_trace_rays(cmd, raygen, miss, hit, &callable, n, 1, 1),
                Launch::Grid(w, h) => rt.pipeline.cmd_trace_rays(cmd, raygen, miss, hit, &callable, w, h, 1),
                Launch::Indirect(args, offset) => {
                    rt.pipeline
                        .cmd_trace_rays_indirect(cmd, raygen, miss, hit, &callable, args.address() + offset)
                }
            }
        }
    }
}

/// Where a shader binding table's regions lie: each region starts on
/// `shaderGroupBaseAlignment`, each record is `shaderGroupHandleSize` rounded up to
/// `shaderGroupHandleAlignment`, and the ray generation's one record fills its region
/// (Vulkan requires its size to equal its stride).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SbtLayout {
    pub record: u64,
    pub base: u64,
    pub raygen_size: u64,
    /// Byte offsets of the ray generation, miss and hit regions.
    pub offsets: [u64; 3],
    /// The table's bytes.
    pub size: u64,
}

impl SbtLayout {
    pub fn of(l: &super::rt::RtLimits, misses: u64) -> Self {
        let record =
            (l.shader_group_handle_size as u64).next_multiple_of(l.shader_group_handle_alignment.max(1) as u64);
        let base = l.shader_group_base_alignment.max(1) as u64;
        let raygen_size = record.next_multiple_of(base);
        let miss_size = (misses * record).next_multiple_of(base);
        let offsets = [0, raygen_size, raygen_size + miss_size];
        Self {
            record,
            base,
            raygen_size,
            offsets,
            size: offsets[2] + record,
        }
    }
}

/// The table: the ray generation's record, the misses', the hit group's, each region
/// starting on `shaderGroupBaseAlignment` and each record `shaderGroupHandleSize`
/// rounded up to `shaderGroupHandleAlignment`.
fn shader_binding_table(
    ctx: &Arc<Context>,
    name: &str,
    rt: &super::rt::RayTracing,
    pipeline: vk::Pipeline,
    groups: u32,
) -> Result<(Buffer, [vk::StridedDeviceAddressRegionKHR; 3])> {
    let l = &rt.limits;
    let handle = l.shader_group_handle_size as u64;
    let layout = SbtLayout::of(l, groups as u64 - 2);
    let (record, base, offsets) = (layout.record, layout.base, layout.offsets);
    let handles = unsafe {
        rt.pipeline
            .get_ray_tracing_shader_group_handles(pipeline, 0, groups, (groups as u64 * handle) as usize)
    }
    .vk("vkGetRayTracingShaderGroupHandlesKHR")?;
    let misses = groups as u64 - 2;
    let mut table = vec![0u8; layout.size as usize];
    let group_at = |g: u64| &handles[(g * handle) as usize..((g + 1) * handle) as usize];
    let mut put = |at: u64, g: u64| table[at as usize..(at + handle) as usize].copy_from_slice(group_at(g));
    put(0, 0);
    for m in 0..misses {
        put(offsets[1] + m * record, 1 + m);
    }
    put(offsets[2], groups as u64 - 1);
    let usage = vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    // The table's start must be base-aligned too: over-allocate by the alignment, and
    // upload the table at the first aligned address inside.
    let size = base + table.len() as u64;
    let usage = usage | vk::BufferUsageFlags::TRANSFER_DST;
    let sbt = Buffer::new(ctx, &format!("{name}.sbt"), size, usage, MemoryLocation::GpuOnly)?;
    let start = sbt.address().next_multiple_of(base);
    let mut aligned = vec![0u8; (start - sbt.address()) as usize];
    aligned.extend_from_slice(&table);
    aligned.resize(size as usize, 0);
    sbt.write(&aligned)?;
    let region = |at: u64, stride: u64, size: u64| {
        vk::StridedDeviceAddressRegionKHR::default()
            .device_address(start + at)
            .stride(stride)
            .size(size)
    };
    Ok((
        sbt,
        [
            region(0, layout.raygen_size, layout.raygen_size),
            region(offsets[1], record, misses * record),
            region(offsets[2], record, record),
        ],
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::rt::RtLimits;

    fn limits(handle: u32, handle_align: u32, base: u32) -> RtLimits {
        RtLimits {
            shader_group_handle_size: handle,
            shader_group_handle_alignment: handle_align,
            shader_group_base_alignment: base,
            max_ray_recursion_depth: 1,
            max_ray_dispatch_invocation_count: 1 << 30,
            min_scratch_offset_alignment: 128,
            max_geometry_count: 1 << 24,
            max_instance_count: 1 << 24,
            max_primitive_count: 1 << 29,
        }
    }

    /// The table's regions for NVIDIA's sizes (32-byte handles, 32-byte handle and
    /// 64-byte base alignment) and for others: every region base-aligned, every record
    /// handle-aligned and no smaller than a handle, no region overlapping the next.
    #[test]
    fn sbt_regions_follow_the_device_alignments() {
        let nvidia = SbtLayout::of(&limits(32, 32, 64), 1);
        assert_eq!(
            nvidia,
            SbtLayout {
                record: 32,
                base: 64,
                raygen_size: 64,
                offsets: [0, 64, 128],
                size: 160
            }
        );
        for (h, ha, b) in [(32, 32, 64), (32, 16, 64), (16, 16, 32), (24, 8, 256), (32, 64, 64)] {
            for misses in 1..4 {
                let s = SbtLayout::of(&limits(h, ha, b), misses);
                assert!(s.record >= h as u64 && s.record.is_multiple_of(ha as u64), "{s:?}");
                assert!(s.offsets.iter().all(|o| o.is_multiple_of(b as u64)), "{s:?}");
                assert!(s.raygen_size >= s.record && s.offsets[1] >= s.raygen_size, "{s:?}");
                assert!(s.offsets[2] >= s.offsets[1] + misses * s.record, "{s:?}");
                assert_eq!(s.size, s.offsets[2] + s.record);
            }
        }
    }
}
