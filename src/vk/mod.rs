//! Vulkan plumbing only: no knowledge of passes or scenes.

pub mod barrier;
pub mod buffer;
pub mod context;
pub mod image;
pub mod pipeline;
pub mod spirv;
pub mod timing;

pub use buffer::Buffer;
pub use context::{list_devices, Context, ContextDesc, DeviceInfo, Surface, WindowHandles};
pub use image::{Image, Sampler};
pub use pipeline::{GraphicsDesc, Groups, Pipeline, Resource, Shader};
pub use timing::{GpuTimer, TimerReadout, TimingCheck, Timings, Wall};
