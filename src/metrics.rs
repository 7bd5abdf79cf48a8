//! Image quality metrics for comparing a render with its reference.
//!
//! SSIM follows Wang, Bovik, Sheikh & Simoncelli 2004 ("Image Quality Assessment: From
//! Error Visibility to Structural Similarity"): an 11x11 Gaussian window with
//! sigma = 1.5, K1 = 0.01, K2 = 0.03, dynamic range 1, population (not sample)
//! statistics, averaged over the pixels whose window lies inside the image. It is
//! computed on luma (Rec. 709 weights of the sRGB-encoded values, as a grey
//! conversion of the PNG would) — the same settings as scikit-image's
//! `structural_similarity(gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=1)`, which the tests check against.
//! RMSE is over the R, G and B channels in [0, 1].

use crate::error::{Error, Result};

/// Window radius: 11x11 window (scikit-image: truncate 3.5 x sigma 1.5, rounded).
const RADIUS: usize = 5;
const SIGMA: f64 = 1.5;

fn gaussian_weights() -> [f64; 2 * RADIUS + 1] {
    let mut w = [0.0; 2 * RADIUS + 1];
    for (i, v) in w.iter_mut().enumerate() {
        let x = i as f64 - RADIUS as f64;
        *v = (-x * x / (2.0 * SIGMA * SIGMA)).exp();
    }
    let sum: f64 = w.iter().sum();
    w.map(|v| v / sum)
}

/// Separable Gaussian filter, evaluated where the window fits: output is
/// (w - 2R) x (h - 2R).
fn filter(img: &[f64], w: usize, h: usize, k: &[f64; 2 * RADIUS + 1]) -> Vec<f64> {
    let (ow, oh) = (w - 2 * RADIUS, h - 2 * RADIUS);
    let mut rows = vec![0.0; ow * h];
    for y in 0..h {
        for x in 0..ow {
            rows[y * ow + x] = (0..=2 * RADIUS).map(|i| k[i] * img[y * w + x + i]).sum();
        }
    }
    let mut out = vec![0.0; ow * oh];
    for y in 0..oh {
        for x in 0..ow {
            out[y * ow + x] = (0..=2 * RADIUS).map(|i| k[i] * rows[(y + i) * ow + x]).sum();
        }
    }
    out
}

/// Smallest side of an image SSIM can be computed on: the 11x11 window must fit.
pub const MIN_SIDE: u32 = 2 * RADIUS as u32 + 1;

/// Fails unless a `w` x `h` image is large enough for SSIM (checked before rendering
/// an image that will be compared).
pub fn check_size(w: u32, h: u32) -> Result<()> {
    if w < MIN_SIDE || h < MIN_SIDE {
        return Err(Error::Input(format!(
            "SSIM needs images of at least {MIN_SIDE}x{MIN_SIDE} (its 11x11 window), got {w}x{h}"
        )));
    }
    Ok(())
}

/// Mean SSIM of two single-channel images with values in [0, 1].
pub fn ssim(a: &[f64], b: &[f64], w: usize, h: usize) -> Result<f64> {
    if a.len() != w * h || b.len() != w * h {
        return Err(Error::Input(format!("SSIM: images must both be {w}x{h}")));
    }
    check_size(w as u32, h as u32)?;
    let k = gaussian_weights();
    let prod = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).collect::<Vec<_>>();
    let mu_a = filter(a, w, h, &k);
    let mu_b = filter(b, w, h, &k);
    let aa = filter(&prod(a, a), w, h, &k);
    let bb = filter(&prod(b, b), w, h, &k);
    let ab = filter(&prod(a, b), w, h, &k);
    let (c1, c2) = ((0.01f64).powi(2), (0.03f64).powi(2));
    let n = mu_a.len() as f64;
    let sum: f64 = (0..mu_a.len())
        .map(|i| {
            let (ma, mb) = (mu_a[i], mu_b[i]);
            let va = aa[i] - ma * ma;
            let vb = bb[i] - mb * mb;
            let cov = ab[i] - ma * mb;
            ((2.0 * ma * mb + c1) * (2.0 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2))
        })
        .sum();
    Ok(sum / n)
}

