//! The adaptive hybrid's exchange rate, measured (`exchange_rate = 0`): what a march
//! costs in traced rays on this device, from the frame's own self-checked timestamps.
//! Each hybrid frame copies its counts — pixels marched (`ssr.trace`'s list) and rays
//! traced (`rt.reflect`'s) — into its slot's host-visible buffer; when the frame has
//! finished and its timings passed their self-check, (`ssr.trace` ms / marched) over
//! (`rt.reflect` ms / rays) joins a running mean (one part in five). The rate the tiles
//! use moves in steps of 1/32 and only once the mean has left it by more than 1/16, so
//! timing noise does not flip tiles from frame to frame.

use crate::error::Result;
use crate::shader_defines::TILE_ONE;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Fewer marched pixels or traced rays than this in a frame say nothing of their
/// costs (a dispatch's fixed cost would dominate).
const MIN_COUNT: u32 = 1000;

/// The measured rate and the one in use (1/`TILE_ONE`; 0 until the first sample: every
/// tile SSR-first).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExchangeRate {
    pub estimate: Option<f64>,
    pub applied: u32,
}

impl ExchangeRate {
    /// Takes one frame's costs: `ssr_ms` over `marched` pixels, `rt_ms` over `rays`.
    pub fn add(&mut self, (ssr_ms, marched): (f64, u32), (rt_ms, rays): (f64, u32)) {
        if marched < MIN_COUNT || rays < MIN_COUNT || !(ssr_ms > 0.0 && rt_ms > 0.0) {
            return;
        }
        let sample = (ssr_ms / marched as f64) / (rt_ms / rays as f64);
        let estimate = self.estimate.map_or(sample, |e| 0.8 * e + 0.2 * sample);
        self.estimate = Some(estimate);
        let scaled = estimate * TILE_ONE as f64;
        if (scaled - self.applied as f64).abs() > TILE_ONE as f64 / 16.0 {
            let step = TILE_ONE as f64 / 32.0;
            self.applied = ((scaled / step).round() * step).clamp(step, 16.0 * TILE_ONE as f64) as u32;
        }
    }

    /// The rate in use as a fraction (a march's cost in rays).
    pub fn fraction(&self) -> f64 {
        self.applied as f64 / TILE_ONE as f64
    }
}

/// One frame slot's counts, read back after its frame: pixels marched, rays traced,
/// pixels marched in SSR-first tiles (the rest were probes).
pub struct FrameCounts {
    buffer: Buffer,
    /// Whether the slot's last frame recorded them (a hybrid frame).
    pub recorded: bool,
}

impl FrameCounts {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        Ok(Self {
            buffer: Buffer::new(ctx, "frame.counts", 12, usage, MemoryLocation::GpuToCpu)?,
            recorded: false,
        })
    }

    /// Records the copies of the march list's length (word 3 of `march_args`), the ray
    /// list's (word 3 of `ray_args`) and the SSR-first tiles' marches (word 0 of
    /// `ssr_first`), after the passes that wrote them; the words end free for the next
    /// frame's writers and visible to the host.
    pub fn record(
        &mut self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        [march_args, ray_args, ssr_first]: [&Buffer; 3],
    ) {
        barrier::global(device, cmd, access::COMPUTE_WRITE, access::TRANSFER_READ);
        for (src, from, at) in [(march_args, 12, 0), (ray_args, 12, 4), (ssr_first, 0, 8)] {
            let region = vk::BufferCopy::default().src_offset(from).dst_offset(at).size(4);
            // SAFETY: both buffers are live and large enough; the barrier above orders the copy.
            unsafe { device.cmd_copy_buffer(cmd, src.raw, self.buffer.raw, &[region]) };
        }
        barrier::record(
            device,
            cmd,
            &[
                barrier::memory(access::TRANSFER_READ, access::ALL_READ_WRITE),
                barrier::memory(access::TRANSFER_WRITE, access::HOST_READ),
            ],
            &[],
        );
        self.recorded = true;
    }

    /// [marched, rays, marched in SSR-first tiles] of the slot's finished frame, if it
    /// recorded them.
    pub fn take(&mut self) -> Option<[u32; 3]> {
        if !std::mem::take(&mut self.recorded) {
            return None;
        }
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&self.buffer.mapped()?[..12]);
        Some([words[0], words[1], words[2]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rate follows the samples' running mean in steps of 1/32, holds within 1/16
    /// of it, and ignores frames with too little of either.
    #[test]
    fn the_rate_is_smoothed_and_quantised() {
        let mut r = ExchangeRate::default();
        r.add((1.0, 500), (1.0, 5000));
        assert_eq!(r, ExchangeRate::default(), "too few marched");
        // A march costing 0.86 of a ray: applied 0.875 (28/32).
        r.add((8.6, 10_000), (10.0, 10_000));
        assert_eq!((r.applied, r.fraction()), (224, 0.875));
        // Noise of a few percent moves the mean, not the rate.
        for k in 0..20 {
            let ms = if k % 2 == 0 { 8.2 } else { 9.0 };
            r.add((ms, 10_000), (10.0, 10_000));
            assert_eq!(r.applied, 224, "sample {k}");
        }
        // A new device's costs pull it over within a few frames.
        for _ in 0..20 {
            r.add((1.0, 10_000), (10.0, 10_000));
        }
        let e = r.estimate.unwrap();
        assert!(e < 0.12 && (r.fraction() - e).abs() <= 1.0 / 16.0, "{r:?}");
    }
}
