//! One file per pass. A pass owns its pipeline and its output images and records its
//! own commands; it knows nothing of the other passes beyond the names of its outputs'
//! readers: what passes hand each other (the G-buffer, the compacted pixel list, the
//! surfaces and geometry) is defined here, not in a pass; what a trace walks, and the
//! kernels that walk it, are `tracers`'.
//!
//! One shape: `NAME` (its timer scope, the frame table's name for it), `new`,
//! `record(cmd, inputs, params)` (resources first, an `…Inputs` struct when there are
//! more than four; then the settings it reads), `resize` for screen-sized passes, and
//! its result in `pub out`. Each pass's module doc names its CPU reference.
//!
//! Barrier rule: a pass's `record` begins with the barriers that make its outputs
//! writable (the previous frame's readers done; attachments moved to their attachment
//! layout) and ends with the barrier that makes them visible to the readers its
//! documentation names. Storage images stay in `GENERAL` from creation
//! (`Image::storage`), so compute passes need memory barriers only.
//! `renderer/frame.rs` records only what spans passes (the uniform upload) and the
//! timer scopes, as `renderer/plan.rs` decides.

pub mod compose;
pub mod gbuffer;
pub mod gbuffer_trace;
pub mod light_direct;
pub mod reflect_denoise;
pub mod reflect_merge;
pub mod rt_reflect;
pub mod rt_trace;
pub mod shadow_map;
pub mod shadow_trace;
pub mod sim_cloth;
pub mod sim_skin;
pub mod sim_transform;
pub mod ssr_compact;
pub mod ssr_hiz;
pub mod ssr_trace;

use crate::vk::{Buffer, Image};
use ash::vk;

/// Sets a full-target viewport and scissor (both are dynamic state).
pub(crate) fn set_viewport(device: &ash::Device, cmd: vk::CommandBuffer, extent: vk::Extent2D) {
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let scissor = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    };
    // SAFETY: `cmd` is recording inside a render pass of a pipeline with dynamic
    // viewport and scissor.
    unsafe {
        device.cmd_set_viewport(cmd, 0, &[viewport]);
        device.cmd_set_scissor(cmd, 0, &[scissor]);
    }
}

/// `list_groups` of `glsl/shared/pixel_list.glsl`: the (x, y) workgroup counts of a
/// list kernel's indirect dispatch over `groups` workgroups.
pub fn list_groups(groups: u32) -> [u32; 2] {
    use crate::shader_defines::LIST_GROUPS_X;
    [groups.min(LIST_GROUPS_X), groups.div_ceil(LIST_GROUPS_X).max(1)]
}

/// How the scene's surfaces look, for the passes that shade them (the G-buffer and the
/// reflection tracer): materials, per-vertex texture coordinates (static and dynamic
/// geometry; the static ones again while there is no dynamic geometry), and the
/// texture array with its sampler (`scene::texture`).
#[derive(Clone, Copy)]
pub struct Surfaces<'a> {
    pub materials: &'a crate::vk::Buffer,
    pub uvs: [&'a crate::vk::Buffer; 2],
    pub textures: &'a crate::vk::Image,
    pub sampler: &'a crate::vk::Sampler,
}

/// Geometry as the raster passes draw it (the static scene, or the dynamic geometry
/// `sim.transform` moved): vertices in world space, their texture coordinates, indices.
pub struct SceneGeometry<'a> {
    pub vertices: &'a crate::vk::Buffer,
    /// The same vertices as the frame before saw them (`vertices` itself where they have
    /// not moved since): the G-buffer's motion.
    pub previous: &'a crate::vk::Buffer,
    pub uvs: &'a crate::vk::Buffer,
    pub indices: &'a crate::vk::Buffer,
    pub index_count: u32,
}

/// The G-buffer images; `SHADER_READ_ONLY_OPTIMAL` between frames.
pub struct GBuffer {
    pub depth: Image,
    pub normal: Image,
    pub albedo: Image,
    pub material: Image,
    /// xyz: where the surface point was the frame before, minus where it is (world
    /// space; 0 on geometry that did not move), for reprojection; w: metallic per texel.
    pub motion: Image,
}

/// `ssr.hiz`'s min-depth pyramid: its buffer (floats, level after level) and the levels
/// in it.
pub struct HiZ {
    pub buffer: Buffer,
    pub levels: Vec<Level>,
}

/// One pyramid level: where it starts in the buffer (in floats) and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    pub offset: u32,
    pub size: [u32; 2],
}

/// The compacted list and its size.
pub struct CompactOutputs {
    /// One `u32` per listed pixel: `x | y << 16`.
    pub pixels: Buffer,
    /// `[groups_x, groups_y, 1, count]`: a `VkDispatchIndirectCommand` for `RT_LIST_WG`-wide
    /// workgroups (`list_groups`), then the number of listed pixels; at byte
    /// `tracers::TRACE_RAYS_ARGS`, `[count, 1, 1, 0]`: a `VkTraceRaysIndirectCommandKHR`.
    pub indirect: Buffer,
    tile_counts: Buffer,
    extent: vk::Extent2D,
}
