//! Reference of `glsl/reflect_merge.comp`, `glsl/reflect_tiles.comp` and
//! `glsl/reflect_blur.comp` (reflect.merge).

use crate::shader_defines::{FAIL_BLEND, FAIL_UNTRACED, SOURCE_NONE, SOURCE_RT, SOURCE_SSR, WG_2D};

/// One pixel of the merge: the reflection and its source (`SOURCE_*`, stored in alpha).
/// `fail`: the fail mask; `ssr`: SSR colour (rgb) and confidence (a); `rt`: the
/// ray-traced colour (rgb); `reflective`: the surface reflects; `rt_enabled`: failed
/// pixels take the ray-traced colour; `block`: the fail mask and ray-traced colour of
/// the even corner of the pixel's 2x2 block, which an untraced pixel takes where it
/// was traced.
pub fn merge(
    fail: u32,
    ssr: [f32; 4],
    rt: [f32; 4],
    reflective: bool,
    rt_enabled: bool,
    block: (u32, [f32; 4]),
) -> [f32; 4] {
    let mix = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
    let (block_fail, block_rt) = block;
    if !reflective {
        [0.0, 0.0, 0.0, SOURCE_NONE as f32]
    } else if fail == 0 {
        [ssr[0], ssr[1], ssr[2], SOURCE_SSR as f32]
    } else if fail & FAIL_UNTRACED != 0 {
        if rt_enabled && block_fail != 0 && block_fail & FAIL_UNTRACED == 0 {
            [block_rt[0], block_rt[1], block_rt[2], SOURCE_RT as f32]
        } else {
            [ssr[0], ssr[1], ssr[2], SOURCE_SSR as f32]
        }
    } else if rt_enabled {
        let c = if fail == FAIL_BLEND { ssr[3] } else { 0.0 };
        [
            mix(rt[0], ssr[0], c),
            mix(rt[1], ssr[1], c),
            mix(rt[2], ssr[2], c),
            SOURCE_RT as f32,
        ]
    } else if fail == FAIL_BLEND {
        [ssr[0] * ssr[3], ssr[1] * ssr[3], ssr[2] * ssr[3], SOURCE_SSR as f32]
    } else {
        [0.0, 0.0, 0.0, SOURCE_NONE as f32]
    }
}

/// `SEAM_EDGE`, `SEAM_EDGE_GLOSSY` of `reflect_blur.comp`: the relative colour
/// difference at which a neighbour's weight in the seam blur falls to 1/e, around a
/// mirror and around a glossy pixel.
pub const SEAM_EDGE: f32 = 0.3;
pub const SEAM_EDGE_GLOSSY: f32 = 0.9;

/// `range_weight`: how a neighbour of colour `b` counts beside a pixel of colour `a`.
pub fn range_weight(a: [f32; 3], b: [f32; 3], edge: f32) -> f32 {
    let d = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max);
    let m = (0..3).map(|c| a[c].max(b[c])).fold(0.0, f32::max);
    let r = d / (m + 0.05);
    (-(r * r) / (edge * edge)).exp()
}

/// One direction of the seam blur over a `width` x `height` row-major image whose alpha
/// is the source: `axis` (1, 0) or (0, 1); `radius` and `band` in pixels. Each
/// neighbour's Gaussian weight is scaled by its `range_weight` to the pixel, with the
/// glossy range where the pixel is `glossy`.
pub fn seam_blur(
    src: &[[f32; 4]],
    glossy: &[bool],
    width: usize,
    height: usize,
    axis: [i32; 2],
    radius: i32,
    band: i32,
) -> Vec<[f32; 4]> {
    let at = |x: i32, y: i32| -> [f32; 4] {
        if x < 0 || y < 0 || x >= width as i32 || y >= height as i32 {
            [0.0, 0.0, 0.0, SOURCE_NONE as f32]
        } else {
            src[y as usize * width + x as usize]
        }
    };
    let mut out = src.to_vec();
    for y in 0..height as i32 {
        for x in 0..width as i32 {
            let me = at(x, y);
            let source = me[3] as u32;
            let seam = source != SOURCE_NONE
                && radius > 0
                && (-band..=band).any(|k| {
                    let s = at(x + axis[0] * k, y + axis[1] * k)[3] as u32;
                    s != SOURCE_NONE && s != source
                });
            if !seam {
                continue;
            }
            let sigma = (radius as f32 * 0.5).max(0.5);
            let (mut sum, mut weight) = ([0.0f32; 3], 0.0f32);
            for k in -radius..=radius {
                let s = at(x + axis[0] * k, y + axis[1] * k);
                if s[3] as u32 == SOURCE_NONE {
                    continue;
                }
                let edge = match glossy[y as usize * width + x as usize] {
                    true => SEAM_EDGE_GLOSSY,
                    false => SEAM_EDGE,
                };
                let range = range_weight([me[0], me[1], me[2]], [s[0], s[1], s[2]], edge);
                let wk = (-((k * k) as f32) / (2.0 * sigma * sigma)).exp() * range;
                for c in 0..3 {
                    sum[c] += s[c] * wk;
                }
                weight += wk;
            }
            out[y as usize * width + x as usize] = [sum[0] / weight, sum[1] / weight, sum[2] / weight, me[3]];
        }
    }
    out
}

/// The seam blur's tile activity (`glsl/reflect_tiles.comp`): per `WG_2D` x `WG_2D`
/// tile of a `width` x `height` merged image (alpha: the source), row-major, whether the
/// tiles within `ceil(band / WG_2D)` of it hold both SSR and RT pixels.
pub fn active_tiles(merged: &[[f32; 4]], width: usize, height: usize, band: u32) -> Vec<bool> {
    let wg = WG_2D as usize;
    let (tx, ty) = (width.div_ceil(wg), height.div_ceil(wg));
    let mut bits = vec![0u32; tx * ty];
    for (i, p) in merged.iter().enumerate() {
        bits[(i / width / wg) * tx + (i % width) / wg] |= 1 << (p[3] as u32);
    }
    let k = band.div_ceil(WG_2D) as usize;
    let both = (1 << SOURCE_SSR) | (1 << SOURCE_RT);
    (0..tx * ty)
        .map(|t| {
            let (x, y) = (t % tx, t / tx);
            let mut b = 0;
            for yy in y.saturating_sub(k)..=(y + k).min(ty - 1) {
                for xx in x.saturating_sub(k)..=(x + k).min(tx - 1) {
                    b |= bits[yy * tx + xx];
                }
            }
            b & both == both
        })
        .collect()
}
