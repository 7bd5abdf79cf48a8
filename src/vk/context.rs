//! Instance, device selection, the queue, the memory allocator and the validation
//! messenger. Everything else in `vk/` takes a `&Context`.
//!
//! Contract: one graphics+compute queue; Vulkan 1.3 with synchronization2 and dynamic
//! rendering, plus `VK_KHR_push_descriptor`. Validation (with synchronization
//! validation) is switched on by `ContextDesc::validation`; every warning or error the
//! layer reports is printed and counted in `Context::validation_messages`.

use super::device::{check_device, describe, select, DeviceInfo};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a context.
#[derive(Clone, Debug, Default)]
pub struct ContextDesc {
    /// Enable `VK_LAYER_KHRONOS_validation` with synchronization validation.
    pub validation: bool,
    /// Pick a device by index (as `speculum devices` lists) or by a case-insensitive
    /// substring of its name; `None` prefers a discrete GPU and falls back to a CPU one.
    pub device: Option<String>,
    /// A window to present to (the demo): the instance gets the surface extensions
    /// its platform needs, the context creates its surface (`Context::surface`), the
    /// device gets `VK_KHR_swapchain`, and a device whose queue cannot present to it
    /// is refused. The window must outlive the context.
    pub window: Option<WindowHandles>,
    /// Specialize the kernels as for a device of this type (`Context::kernels_for`)
    /// instead of the device's own: the GPU's sort tiles run on lavapipe in the tests,
    /// a path otherwise only a GPU takes. `None`: the device's type.
    pub kernels_for: Option<vk::PhysicalDeviceType>,
    /// Make the LBVH fit climb in lockstep (the variant lavapipe before Mesa 25 needs)
    /// or freely, whatever the driver (`Context::lockstep_fit`). `None`: as the driver needs.
    pub lockstep_fit: Option<bool>,
    /// The sort's scatter writes a GPU tile's pairs out in order
    /// (`sort::SortTile::local`), a candidate `bench lbvh --sort-scatter local` measures.
    pub local_sort_scatter: bool,
    /// Every sort of more than one tile runs its scan (`sort::SortTile::fused` 0), as
    /// before the scatter found small sorts' offsets itself: what `bench lbvh
    /// --sort-scan` compares the fused passes against.
    pub sort_scan: bool,
    /// Leave the vendor tracer's extensions off, as on a device without them
    /// (`Context::ray_tracing` is `None`, `ray_tracing_missing` says so): how the tests
    /// reach `tracer = khr`'s error on a device that has them.
    pub no_ray_tracing: bool,
}

/// A window's raw display and window handles (`raw-window-handle`), for `ContextDesc`.
#[derive(Clone, Copy, Debug)]
pub struct WindowHandles {
    pub display: raw_window_handle::RawDisplayHandle,
    pub window: raw_window_handle::RawWindowHandle,
}

/// The window surface of a context made for one (`ContextDesc::window`).
pub struct Surface {
    pub loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
    pub swapchain: ash::khr::swapchain::Device,
}

/// Counts validation messages; lives in a `Box` whose address the messenger holds.
#[derive(Default)]
struct MessageCounter {
    count: AtomicU32,
}

/// The Vulkan context every pass and resource is created from. Shared as `Arc<Context>`:
/// every resource holds one, so the device outlives everything made from it.
pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    /// Device name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub device_name: String,
    /// The device's type (discrete GPU, CPU, ...).
    pub device_type: vk::PhysicalDeviceType,
    /// The device type the kernels are specialized for (the sort's tile shape):
    /// `device_type` unless `ContextDesc::kernels_for` chose another.
    pub kernels_for: vk::PhysicalDeviceType,
    /// `ContextDesc::lockstep_fit`: the fit's climb chosen by the caller, if it chose.
    pub lockstep_fit: Option<bool>,
    /// `ContextDesc::local_sort_scatter`.
    pub local_sort_scatter: bool,
    /// `ContextDesc::sort_scan`.
    pub sort_scan: bool,
    /// Vulkan version the device supports (`vk::make_api_version` encoding).
    pub api_version: u32,
    /// The driver's raw version number (its encoding is the vendor's).
    pub driver_version: u32,
    /// `VkPhysicalDeviceDriverProperties`: the driver's name and version text, e.g.
    /// "llvmpipe" and "Mesa 22.3.6 (LLVM 15.0.6)".
    pub driver_name: String,
    pub driver_info: String,
    pub limits: vk::PhysicalDeviceLimits,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f64,
    /// Bits of a timestamp that are valid on our queue (results wrap at 2^bits).
    pub timestamp_valid_bits: u32,
    pub push_descriptor: ash::khr::push_descriptor::Device,
    /// The vendor tracer's extensions and limits (`vk::rt`), when the device has them
    /// and `ContextDesc::no_ray_tracing` did not hide them.
    pub ray_tracing: Option<super::rt::RayTracing>,
    /// What the device lacks for the vendor tracer, in one line, when `ray_tracing` is
    /// `None`.
    pub ray_tracing_missing: Option<String>,
    /// Present when the loader offers VK_EXT_debug_utils: object names and labels.
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    debug_instance: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    counter: Box<MessageCounter>,
    validation: bool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    command_pool: vk::CommandPool,
    /// The window's surface when the context was made for one.
    pub surface: Option<Surface>,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; `user` is the boxed counter that
    // outlives the messenger (destroyed first in Drop).
    let message = unsafe {
        let data = &*data;
        if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(data.p_message).to_string_lossy().into_owned()
        }
    };
    let counted = types
        .intersects(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE);
    if counted {
        let counter = unsafe { &*(user as *const MessageCounter) };
        counter.count.fetch_add(1, Ordering::SeqCst);
    }
    eprintln!("[vulkan {severity:?} {types:?}] {message}");
    vk::FALSE
}

fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading the system Vulkan loader; no other code is running inside it.
    unsafe { ash::Entry::load() }.map_err(|e| Error::Loader(e.to_string()))
}

fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    window: Option<&WindowHandles>,
) -> Result<(ash::Instance, bool)> {
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
    let has_layer = layers
        .iter()
        .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
    if validation && !has_layer {
        return Err(Error::NoValidationLayer);
    }
    let extensions =
        unsafe { entry.enumerate_instance_extension_properties(None) }.vk("vkEnumerateInstanceExtensionProperties")?;
    let has_debug_utils = extensions.iter().any(|e| {
        e.extension_name_as_c_str()
            .is_ok_and(|n| n == ash::ext::debug_utils::NAME)
    });

    let app = vk::ApplicationInfo::default()
        .application_name(c"speculum")
        .engine_name(c"speculum")
        .api_version(vk::API_VERSION_1_3);
    let layer_names = if validation {
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        vec![]
    };
    let mut ext_names = if has_debug_utils {
        vec![ash::ext::debug_utils::NAME.as_ptr()]
    } else {
        vec![]
    };
    if let Some(w) = window {
        let needed = ash_window::enumerate_required_extensions(w.display)
            .map_err(|e| Error::NoDevice(format!("this window system has no Vulkan surface support: {e}")))?;
        ext_names.extend_from_slice(needed);
    }
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names);
    if validation {
        info = info.push_next(&mut features);
    }
    let instance = unsafe { entry.create_instance(&info, None) }.vk("vkCreateInstance")?;
    Ok((instance, has_debug_utils))
}

/// Lists the physical devices, usable or not, in the order `--device INDEX` counts them.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let entry = load_entry()?;
    let (instance, _) = create_instance(&entry, false, None)?;
    let list = describe(&instance);
    unsafe { instance.destroy_instance(None) };
    Ok(list?.into_iter().map(|(_, info)| info).collect())
}

/// Something a half-made context created, undone (`undo`) when the guard drops, unless
/// `keep` took it: a failed step then cleans up the steps before it, in reverse.
struct Undo<T, F: FnOnce(T)> {
    value: Option<T>,
    undo: Option<F>,
}

impl<T, F: FnOnce(T)> Undo<T, F> {
    fn new(value: T, undo: F) -> Self {
        Self {
            value: Some(value),
            undo: Some(undo),
        }
    }

    fn get(&self) -> &T {
        self.value.as_ref().expect("kept only once")
    }

    /// The value, no longer undone.
    fn keep(mut self) -> T {
        self.value.take().expect("kept only once")
    }
}

impl<T, F: FnOnce(T)> Drop for Undo<T, F> {
    fn drop(&mut self) {
        if let (Some(v), Some(undo)) = (self.value.take(), self.undo.take()) {
            undo(v);
        }
    }
}

type Messenger = (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT);

/// The validation layer's messenger: warnings and errors counted in `counter`.
fn create_messenger(entry: &ash::Entry, instance: &ash::Instance, counter: &MessageCounter) -> Result<Messenger> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(counter as *const MessageCounter as *mut c_void);
    let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }.vk("vkCreateDebugUtilsMessengerEXT")?;
    Ok((loader, messenger))
}

