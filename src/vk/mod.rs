//! Vulkan plumbing only: no knowledge of passes or scenes.
//!
//! Every Vulkan call is `unsafe` (ash's FFI), and this layer is where they live: each
//! wrapper owns its handles and frees them once, so its blocks are not each annotated
//! (`undocumented_unsafe_blocks`, denied everywhere else, is allowed here).
#![allow(clippy::undocumented_unsafe_blocks)]

pub mod accel;
pub mod barrier;
pub mod buffer;
pub mod context;
pub mod device;
pub mod frame_sync;
pub mod image;
pub mod pipeline;
pub mod rt;
pub mod rt_pipeline;
pub mod spirv;
pub mod swapchain;
pub mod timing;

pub use buffer::{Buffer, Staged, TexelView};
pub use context::{list_devices, Context, ContextDesc, Surface, WindowHandles};
pub use device::DeviceInfo;
pub use frame_sync::{Acquired, FrameSync};
pub use image::{Image, Sampler};
pub use pipeline::{Bind, GraphicsDesc, Groups, Pipeline, Resource, Shader};
pub use swapchain::Swapchain;
pub use timing::{remeasure, remeasure_readout, GpuTimer, TimerReadout, TimingCheck, Timings, Wall};
