//! Speculum: a real-time hybrid reflection renderer on raw Vulkan.
//!
//! Layout: `vk` is Vulkan plumbing only; `passes` holds one file per pass (each placing
//! its own barriers); `renderer` records a frame top to bottom; `limits` checks a frame
//! against the device before any GPU work; `scene` loads and builds scenes; `cpu_ref`
//! mirrors every GPU kernel on the CPU for tests; `report` is the JSON schema every
//! report follows, `output` writes files all-or-none; `headless` and `bench` drive the
//! renderer for the command line, `demo` drives it in a window. The design:
//! docs/architecture.md.

pub mod aabb;
pub mod bench;
pub mod cpu_ref;
pub mod demo;
pub mod error;
pub mod gpu_types;
pub mod headless;
pub mod limits;
pub mod metrics;
pub mod output;
pub mod passes;
pub mod reflection_maps;
pub mod renderer;
pub mod report;
pub mod scene;
pub mod settings;
pub mod shadow_maps;
pub mod sim;
pub mod steady;
pub mod tracers;
pub mod tune;
pub mod vk;

/// Constants shared with GLSL (also compiled into build.rs).
pub mod shader_defines {
    include!("shader_defines.rs");
}

/// Compiled SPIR-V of every shader under `glsl/`, as bytes.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

pub use error::{Error, Result};
pub use renderer::Renderer;
pub use settings::Settings;
