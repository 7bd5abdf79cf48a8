//! The physical devices: what each is, whether it can run Speculum (`check_device`:
//! Vulkan 1.3, synchronization2, dynamic rendering, push descriptors, the subgroup
//! operations), and which one a run picks (`select`).

use crate::error::{Error, Result, VkContext};
use crate::shader_defines::{REFIT_TOP_WG, SORT_BINS, SORT_WG_GPU};
use ash::vk;
use std::ffi::CStr;

/// One physical device as `speculum devices` shows it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: u32,
    /// The driver's name and version text (`VkPhysicalDeviceDriverProperties`), e.g.
    /// "llvmpipe, Mesa 25.0.7 (LLVM 15.0.6)".
    pub driver: String,
    /// `Err(reason)` when Speculum cannot run on it.
    pub usable: std::result::Result<(), String>,
    /// What it lacks for the vendor tracer (`tracer = khr`; `vk::rt::missing`), if
    /// anything.
    pub ray_tracing_missing: Option<String>,
}

impl DeviceInfo {
    /// "discrete GPU", "CPU", ... for listings.
    pub fn kind_name(&self) -> &'static str {
        kind_name(self.kind)
    }

    /// Preference order when no device is named: lower is better.
    fn rank(&self) -> u32 {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        }
    }
}

/// "discrete GPU", "CPU", ... for a device type.
pub fn kind_name(kind: vk::PhysicalDeviceType) -> &'static str {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

/// Why a physical device cannot run Speculum, if it cannot.
pub(super) fn check_device(instance: &ash::Instance, pd: vk::PhysicalDevice) -> std::result::Result<u32, String> {
    let props = unsafe { instance.get_physical_device_properties(pd) };
    if props.api_version < vk::API_VERSION_1_3 {
        return Err(format!(
            "Vulkan {}.{} < 1.3",
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version)
        ));
    }
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.map_err(|e| e.to_string())?;
    if !exts.iter().any(|e| {
        e.extension_name_as_c_str()
            .is_ok_and(|n| n == ash::khr::push_descriptor::NAME)
    }) {
        return Err("no VK_KHR_push_descriptor".into());
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    if f13.synchronization2 == 0 || f13.dynamic_rendering == 0 {
        return Err("no synchronization2 or dynamic rendering".into());
    }
    // The list kernels aggregate their atomics per subgroup (ballot, elect, broadcast,
    // subgroupOr), whatever the subgroup's size.
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    let ops = vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::BALLOT | vk::SubgroupFeatureFlags::ARITHMETIC;
    if !subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
        || !subgroup.supported_operations.contains(ops)
    {
        return Err("no basic, ballot and arithmetic subgroup operations in compute shaders".into());
    }
    let depth = unsafe { instance.get_physical_device_format_properties(pd, DEPTH_FORMAT) };
    if let Some(short) = limits_shortfall(&props.limits, depth.optimal_tiling_features) {
        return Err(short);
    }
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    families
        .iter()
        .position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
                && f.timestamp_valid_bits > 0
        })
        .map(|i| i as u32)
        .ok_or_else(|| "no graphics+compute queue with timestamps".to_string())
}

pub(super) fn describe(instance: &ash::Instance) -> Result<Vec<(vk::PhysicalDevice, DeviceInfo)>> {
    let pds = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    Ok(pds
        .into_iter()
        .enumerate()
        .map(|(index, pd)| {
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = props
                .device_name_as_c_str()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let usable = check_device(instance, pd).map(|_| ());
            let mut driver = vk::PhysicalDeviceDriverProperties::default();
            let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
            unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
            let text =
                |c: std::result::Result<&CStr, _>| c.map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
            let info = DeviceInfo {
                index,
                name,
                kind: props.device_type,
                api_version: props.api_version,
                driver: format!(
                    "{}, {}",
                    text(driver.driver_name_as_c_str()),
                    text(driver.driver_info_as_c_str())
                ),
                usable,
                ray_tracing_missing: super::rt::missing(instance, pd),
            };
            (pd, info)
        })
        .collect())
}

