//! Thin synchronization2 helpers (after zeux/niagara's `stageBarrier`/`imageBarrier`).
//! Callers put a one-line comment naming the hazard next to each use.
//!
//! `global` (one memory barrier) and `transition` (layout changes of whole images, the
//! aspect taken from each image) are what passes use; `image`/`memory`/`record` build
//! barriers one by one for `vk/` itself.

use ash::vk;

/// (stage, access) of one side of a barrier.
pub type Scope = (vk::PipelineStageFlags2, vk::AccessFlags2);

/// Records one global memory barrier: `src` accesses of every resource finish and are
/// made visible before `dst` accesses start.
pub fn global(device: &ash::Device, cmd: vk::CommandBuffer, src: Scope, dst: Scope) {
    record(device, cmd, &[memory(src, dst)], &[]);
}

/// An image as `transition` sees it: its handle and aspect (`vk::Image`, the module
/// above, implements it;
/// the trait keeps this module below the image module).
pub trait WholeImage {
    fn handle_and_aspect(&self) -> (vk::Image, vk::ImageAspectFlags);
}

/// Records the layout transition `old` → `new` of every image in `images` (all mips and
/// layers of each image's aspect), ordering `src` accesses before `dst` accesses.
pub fn transition<I: WholeImage>(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    images: &[&I],
    (src, dst): (Scope, Scope),
    (old, new): (vk::ImageLayout, vk::ImageLayout),
) {
    let barriers: Vec<_> = images
        .iter()
        .map(|i| {
            let (raw, aspect) = i.handle_and_aspect();
            image(raw, aspect, src, dst, old, new)
        })
        .collect();
    record(device, cmd, &[], &barriers);
}

/// An image barrier over the whole image (all mips and layers of `aspect`).
pub fn image(
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    (src_stage, src_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    (dst_stage, dst_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    old_layout: vk::ImageLayout,
    new_layout: vk::ImageLayout,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)
        .old_layout(old_layout)
        .new_layout(new_layout)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(aspect)
                .level_count(vk::REMAINING_MIP_LEVELS)
                .layer_count(vk::REMAINING_ARRAY_LAYERS),
        )
}

/// A global memory barrier (covers every buffer).
pub fn memory(
    (src_stage, src_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    (dst_stage, dst_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
) -> vk::MemoryBarrier2<'static> {
    vk::MemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)
}

