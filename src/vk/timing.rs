//! GPU timing by named scope. A scope writes a timestamp at its start and its end and
//! opens a debug label of the same name, so the profiler, the command-buffer labels
//! and the timings JSON all say the same thing. No slot numbers leave this file.

use super::context::Context;
use crate::error::{Result, VkContext};
use ash::vk;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Timestamp queries for one command buffer in flight.
pub struct GpuTimer {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    capacity: u32,
    /// (name, first query) of every scope recorded since the last reset.
    scopes: Vec<(&'static str, u32)>,
    open: Vec<usize>,
}

impl GpuTimer {
    /// Room for `max_scopes` scopes per frame.
    pub fn new(ctx: &Arc<Context>, max_scopes: u32) -> Result<Self> {
        let capacity = max_scopes * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(pool, "timer.queries");
        Ok(Self {
            ctx: ctx.clone(),
            pool,
            capacity,
            scopes: Vec::new(),
            open: Vec::new(),
        })
    }

    /// Starts a frame: forgets earlier scopes and resets the queries on the GPU.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.scopes.clear();
        self.open.clear();
        unsafe { self.ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
    }

    /// Opens scope `name` (scopes nest).
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &'static str) {
        let first = self.scopes.len() as u32 * 2;
        assert!(
            first + 2 <= self.capacity,
            "GpuTimer: more than {} scopes in a frame",
            self.capacity / 2
        );
        if let Some(du) = &self.ctx.debug_utils {
            let cname = std::ffi::CString::new(name).expect("scope names have no NUL");
            let label = vk::DebugUtilsLabelEXT::default().label_name(&cname);
            unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
        }
        unsafe {
            self.ctx
                .device
                .cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, first)
        };
        self.open.push(self.scopes.len());
        self.scopes.push((name, first));
    }

    /// Closes the innermost scope, which must be `name`.
    pub fn end(&mut self, cmd: vk::CommandBuffer, name: &'static str) {
        let i = self.open.pop().expect("GpuTimer::end without begin");
        assert_eq!(self.scopes[i].0, name, "GpuTimer scopes closed out of order");
        unsafe {
            self.ctx.device.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                self.scopes[i].1 + 1,
            )
        };
        if let Some(du) = &self.ctx.debug_utils {
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Records `record` inside scope `name`.
    pub fn scope<R>(&mut self, cmd: vk::CommandBuffer, name: &'static str, record: impl FnOnce() -> R) -> R {
        self.begin(cmd, name);
        let r = record();
        self.end(cmd, name);
        r
    }

    /// Milliseconds of every scope of the last frame; call after its fence signalled.
    pub fn results(&self) -> Result<Vec<(&'static str, f64)>> {
        let n = self.scopes.len() * 2;
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut raw = vec![0u64; n];
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let bits = self.ctx.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let period = self.ctx.timestamp_period_ns;
        Ok(self
            .scopes
            .iter()
            .map(|&(name, q)| {
                // Only the low `bits` bits count; the difference wraps modulo 2^bits.
                let ticks = (raw[q as usize + 1] & mask).wrapping_sub(raw[q as usize] & mask) & mask;
                (name, ticks as f64 * period * 1e-6)
            })
            .collect())
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}

/// Per-scope samples over many frames; reports medians.
#[derive(Default, Debug, Clone)]
pub struct Timings {
    samples: BTreeMap<&'static str, Vec<f64>>,
}

impl Timings {
    /// Adds one frame's scopes (a scope seen twice in a frame is summed).
    pub fn add_frame(&mut self, frame: &[(&'static str, f64)]) {
        let mut sums: BTreeMap<&'static str, f64> = BTreeMap::new();
        for &(name, ms) in frame {
            *sums.entry(name).or_default() += ms;
        }
        for (name, ms) in sums {
            self.samples.entry(name).or_default().push(ms);
        }
    }

    /// The samples of scope `name` (milliseconds, in frame order), if it was timed.
    pub fn samples(&self, name: &str) -> Option<&[f64]> {
        self.samples.get(name).map(|v| v.as_slice())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timings_sum_repeated_scopes_within_a_frame() {
        let mut t = Timings::default();
        t.add_frame(&[("a", 1.0), ("b", 2.0), ("a", 0.5)]);
        t.add_frame(&[("a", 3.0), ("b", 4.0)]);
        t.add_frame(&[("a", 2.0), ("b", 3.0)]);
        assert_eq!(t.samples("a"), Some(&[1.5, 3.0, 2.0][..]));
        assert_eq!(t.samples("b"), Some(&[2.0, 4.0, 3.0][..]));
        assert_eq!(t.samples("c"), None);
    }
}
