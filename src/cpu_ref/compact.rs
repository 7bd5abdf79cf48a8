//! Reference of `ssr.compact` (`glsl/compact_*.comp`).

use crate::shader_defines::{FAIL_UNTRACED, WG_2D};

/// The pixels in the list's order (`glsl/shared/compact.glsl`): `WG_2D` x `WG_2D`
/// blocks row-major, pixels row-major inside each block.
pub fn order(width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
    let (bx, by) = (width.div_ceil(WG_2D), height.div_ceil(WG_2D));
    (0..by * bx)
        .flat_map(move |b| {
            (0..WG_2D * WG_2D).map(move |j| ((b % bx) * WG_2D + j % WG_2D, (b / bx) * WG_2D + j / WG_2D))
        })
        .filter(move |&(x, y)| x < width && y < height)
}

/// The pixels of a `width` x `height` row-major mask whose value is nonzero and not
/// `FAIL_UNTRACED`, in the list's order, packed `x | y << 16`.
pub fn compact(mask: &[u32], width: u32, height: u32) -> Vec<u32> {
    order(width, height)
        .filter(|&(x, y)| {
            let m = mask[(y * width + x) as usize];
            m != 0 && m & FAIL_UNTRACED == 0
        })
        .map(|(x, y)| x | (y << 16))
        .collect()
}
