//! One file per pass. A pass owns its pipeline and its output images and records its
//! own commands; it knows nothing of the other passes. Layout transitions and the
//! barriers between passes belong to `renderer.rs`.

pub mod compose;
pub mod gbuffer;
pub mod lbvh;
pub mod light_direct;
pub mod reflect_merge;
pub mod rt_reflect;
pub mod rt_trace;
pub mod shadow_map;
pub mod ssr_compact;
pub mod ssr_trace;

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
    unsafe {
        device.cmd_set_viewport(cmd, 0, &[viewport]);
        device.cmd_set_scissor(cmd, 0, &[scissor]);
    }
}

/// The scene's GPU geometry, as raster passes draw it.
pub struct SceneGeometry<'a> {
    pub vertices: &'a crate::vk::Buffer,
    pub indices: &'a crate::vk::Buffer,
    pub index_count: u32,
}