/// Rec. 709 luma of tightly packed RGBA8 pixels, in [0, 1].
pub fn luma(rgba: &[u8]) -> Vec<f64> {
    rgba.chunks_exact(4)
        .map(|p| (0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64) / 255.0)
        .collect()
}

/// Root-mean-square difference over R, G and B, in [0, 1].
pub fn rmse_rgb(a: &[u8], b: &[u8]) -> f64 {
    let (sum, n) = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .fold((0.0f64, 0usize), |(s, n), (p, q)| {
            let d: f64 = (0..3).map(|c| ((p[c] as f64 - q[c] as f64) / 255.0).powi(2)).sum();
            (s + d, n + 3)
        });
    (sum / n.max(1) as f64).sqrt()
}

/// SSIM (on luma) and RMSE (RGB) of two RGBA8 images of equal size.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Comparison {
    pub ssim: f64,
    pub rmse: f64,
}

pub fn compare_rgba8(a: &[u8], b: &[u8], w: u32, h: u32) -> Result<Comparison> {
    let (w, h) = (w as usize, h as usize);
    Ok(Comparison {
        ssim: ssim(&luma(a), &luma(b), w, h)?,
        rmse: rmse_rgb(a, b),
    })
}

/// Loads an image file as RGBA8.
pub fn load_rgba(p: &std::path::Path) -> Result<image::RgbaImage> {
    let bytes = crate::error::read_file(p, "image", crate::error::bounds::IMAGE)?;
    Ok(image::load_from_memory(&bytes)
        .map_err(|e| Error::BadAsset {
            what: "image",
            path: p.into(),
            detail: e.to_string(),
        })?
        .to_rgba8())
}

/// Per-pixel error at which `error_heatmap` saturates: an RMS difference over R, G and
/// B of 0.25 (in [0, 1]) is drawn white, so errors of a few percent stay visible.
pub const HEATMAP_FULL_SCALE: f64 = 0.25;

/// A heat map of the per-pixel error of two RGBA8 images of equal size, as RGBA8:
/// the RMS difference over R, G and B, scaled by `HEATMAP_FULL_SCALE`, through a
/// black → purple → orange → white ramp (0 is black).
pub fn error_heatmap(a: &[u8], b: &[u8]) -> Vec<u8> {
    const RAMP: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [0.45, 0.05, 0.55], [0.95, 0.45, 0.1], [1.0, 1.0, 1.0]];
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .flat_map(|(p, q)| {
            let e2: f64 = (0..3)
                .map(|c| ((p[c] as f64 - q[c] as f64) / 255.0).powi(2))
                .sum::<f64>()
                / 3.0;
            let t = (e2.sqrt() / HEATMAP_FULL_SCALE).clamp(0.0, 1.0) * 3.0;
            let (i, f) = ((t.floor() as usize).min(2), t - (t.floor()).min(2.0));
            let rgb = [0, 1, 2].map(|c| ((RAMP[i][c] + (RAMP[i + 1][c] - RAMP[i][c]) * f) * 255.0).round() as u8);
            [rgb[0], rgb[1], rgb[2], 255]
        })
        .collect()
}

/// Loads two PNGs and compares them.
pub fn compare_files(a: &std::path::Path, b: &std::path::Path) -> Result<Comparison> {
    let (ia, ib) = (load_rgba(a)?, load_rgba(b)?);
    check_same_size(a, &ia, b, &ib)?;
    compare_rgba8(ia.as_raw(), ib.as_raw(), ia.width(), ia.height())
}

/// Fails unless two loaded images have the same size.
pub fn check_same_size(
    a: &std::path::Path,
    ia: &image::RgbaImage,
    b: &std::path::Path,
    ib: &image::RgbaImage,
) -> Result<()> {
    if ia.dimensions() != ib.dimensions() {
        return Err(Error::Input(format!(
            "cannot compare '{}' ({}x{}) with '{}' ({}x{}): sizes differ",
            a.display(),
            ia.width(),
            ia.height(),
            b.display(),
            ib.width(),
            ib.height()
        )));
    }
    Ok(())
}

