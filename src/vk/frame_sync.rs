//! Frames in flight on a swapchain (after niagara's swapchain module): per slot a
//! command buffer, a fence (the slot's last frame finished) and an "image acquired"
//! semaphore; `acquire` → `begin` → (the caller records) → `submit_present`. The
//! "rendered" semaphores are the swapchain's, one per image.

use super::context::Context;
use super::swapchain::Swapchain;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use std::sync::Arc;

struct Slot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    acquired: vk::Semaphore,
}

pub struct FrameSync {
    ctx: Arc<Context>,
    pool: vk::CommandPool,
    slots: Vec<Slot>,
}

/// The result of `FrameSync::acquire`.
pub enum Acquired {
    /// Image `index` is the slot's; `suboptimal`: present it, then recreate.
    Image { index: usize, suboptimal: bool },
    /// The swapchain no longer fits the surface: recreate it, skip this frame.
    OutOfDate,
}

impl FrameSync {
    /// `n` slots, their fences signalled (no frame pending).
    pub fn new(ctx: &Arc<Context>, n: usize) -> Result<Self> {
        let d = &ctx.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut sync = Self {
            ctx: ctx.clone(),
            pool,
            slots: Vec::new(),
        };
        // From here on, Drop cleans up whatever was made.
        for i in 0..n {
            let info = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = unsafe { d.allocate_command_buffers(&info) }.vk("vkAllocateCommandBuffers")?[0];
            let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            let fence = unsafe { d.create_fence(&signalled, None) }.vk("vkCreateFence")?;
            let acquired = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) };
            let acquired = acquired
                .vk("vkCreateSemaphore")
                .inspect_err(|_| unsafe { d.destroy_fence(fence, None) })?;
            ctx.set_name(acquired, &format!("frame.acquired[{i}]"));
            ctx.set_name(cmd, &format!("frame.commands[{i}]"));
            sync.slots.push(Slot { cmd, fence, acquired });
        }
        Ok(sync)
    }

    pub fn len(&self) -> usize {
        self.slots.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The pool the slots' command buffers come from (for one-time uploads).
    pub fn pool(&self) -> vk::CommandPool {
        self.pool
    }

    /// Blocks until slot `i`'s last frame has finished on the GPU.
    pub fn wait(&self, i: usize) -> Result<()> {
        unsafe { self.ctx.device.wait_for_fences(&[self.slots[i].fence], true, u64::MAX) }.vk("vkWaitForFences")
    }

    /// Acquires the next image of `sc` for slot `i`'s frame (which must have finished).
    pub fn acquire(&self, i: usize, sc: &Swapchain) -> Result<Acquired> {
        let surface = self.ctx.surface.as_ref().expect("a window context");
        let acquired = self.slots[i].acquired;
        match unsafe {
            surface
                .swapchain
                .acquire_next_image(sc.raw, u64::MAX, acquired, vk::Fence::null())
        } {
            Ok((index, suboptimal)) => Ok(Acquired::Image {
                index: index as usize,
                suboptimal,
            }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(Error::Vulkan {
                what: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Slot `i`'s command buffer, reset and begun for one submission.
    pub fn begin(&self, i: usize) -> Result<vk::CommandBuffer> {
        let cmd = self.slots[i].cmd;
        self.ctx.begin(cmd)?;
        Ok(cmd)
    }

    /// Ends slot `i`'s command buffer and submits it, waiting for the acquire at the
    /// transfer and colour-output stages and signalling image `image`'s "rendered"
    /// semaphore and the slot's fence, then presents the image. `Ok(true)`: the
    /// swapchain should be recreated (suboptimal or out of date).
    pub fn submit_present(&self, i: usize, sc: &Swapchain, image: usize) -> Result<bool> {
        let (d, slot) = (&self.ctx.device, &self.slots[i]);
        unsafe { d.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer")?;
        let rendered = sc.rendered[image];
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(slot.acquired)
            .stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER | vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(rendered)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        unsafe {
            d.reset_fences(&[slot.fence]).vk("vkResetFences")?;
            d.queue_submit2(self.ctx.queue, &submit, slot.fence)
                .vk("vkQueueSubmit2")?;
        }
        let (chains, images, semaphores) = ([sc.raw], [image as u32], [rendered]);
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&semaphores)
            .swapchains(&chains)
            .image_indices(&images);
        let surface = self.ctx.surface.as_ref().expect("a window context");
        match unsafe { surface.swapchain.queue_present(self.ctx.queue, &present) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(result) => Err(Error::Vulkan {
                what: "vkQueuePresentKHR",
                result,
            }),
        }
    }
}

impl Drop for FrameSync {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        unsafe {
            let _ = d.device_wait_idle();
            for s in &self.slots {
                d.destroy_fence(s.fence, None);
                d.destroy_semaphore(s.acquired, None);
            }
            d.destroy_command_pool(self.pool, None);
        }
    }
}