/// Records one `vkCmdPipelineBarrier2` with the given barriers.
pub fn record(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    memory: &[vk::MemoryBarrier2<'_>],
    images: &[vk::ImageMemoryBarrier2<'_>],
) {
    let info = vk::DependencyInfo::default()
        .memory_barriers(memory)
        .image_memory_barriers(images);
    // SAFETY: `cmd` is in the recording state; the barriers reference live objects.
    unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
}

/// Common (stage, access) pairs, named for what they are.
pub mod access {
    use ash::vk::{AccessFlags2 as A, PipelineStageFlags2 as S};

    pub const NONE: (S, A) = (S::NONE, A::NONE);
    pub const TRANSFER_WRITE: (S, A) = (S::ALL_TRANSFER, A::TRANSFER_WRITE);
    pub const TRANSFER_READ: (S, A) = (S::ALL_TRANSFER, A::TRANSFER_READ);
    /// A copy: it reads its source and writes its destination.
    pub const TRANSFER_WRITE_READ: (S, A) = (
        S::ALL_TRANSFER,
        A::from_raw(A::TRANSFER_WRITE.as_raw() | A::TRANSFER_READ.as_raw()),
    );
    pub const HOST_READ: (S, A) = (S::HOST, A::HOST_READ);
    pub const COMPUTE_READ: (S, A) = (S::COMPUTE_SHADER, A::SHADER_READ);
    pub const COMPUTE_WRITE: (S, A) = (S::COMPUTE_SHADER, A::SHADER_WRITE);
    /// Compute reads and writes of the same data: atomics, read-modify-write images.
    pub const COMPUTE_READ_WRITE: (S, A) = (
        S::COMPUTE_SHADER,
        A::from_raw(A::SHADER_READ.as_raw() | A::SHADER_WRITE.as_raw()),
    );
    /// What reads a list a compute pass wrote and dispatches over it: the shaders, and
    /// `vkCmdDispatchIndirect` reading its arguments.
    pub const COMPUTE_READ_AND_INDIRECT: (S, A) = (
        S::from_raw(S::COMPUTE_SHADER.as_raw() | S::DRAW_INDIRECT.as_raw()),
        A::from_raw(A::SHADER_READ.as_raw() | A::INDIRECT_COMMAND_READ.as_raw()),
    );
    /// Every compute access and indirect-argument read (the source of a WAR or WAW
    /// barrier before data such passes used is rewritten).
    pub const COMPUTE_ANY: (S, A) = (
        S::from_raw(S::COMPUTE_SHADER.as_raw() | S::DRAW_INDIRECT.as_raw()),
        A::from_raw(A::SHADER_READ.as_raw() | A::SHADER_WRITE.as_raw() | A::INDIRECT_COMMAND_READ.as_raw()),
    );
    pub const ANY_SHADER_READ: (S, A) = (
        S::from_raw(S::VERTEX_SHADER.as_raw() | S::FRAGMENT_SHADER.as_raw() | S::COMPUTE_SHADER.as_raw()),
        A::from_raw(A::SHADER_READ.as_raw() | A::UNIFORM_READ.as_raw()),
    );
    pub const ALL_READ_WRITE: (S, A) = (
        S::ALL_COMMANDS,
        A::from_raw(A::MEMORY_READ.as_raw() | A::MEMORY_WRITE.as_raw()),
    );
    pub const COLOR_WRITE: (S, A) = (
        S::COLOR_ATTACHMENT_OUTPUT,
        A::from_raw(A::COLOR_ATTACHMENT_WRITE.as_raw() | A::COLOR_ATTACHMENT_READ.as_raw()),
    );
    /// An acceleration-structure build or copy: it writes its destination and reads
    /// (and writes) its source and scratch.
    pub const AS_BUILD: (S, A) = (
        S::ACCELERATION_STRUCTURE_BUILD_KHR,
        A::from_raw(A::ACCELERATION_STRUCTURE_READ_KHR.as_raw() | A::ACCELERATION_STRUCTURE_WRITE_KHR.as_raw()),
    );
    /// A build reading its input buffers (vertices, indices, instances).
    pub const AS_BUILD_INPUT: (S, A) = (S::ACCELERATION_STRUCTURE_BUILD_KHR, A::SHADER_READ);
    /// Ray-tracing shaders reading buffers, images and acceleration structures, and
    /// `vkCmdTraceRaysIndirectKHR` reading its arguments.
    pub const RT_READ_AND_INDIRECT: (S, A) = (
        S::from_raw(S::RAY_TRACING_SHADER_KHR.as_raw() | S::DRAW_INDIRECT.as_raw()),
        A::from_raw(
            A::SHADER_READ.as_raw() | A::ACCELERATION_STRUCTURE_READ_KHR.as_raw() | A::INDIRECT_COMMAND_READ.as_raw(),
        ),
    );
    /// Ray-tracing shaders writing their outputs.
    pub const RT_WRITE: (S, A) = (S::RAY_TRACING_SHADER_KHR, A::SHADER_WRITE);
    /// Every access of a ray-tracing pass: its shaders' reads (acceleration structures
    /// included) and writes, and its indirect arguments.
    pub const RT_ANY: (S, A) = (
        S::from_raw(S::RAY_TRACING_SHADER_KHR.as_raw() | S::DRAW_INDIRECT.as_raw()),
        A::from_raw(
            A::SHADER_READ.as_raw()
                | A::SHADER_WRITE.as_raw()
                | A::ACCELERATION_STRUCTURE_READ_KHR.as_raw()
                | A::INDIRECT_COMMAND_READ.as_raw(),
        ),
    );
    pub const DEPTH_WRITE: (S, A) = (
        S::from_raw(S::EARLY_FRAGMENT_TESTS.as_raw() | S::LATE_FRAGMENT_TESTS.as_raw()),
        A::from_raw(A::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw() | A::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()),
    );
}
