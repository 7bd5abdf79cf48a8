//! Device limits a frame must fit, checked once when a renderer is created or resized,
//! before any GPU work: every image side against `maxImageDimension2D`, the per-pixel
//! lists against `maxStorageBufferRange`, every dispatch the frame can make (direct or
//! indirect, at its largest) against `maxComputeWorkGroupCount`. List kernels spread
//! their workgroups over x and y (`passes::list_groups`), so no list is too long to
//! dispatch. (Every buffer also checks its range where it is created, `Buffer::new`.)
//! A frame beyond a limit is refused with one line naming the limit, the size and the
//! device.

use crate::error::Result;
use crate::passes::{list_groups, ssr_compact};
use crate::settings::Settings;
use crate::shader_defines::{RT_LIST_WG, SSR_LIST_WG, WG_2D};
use crate::vk::Context;

/// Bytes per pixel of the per-pixel lists (the march list, the ray list): one packed
/// `u32` each.
const LIST_ENTRY_BYTES: u64 = 4;

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

    let pixels = w as u64 * h as u64;
    let range = ctx.limits.max_storage_buffer_range as u64;
    let list = || format!("{} (its pixel lists, 4 B per pixel)", res());
    ctx.check_limit(list, pixels * LIST_ENTRY_BYTES, "bytes", "maxStorageBufferRange", range)?;

    let max = ctx.limits.max_compute_work_group_count.map(u64::from);
    let tiles = (w.div_ceil(WG_2D), h.div_ceil(WG_2D));
    let slots = tiles.0 * tiles.1 * WG_2D * WG_2D;
    let px = pixels.min(u32::MAX as u64) as u32;
    // (what, workgroups) of every 1D or list dispatch at its largest: lists can hold
    // every pixel, the blur every tile.
    let lists = [
        ("ssr.trace over every pixel", list_groups(px.div_ceil(SSR_LIST_WG))),
        ("rt.reflect over every pixel", list_groups(px.div_ceil(RT_LIST_WG))),
        ("the seam blur over every tile", list_groups(tiles.0 * tiles.1)),
        ("ssr.compact", [slots.div_ceil(ssr_compact::TILE), 1]),
    ];
    for (pass, [x, y]) in lists {
        let what = || format!("{} ({pass})", res());
        ctx.check_limit(
            what,
            x as u64,
            "workgroups along x",
            "maxComputeWorkGroupCount[0]",
            max[0],
        )?;
        ctx.check_limit(
            what,
            y as u64,
            "workgroups along y",
            "maxComputeWorkGroupCount[1]",
            max[1],
        )?;
    }
    let full_screen = || format!("{} (full-screen passes)", res());
    let x = "workgroups along x";
    ctx.check_limit(full_screen, tiles.0 as u64, x, "maxComputeWorkGroupCount[0]", max[0])?;
    let y = "workgroups along y";
    ctx.check_limit(full_screen, tiles.1 as u64, y, "maxComputeWorkGroupCount[1]", max[1])?;
    Ok(())
}