/// Picks the device `wanted` names, or the best usable one.
pub(super) fn select(list: &[(vk::PhysicalDevice, DeviceInfo)], wanted: Option<&str>) -> Result<usize> {
    let names = || {
        list.iter()
            .map(|(_, d)| format!("{}: {}", d.index, d.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen = match wanted {
        Some(w) => {
            let found = match w.trim().parse::<usize>() {
                Ok(i) => list.iter().position(|(_, d)| d.index == i),
                Err(_) => {
                    let w = w.to_lowercase();
                    list.iter().position(|(_, d)| d.name.to_lowercase().contains(&w))
                }
            };
            let i = found.ok_or_else(|| {
                Error::NoDevice(format!(
                    "no Vulkan device matches --device '{w}' (devices: {})",
                    names()
                ))
            })?;
            if let Err(why) = &list[i].1.usable {
                return Err(Error::NoDevice(format!(
                    "device '{}' cannot run Speculum: {why}",
                    list[i].1.name
                )));
            }
            i
        }
        None => list
            .iter()
            .enumerate()
            .filter(|(_, (_, d))| d.usable.is_ok())
            .min_by_key(|(_, (_, d))| d.rank())
            .map(|(i, _)| i)
            .ok_or_else(|| {
                Error::NoDevice(format!(
                    "no usable Vulkan 1.3 device found (devices: {}); install mesa-vulkan-drivers for lavapipe",
                    if list.is_empty() { "none".into() } else { names() }
                ))
            })?,
    };
    Ok(chosen)
}

/// The depth format of the G-buffer and the shadow map: rendered to, then sampled.
/// Vulkan guarantees depth attachments of D16 and of D24 or D32 only, so it is checked.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Shared memory of the sort's scatter with the GPU's workgroup, the most any kernel
/// declares, in 32-bit words (`radix_scatter.comp`): `s_counts[SORT_BINS * SORT_WG]`;
/// `s_base`, `s_first` and `s_digit_total`, `SORT_BINS` each; `s_fused[2 * SORT_WG]`;
/// and its workgroup scan's (`wg_scan.glsl`) `SORT_WG` and `SORT_WG / 16 + 1`. 19,716
/// bytes, above the 16,384 every Vulkan device has (NVIDIA GPUs have 48K).
pub const SHARED_BYTES_NEEDED: u32 =
    (SORT_BINS * SORT_WG_GPU + 3 * SORT_BINS + 2 * SORT_WG_GPU + SORT_WG_GPU + SORT_WG_GPU / 16 + 1) * 4;

/// What a device's limits and depth format lack for Speculum's kernels, as one line
/// naming it (`None` when nothing): workgroups of `REFIT_TOP_WG` invocations along x
/// (the refit's top pass; Vulkan's minimum is 128), `SHARED_BYTES_NEEDED` of shared
/// memory, and `DEPTH_FORMAT` as a depth attachment that is also sampled.
pub fn limits_shortfall(limits: &vk::PhysicalDeviceLimits, depth: vk::FormatFeatureFlags) -> Option<String> {
    if limits.max_compute_work_group_invocations < REFIT_TOP_WG || limits.max_compute_work_group_size[0] < REFIT_TOP_WG
    {
        return Some(format!(
            "compute workgroups of {REFIT_TOP_WG} invocations (the refit's top pass); the device allows {} ({} along x)",
            limits.max_compute_work_group_invocations, limits.max_compute_work_group_size[0]
        ));
    }
    if limits.max_compute_shared_memory_size < SHARED_BYTES_NEEDED {
        return Some(format!(
            "{SHARED_BYTES_NEEDED} bytes of compute shared memory (the sort's scatter); the device has {}",
            limits.max_compute_shared_memory_size
        ));
    }
    let needed = vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT | vk::FormatFeatureFlags::SAMPLED_IMAGE;
    if !depth.contains(needed) {
        return Some(format!("{DEPTH_FORMAT:?} as a sampled depth attachment"));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device at Vulkan's minimum limits lacks the workgroups and the shared memory,
    /// each named in its line; one with a GPU's limits and D32 lacks nothing.
    #[test]
    fn limits_below_the_kernels_needs_are_named() {
        let depth = vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT | vk::FormatFeatureFlags::SAMPLED_IMAGE;
        let gpu = vk::PhysicalDeviceLimits {
            max_compute_work_group_invocations: 1024,
            max_compute_work_group_size: [1024, 1024, 64],
            max_compute_shared_memory_size: 49152,
            ..Default::default()
        };
        assert_eq!(limits_shortfall(&gpu, depth), None);
        let minimum = vk::PhysicalDeviceLimits {
            max_compute_work_group_invocations: 128,
            max_compute_work_group_size: [128, 128, 64],
            max_compute_shared_memory_size: 16384,
            ..Default::default()
        };
        let line = limits_shortfall(&minimum, depth).unwrap();
        assert!(
            line.contains("1024 invocations") && line.contains("allows 128"),
            "{line}"
        );
        let few_bytes = vk::PhysicalDeviceLimits {
            max_compute_shared_memory_size: 16384,
            ..gpu
        };
        let line = limits_shortfall(&few_bytes, depth).unwrap();
        assert!(line.contains("19716 bytes") && line.contains("has 16384"), "{line}");
        let line = limits_shortfall(&gpu, vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT).unwrap();
        assert!(line.contains("D32_SFLOAT"), "{line}");
    }
}