/// The device `desc` asks for (or the best usable one), and its graphics+compute queue
/// family; with a window, one that can present to it.
fn pick_device(
    instance: &ash::Instance,
    surface: Option<&(ash::khr::surface::Instance, vk::SurfaceKHR)>,
    desc: &ContextDesc,
) -> Result<(vk::PhysicalDevice, DeviceInfo, u32)> {
    let list = describe(instance)?;
    let chosen = select(&list, desc.device.as_deref())?;
    let (physical_device, info) = list[chosen].clone();
    let queue_family = check_device(instance, physical_device).expect("checked by select");
    if let Some((loader, raw)) = surface {
        let presents =
            unsafe { loader.get_physical_device_surface_support(physical_device, queue_family, *raw) }.unwrap_or(false);
        let has_swapchain = unsafe { instance.enumerate_device_extension_properties(physical_device) }
            .unwrap_or_default()
            .iter()
            .any(|e| {
                e.extension_name_as_c_str()
                    .is_ok_and(|n| n == ash::khr::swapchain::NAME)
            });
        if !presents || !has_swapchain {
            return Err(Error::NoDevice(format!(
                "device '{}' cannot present to this window (its graphics+compute queue has no present support{})",
                info.name,
                if has_swapchain { "" } else { ", no VK_KHR_swapchain" }
            )));
        }
    }
    Ok((physical_device, info, queue_family))
}

/// The logical device: one queue of `queue_family`, push descriptors, synchronization2
/// and dynamic rendering (and the swapchain extension when presenting; the vendor
/// tracer's extensions and features with `ray_tracing`).
fn create_device(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
    queue_family: u32,
    presents: bool,
    ray_tracing: bool,
) -> Result<ash::Device> {
    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let mut dev_exts = vec![ash::khr::push_descriptor::NAME.as_ptr()];
    if presents {
        dev_exts.push(ash::khr::swapchain::NAME.as_ptr());
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .synchronization2(true)
        .dynamic_rendering(true);
    let (mut accel, mut pipe, mut f12) = super::rt::enabled_features();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
    if ray_tracing {
        dev_exts.extend(super::rt::EXTENSIONS.iter().map(|n| n.as_ptr()));
        f2 = f2.push_next(&mut accel).push_next(&mut pipe).push_next(&mut f12);
    }
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&dev_exts)
        .push_next(&mut f2);
    unsafe { instance.create_device(physical_device, &dinfo, None) }.vk("vkCreateDevice")
}