/// Mean NVIDIA FLIP error (Andersson et al. 2020; the `nv-flip` crate, which builds
/// NVIDIA's C++ implementation) of `test` against `reference`, both tightly packed
/// RGBA8 (sRGB) of `w` x `h`, alpha ignored, at FLIP's default 67 pixels per degree
/// (a 0.7 m wide monitor of 3840 pixels seen from 0.7 m). 0 for identical images, at
/// most 1.
pub fn flip_mean(test: &[u8], reference: &[u8], w: u32, h: u32) -> Result<f64> {
    let n = (w as usize) * (h as usize) * 4;
    if n == 0 || test.len() != n || reference.len() != n {
        return Err(Error::Input(format!(
            "FLIP: images of {} and {} bytes, not {w}x{h} RGBA8",
            test.len(),
            reference.len()
        )));
    }
    let rgb = |rgba: &[u8]| -> Vec<u8> { rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(test));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(nv_flip::FlipPool::from_image(&map).mean() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heatmap_is_black_where_equal_and_white_at_full_scale() {
        let a = [10, 20, 30, 255, 0, 0, 0, 255, 0, 0, 0, 255];
        let b = [10, 20, 30, 255, 255, 255, 255, 255, 32, 32, 32, 255];
        let h = error_heatmap(&a, &b);
        assert_eq!(&h[0..4], &[0, 0, 0, 255]);
        assert_eq!(&h[4..8], &[255, 255, 255, 255]);
        // 32/255 = 0.125 = half scale: between purple and orange.
        assert!(h[8] > 115 && h[8] < 242 && h[10] < 140, "{:?}", &h[8..12]);
    }

    /// The synthetic images of the scikit-image check (64x48, float64).
    fn images() -> (Vec<f64>, Vec<Vec<f64>>) {
        let (w, h) = (64, 48);
        let mut a = vec![0.0; w * h];
        let mut b = a.clone();
        let mut c = a.clone();
        let mut d = a.clone();
        for y in 0..h {
            for x in 0..w {
                let (xf, yf) = (x as f64, y as f64);
                let i = y * w + x;
                a[i] = 0.5 + 0.4 * (0.3 * xf).sin() * (0.2 * yf).cos();
                b[i] = (a[i] + 0.1 * (0.7 * xf + 0.5 * yf).sin()).clamp(0.0, 1.0);
                c[i] = a[i] * 0.8 + 0.1;
                d[i] = (xf * xf * 0.618 + yf * 0.377 + xf * yf * 0.013).rem_euclid(1.0);
            }
        }
        (a, vec![b, c, d])
    }

    /// Values from scikit-image 0.26.0, `structural_similarity(a, x,
    /// gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0)`
    /// on the same images.
    #[test]
    fn ssim_matches_scikit_image() {
        let (a, others) = images();
        let want = [0.7905129011299752, 0.9728302492100221, 0.014487803151716086];
        for (x, w) in others.iter().zip(want) {
            let got = ssim(&a, x, 64, 48).unwrap();
            assert!((got - w).abs() < 1e-9, "got {got}, scikit-image {w}");
        }
        assert!((ssim(&a, &a, 64, 48).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn rmse_of_known_differences() {
        let a = [0u8, 0, 0, 255, 255, 255, 255, 255];
        let b = [255u8, 0, 0, 0, 255, 255, 255, 0];
        // One of six channels differs by 1.0: sqrt(1/6). Alpha is ignored.
        assert!((rmse_rgb(&a, &b) - (1.0f64 / 6.0).sqrt()).abs() < 1e-12);
        assert_eq!(rmse_rgb(&a, &a), 0.0);
    }

    #[test]
    fn tiny_images_are_an_error() {
        assert!(ssim(&[0.5; 100], &[0.5; 100], 10, 10).is_err());
    }
}
