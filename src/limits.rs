//! Device limits a frame must fit, checked once when a renderer is created or resized,
//! before any GPU work: every image side against `maxImageDimension2D`, every dispatch
//! the frame can make (direct or indirect, at its largest) against
//! `maxComputeWorkGroupCount`. Buffers check `maxStorageBufferRange` themselves where they
//! are created (`Buffer::new`). A frame beyond a limit is refused with one line naming
//! the limit, the size and the device.

use crate::error::Result;
use crate::passes::ssr_compact;
use crate::settings::Settings;
use crate::shader_defines::{RT_LIST_WG, SSR_LIST_WG, WG_2D};
use crate::vk::Context;

/// Checks a frame of `settings` against the device's limits.
pub fn check_frame(ctx: &Context, settings: &Settings) -> Result<()> {
    let (w, h) = (settings.width, settings.height);
    let res = || format!("a {w}x{h} frame");
    let max_side = ctx.limits.max_image_dimension2_d as u64;
    let side = w.max(h) as u64;
    ctx.check_limit(res, side, "texels per side", "maxImageDimension2D", max_side)?;
    let shadow = settings.shadow_map_size as u64;
    let what = || format!("a shadow map of {shadow}x{shadow}");
    ctx.check_limit(what, shadow, "texels per side", "maxImageDimension2D", max_side)?;

    let max = ctx.limits.max_compute_work_group_count.map(u64::from);
    let pixels = w as u64 * h as u64;
    let tiles = (w.div_ceil(WG_2D) as u64, h.div_ceil(WG_2D) as u64);
    let compaction_slots = tiles.0 * tiles.1 * (WG_2D * WG_2D) as u64;
    // (what, workgroups along x) of every 1D dispatch at its largest: lists can hold
    // every pixel.
    let one_d = [
        ("ssr.trace over every pixel", pixels.div_ceil(SSR_LIST_WG as u64)),
        ("rt.reflect over every pixel", pixels.div_ceil(RT_LIST_WG as u64)),
        ("ssr.compact", compaction_slots.div_ceil(ssr_compact::TILE as u64)),
        ("the seam blur over every tile", tiles.0 * tiles.1),
    ];
    let x = "workgroups along x";
    for (pass, groups) in one_d {
        ctx.check_limit(
            || format!("{} ({pass})", res()),
            groups,
            x,
            "maxComputeWorkGroupCount[0]",
            max[0],
        )?;
    }
    let full_screen = || format!("{} (full-screen passes)", res());
    ctx.check_limit(full_screen, tiles.0, x, "maxComputeWorkGroupCount[0]", max[0])?;
    let y = "workgroups along y";
    ctx.check_limit(full_screen, tiles.1, y, "maxComputeWorkGroupCount[1]", max[1])?;
    Ok(())
}