impl Context {
    /// Creates the instance, picks a device and creates the queue and allocator.
    pub fn new(desc: &ContextDesc) -> Result<std::sync::Arc<Self>> {
        let entry = load_entry()?;
        let (instance, has_debug_utils) = create_instance(&entry, desc.validation, desc.window.as_ref())?;
        // From here on, a failure must destroy the instance: build the rest in a helper.
        // `entry` (the loaded library) must outlive the instance destroyed below.
        match Self::with_instance(entry.clone(), instance.clone(), has_debug_utils, desc) {
            Ok(ctx) => Ok(std::sync::Arc::new(ctx)),
            Err(e) => {
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    // Long: the creation steps in order, each guarded, then the context's 25 fields.
    fn with_instance(
        entry: ash::Entry,
        instance: ash::Instance,
        has_debug_utils: bool,
        desc: &ContextDesc,
    ) -> Result<Self> {
        let counter = Box::<MessageCounter>::default();
        // Each step's failure undoes the steps before it (the guards drop in reverse).
        let messenger = Undo::new(
            has_debug_utils
                .then(|| create_messenger(&entry, &instance, &counter))
                .transpose()?,
            |m| {
                if let Some((loader, m)) = m {
                    unsafe { loader.destroy_debug_utils_messenger(m, None) };
                }
            },
        );
        let surface = match &desc.window {
            Some(w) => {
                let loader = ash::khr::surface::Instance::new(&entry, &instance);
                let raw = unsafe { ash_window::create_surface(&entry, &instance, w.display, w.window, None) }
                    .vk("vkCreate*SurfaceKHR")?;
                Some((loader, raw))
            }
            None => None,
        };
        let surface = Undo::new(surface, |s| {
            if let Some((loader, raw)) = s {
                unsafe { loader.destroy_surface(raw, None) };
            }
        });
        let (physical_device, info, queue_family) = pick_device(&instance, surface.get().as_ref(), desc)?;
        let ray_tracing_missing = if desc.no_ray_tracing {
            Some("its ray-tracing extensions, hidden by the caller (ContextDesc::no_ray_tracing)".to_string())
        } else {
            super::rt::missing(&instance, physical_device)
        };
        let rt = ray_tracing_missing.is_none();
        let device = Undo::new(
            create_device(&instance, physical_device, queue_family, surface.get().is_some(), rt)?,
            |d| unsafe { d.destroy_device(None) },
        );
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.get().clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: rt,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| Error::Allocation {
            name: "allocator".into(),
            source,
        })?;
        let allocator = Undo::new(allocator, drop);
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool = unsafe { device.get().create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;

        // Everything is made: the context owns it from here (its Drop destroys it).
        let (allocator, device) = (allocator.keep(), device.keep());
        let (surface, debug_instance) = (surface.keep(), messenger.keep());
        let props = unsafe { instance.get_physical_device_properties(physical_device) };
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        unsafe { instance.get_physical_device_properties2(physical_device, &mut props2) };
        let text = |c: Result<&CStr, _>| c.map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
        let (driver_name, driver_info) = (text(driver.driver_name_as_c_str()), text(driver.driver_info_as_c_str()));
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        Ok(Self {
            queue: unsafe { device.get_device_queue(queue_family, 0) },
            push_descriptor: ash::khr::push_descriptor::Device::new(&instance, &device),
            ray_tracing: rt.then(|| super::rt::RayTracing::new(&instance, physical_device, &device)),
            ray_tracing_missing,
            debug_utils: has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device)),
            surface: surface.map(|(loader, raw)| Surface {
                loader,
                raw,
                swapchain: ash::khr::swapchain::Device::new(&instance, &device),
            }),
            entry,
            physical_device,
            queue_family,
            device_name: info.name,
            device_type: props.device_type,
            kernels_for: desc.kernels_for.unwrap_or(props.device_type),
            lockstep_fit: desc.lockstep_fit,
            local_sort_scatter: desc.local_sort_scatter,
            sort_scan: desc.sort_scan,
            api_version: props.api_version,
            driver_version: props.driver_version,
            driver_name,
            driver_info,
            limits: props.limits,
            timestamp_period_ns: props.limits.timestamp_period as f64,
            timestamp_valid_bits: families[queue_family as usize].timestamp_valid_bits,
            debug_instance,
            counter,
            validation: desc.validation,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            command_pool,
            device,
            instance,
        })
    }

    /// Validation warnings and errors reported so far (0 when validation is off).
    pub fn validation_messages(&self) -> u32 {
        self.counter.count.load(Ordering::SeqCst)
    }

    /// Whether the validation layer is on.
    pub fn validation_enabled(&self) -> bool {
        self.validation
    }

    /// Fails with `Error::DeviceLimit` when `size` (in `unit`) exceeds the device limit
    /// `limit_name` = `limit`.
    pub fn check_limit(
        &self,
        what: impl FnOnce() -> String,
        size: u64,
        unit: &'static str,
        limit_name: &'static str,
        limit: u64,
    ) -> Result<()> {
        if size <= limit {
            return Ok(());
        }
        Err(Error::DeviceLimit {
            what: what(),
            size,
            unit,
            limit,
            limit_name,
            device: self.device_name.clone(),
        })
    }

    /// The memory allocator, shared by buffers and images.
    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Gives a Vulkan object a debug name (shown by validation messages and tools).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.debug_utils {
            let Ok(cname) = std::ffi::CString::new(name) else {
                return;
            };
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&cname);
            // Naming is a debugging aid: a failure here must not fail rendering.
            let _ = unsafe { du.set_debug_utils_object_name(&info) };
        }
    }

    /// Allocates a primary command buffer from the context's pool.
    pub fn allocate_command_buffer(&self) -> Result<vk::CommandBuffer> {
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        Ok(unsafe { self.device.allocate_command_buffers(&info) }.vk("vkAllocateCommandBuffers")?[0])
    }

    /// Frees a command buffer allocated by `allocate_command_buffer`.
    pub fn free_command_buffer(&self, cmd: vk::CommandBuffer) {
        unsafe { self.device.free_command_buffers(self.command_pool, &[cmd]) };
    }

    /// Blocks until the device is idle (before resources a frame may still use change).
    pub fn wait_idle(&self) -> Result<()> {
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }

    /// Resets `cmd` (from a pool that allows it) and begins it for one submission.
    pub fn begin(&self, cmd: vk::CommandBuffer) -> Result<()> {
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe {
            self.device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            self.device.begin_command_buffer(cmd, &begin).vk("vkBeginCommandBuffer")
        }
    }

    /// Resets `cmd` and records `record` into it, begun for one submission and ended.
    pub fn rerecord(&self, cmd: vk::CommandBuffer, record: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
        self.begin(cmd)?;
        record(cmd);
        unsafe { self.device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")
    }

    /// Submits `cmd` (already ended) and blocks until the GPU has finished it.
    pub fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<()> {
        let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos)];
        let result = unsafe { self.device.queue_submit2(self.queue, &submit, fence) }
            .vk("vkQueueSubmit2")
            .and_then(|_| unsafe { self.device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences"));
        unsafe { self.device.destroy_fence(fence, None) };
        result
    }

    /// Records `record` into a fresh command buffer, submits it and waits: for uploads,
    /// readbacks and tests. Not for frames (those reuse their command buffers).
    pub fn one_shot(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
        let cmd = self.allocate_command_buffer()?;
        let result = self.rerecord(cmd, record).and_then(|_| self.submit_and_wait(cmd));
        self.free_command_buffer(cmd);
        result
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.command_pool, None);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some(s) = &self.surface {
                s.loader.destroy_surface(s.raw, None);
            }
            if let Some((loader, messenger)) = &self.debug_instance {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
