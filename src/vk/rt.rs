//! Vendor ray tracing (`tracer = khr`): what a device must have for it, and the
//! extension entry points and limits a context keeps when it has it.
//!
//! Contract: `VK_KHR_acceleration_structure` (with its dependency
//! `VK_KHR_deferred_host_operations`) and `VK_KHR_ray_tracing_pipeline`, the features
//! `accelerationStructure`, `rayTracingPipeline`, `rayTracingPipelineTraceRaysIndirect`
//! (the ray lists are sized on the GPU) and `bufferDeviceAddress`. Ray queries are not
//! needed: NVIDIA's GPUs without RT cores (H100/H200) expose the pipeline but not them.
//! Every size and alignment below is the device's own, read here.

use ash::vk;
use std::ffi::CStr;

/// The device extensions the vendor tracer enables.
pub const EXTENSIONS: [&CStr; 3] = [
    ash::khr::acceleration_structure::NAME,
    ash::khr::deferred_host_operations::NAME,
    ash::khr::ray_tracing_pipeline::NAME,
];

/// A context's vendor ray tracing: the extensions' functions and the device's limits.
pub struct RayTracing {
    pub accel: ash::khr::acceleration_structure::Device,
    pub pipeline: ash::khr::ray_tracing_pipeline::Device,
    pub limits: RtLimits,
}

/// The device's ray-tracing sizes, alignments and counts.
#[derive(Clone, Copy, Debug)]
pub struct RtLimits {
    pub shader_group_handle_size: u32,
    pub shader_group_handle_alignment: u32,
    pub shader_group_base_alignment: u32,
    pub max_ray_recursion_depth: u32,
    pub max_ray_dispatch_invocation_count: u32,
    pub min_scratch_offset_alignment: u32,
    pub max_geometry_count: u64,
    pub max_instance_count: u64,
    pub max_primitive_count: u64,
}

/// What `pd` lacks for the vendor tracer, in one line (`None`: it has everything).
pub fn missing(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<String> {
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |name: &CStr| {
        exts.iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
    };
    let mut lacks: Vec<String> = EXTENSIONS
        .iter()
        .filter(|n| !has(n))
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    if lacks.is_empty() {
        let (mut accel, mut pipe, mut v12) = features();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut accel)
            .push_next(&mut pipe)
            .push_next(&mut v12);
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        for (name, on) in [
            ("accelerationStructure", accel.acceleration_structure),
            ("rayTracingPipeline", pipe.ray_tracing_pipeline),
            (
                "rayTracingPipelineTraceRaysIndirect",
                pipe.ray_tracing_pipeline_trace_rays_indirect,
            ),
            ("bufferDeviceAddress", v12.buffer_device_address),
        ] {
            if on == 0 {
                lacks.push(format!("the {name} feature"));
            }
        }
    }
    (!lacks.is_empty()).then(|| lacks.join(", "))
}

/// The feature structs the vendor tracer enables (empty, to query or to fill).
pub fn features() -> (
    vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'static>,
    vk::PhysicalDeviceVulkan12Features<'static>,
) {
    Default::default()
}

/// The features to enable on a device that has them all (`missing` is `None`).
pub fn enabled_features() -> (
    vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'static>,
    vk::PhysicalDeviceVulkan12Features<'static>,
) {
    (
        vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true),
        vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default()
            .ray_tracing_pipeline(true)
            .ray_tracing_pipeline_trace_rays_indirect(true),
        vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true),
    )
}

impl RayTracing {
    /// The loaders and limits of a device created with `EXTENSIONS` and `enabled_features`.
    pub fn new(instance: &ash::Instance, pd: vk::PhysicalDevice, device: &ash::Device) -> Self {
        let mut pipe = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut accel = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut pipe)
            .push_next(&mut accel);
        unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
        Self {
            accel: ash::khr::acceleration_structure::Device::new(instance, device),
            pipeline: ash::khr::ray_tracing_pipeline::Device::new(instance, device),
            limits: RtLimits {
                shader_group_handle_size: pipe.shader_group_handle_size,
                shader_group_handle_alignment: pipe.shader_group_handle_alignment,
                shader_group_base_alignment: pipe.shader_group_base_alignment,
                max_ray_recursion_depth: pipe.max_ray_recursion_depth,
                max_ray_dispatch_invocation_count: pipe.max_ray_dispatch_invocation_count,
                min_scratch_offset_alignment: accel.min_acceleration_structure_scratch_offset_alignment,
                max_geometry_count: accel.max_geometry_count,
                max_instance_count: accel.max_instance_count,
                max_primitive_count: accel.max_primitive_count,
            },
        }
    }
}
