//! Textures: loading (PNG, JPEG), the layers of the texture array the GPU samples,
//! and the sRGB transfer functions.
//!
//! Lavapipe has no descriptor indexing, so every texture of a scene is one layer of a
//! single 2D array texture (trilinear, repeat): the layer edge is the power of two at or
//! above the largest texture's longer side (at most `LAYER_MAX`), and textures of
//! another size are resampled to it. Colour textures are read through an
//! `R8G8B8A8_SRGB` view (texels decoded to linear light before filtering); data
//! textures (roughness and metallic maps) through an `R8G8B8A8_UNORM` view of the same
//! texels, so their bytes are the data, unencoded, and no sRGB decode (whose place
//! around the filter a device may get wrong) touches them. Each layer has a full mip
//! chain, made here (2x2 means in linear light, or of the data), so the GPU and the CPU
//! references sample the same texels.

use crate::error::{Error, Result};
use image::RgbaImage;
use std::path::Path;

/// Texture file formats `load` reads.
pub const FORMATS: &str = "PNG, JPEG";

/// The largest layer edge: 2048² RGBA8 is 16 MiB a layer (21 MiB with mips).
pub const LAYER_MAX: u32 = 2048;

/// A texture: a base colour, or data (a roughness and metallic map).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages (a file path, or a glTF image).
    pub name: String,
    /// RGBA8 texels, row 0 at v = 0: sRGB-encoded colour, or (`data`) the data's bytes.
    pub image: RgbaImage,
    /// Linear data, read through the array's UNORM view; else sRGB colour.
    pub data: bool,
}

impl Texture {
    /// A colour texture of sRGB-encoded texels.
    pub fn colour(name: impl Into<String>, image: RgbaImage) -> Self {
        Self {
            name: name.into(),
            image,
            data: false,
        }
    }
}

/// Reads and decodes a texture file. A missing or unreadable file is `Error::Io`; one
/// that is not a PNG or JPEG, or does not decode, is `Error::BadAsset`.
pub fn load(path: &Path) -> Result<Texture> {
    let bytes = crate::error::read_file(path, "texture", crate::error::bounds::IMAGE)?;
    decode(&bytes, &path.display().to_string()).map_err(|detail| Error::BadAsset {
        what: "texture",
        path: path.into(),
        detail,
    })
}

/// Decodes texture file bytes (PNG or JPEG, told by their content).
pub fn decode(bytes: &[u8], name: &str) -> std::result::Result<Texture, String> {
    let format = image::guess_format(bytes)
        .map_err(|_| format!("not an image file of a supported format (supported: {FORMATS})"))?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(format!("unsupported texture format {format:?} (supported: {FORMATS})"));
    }
    let img = image::load_from_memory_with_format(bytes, format).map_err(|e| e.to_string())?;
    if img.width() == 0 || img.height() == 0 {
        return Err("the image has no texels".into());
    }
    Ok(Texture::colour(name, img.to_rgba8()))
}

/// `t` as linear data (a roughness map): its bytes are the data, read through the
/// array's UNORM view, and its mip levels average the data.
pub fn data_texture(t: Texture) -> Texture {
    Texture { data: true, ..t }
}

/// The sRGB decoding of an 8-bit value (IEC 61966-2-1), as Vulkan's `_SRGB` formats do.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB encoding of a linear value in [0, 1], rounded to 8 bits.
pub fn linear_to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let e = if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0).round() as u8
}

/// The layer edge for textures of these sizes: the power of two at or above the
/// longest side, at most `max` (itself a power of two); 1 when there are none.
pub fn layer_size(sizes: impl IntoIterator<Item = (u32, u32)>, max: u32) -> u32 {
    let longest = sizes.into_iter().map(|(w, h)| w.max(h)).max().unwrap_or(1);
    longest.next_power_of_two().min(max).max(1)
}

/// The texels as linear values: sRGB decoded, or (`data`) the bytes / 255.
fn to_linear(img: &RgbaImage, data: bool) -> image::Rgba32FImage {
    let lut: Vec<f32> = (0..=255u8)
        .map(|c| if data { c as f32 / 255.0 } else { srgb_to_linear(c) })
        .collect();
    image::Rgba32FImage::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get_pixel(x, y).0;
        image::Rgba([
            lut[p[0] as usize],
            lut[p[1] as usize],
            lut[p[2] as usize],
            p[3] as f32 / 255.0,
        ])
    })
}

/// `to_linear`'s inverse, rounded to 8 bits.
fn to_bytes(img: &image::Rgba32FImage, data: bool) -> RgbaImage {
    let unorm = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    let colour = |c: f32| if data { unorm(c) } else { linear_to_srgb(c) };
    RgbaImage::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get_pixel(x, y).0;
        image::Rgba([colour(p[0]), colour(p[1]), colour(p[2]), unorm(p[3])])
    })
}

/// The texture array of `textures`: its layer edge (`layer_size`, at most `max`) and
/// each texture's mip chain (`mip_chain`); one white 1x1 layer when there are none.
pub fn layers(textures: &[Texture], max: u32) -> (u32, Vec<Vec<RgbaImage>>) {
    if textures.is_empty() {
        return (1, vec![vec![RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]))]]);
    }
    let size = layer_size(textures.iter().map(|t| t.image.dimensions()), max);
    (
        size,
        textures.iter().map(|t| mip_chain(&t.image, size, t.data)).collect(),
    )
}

/// The mip chain of `image` as a layer of edge `size` (a power of two), largest
/// first, down to 1x1. Level 0 is the image itself when it is `size`² already, else
/// the image resampled (triangle filter) in linear light; each further level is the
/// mean of 2x2 texels of the one before, in linear light (alpha linear throughout).
/// `data`: the bytes are linear data, resampled and averaged as they are.
pub fn mip_chain(image: &RgbaImage, size: u32, data: bool) -> Vec<RgbaImage> {
    assert!(size.is_power_of_two(), "layer edge {size} is not a power of two");
    let mut linear = to_linear(image, data);
    let mut levels = Vec::new();
    if image.dimensions() == (size, size) {
        levels.push(image.clone());
    } else {
        linear = image::imageops::resize(&linear, size, size, image::imageops::FilterType::Triangle);
        levels.push(to_bytes(&linear, data));
    }
    while linear.width() > 1 {
        let half = linear.width() / 2;
        linear = image::Rgba32FImage::from_fn(half, half, |x, y| {
            let mut sum = [0.0f32; 4];
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = linear.get_pixel(2 * x + dx, 2 * y + dy).0;
                for (s, c) in sum.iter_mut().zip(p) {
                    *s += c;
                }
            }
            image::Rgba(sum.map(|s| 0.25 * s))
        });
        levels.push(to_bytes(&linear, data));
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_byte() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(c)), c);
        }
    }

    #[test]
    fn layer_sizes_are_powers_of_two_within_the_cap() {
        assert_eq!(layer_size([], 2048), 1);
        assert_eq!(layer_size([(64, 64)], 2048), 64);
        assert_eq!(layer_size([(100, 30), (20, 300)], 2048), 512);
        assert_eq!(layer_size([(5000, 10)], 2048), 2048);
    }

    /// A 4x4 checker of `a` and `b`.
    fn checker(a: image::Rgba<u8>, b: image::Rgba<u8>) -> RgbaImage {
        RgbaImage::from_fn(4, 4, |x, y| if (x + y) % 2 == 0 { a } else { b })
    }

    /// A 4x4 checker of two colours: level 0 is the texels themselves, level 1 the 2x2
    /// means in linear light, the chain ends at 1x1; a 3x5 image is resampled to 8x8.
    #[test]
    fn mip_chains_average_in_linear_light() {
        let (a, b) = (image::Rgba([200, 30, 10, 255]), image::Rgba([10, 90, 240, 255]));
        let img = checker(a, b);
        let chain = mip_chain(&img, 4, false);
        assert_eq!(chain.len(), 3);
        assert_eq!(chain[0], img);
        let mean = |k: usize| linear_to_srgb(0.5 * (srgb_to_linear(a.0[k]) + srgb_to_linear(b.0[k])));
        for level in &chain[1..] {
            for p in level.pixels() {
                assert_eq!(p.0, [mean(0), mean(1), mean(2), 255]);
            }
        }
        let odd = RgbaImage::from_pixel(3, 5, a);
        let chain = mip_chain(&odd, 8, false);
        assert_eq!(chain.iter().map(|l| l.width()).collect::<Vec<_>>(), [8, 4, 2, 1]);
        assert!(chain[0]
            .pixels()
            .all(|p| p.0.iter().zip(a.0).all(|(&c, w)| c.abs_diff(w) <= 1)));
    }

    /// A data texture's chain: level 0 its bytes, level 1 the plain means of its bytes
    /// (no sRGB curve), rounded to the nearest byte.
    #[test]
    fn data_mip_chains_average_the_data() {
        let img = checker(image::Rgba([200, 31, 11, 7]), image::Rgba([10, 91, 241, 255]));
        let chain = mip_chain(&img, 4, true);
        assert_eq!(chain[0], img);
        for level in &chain[1..] {
            for p in level.pixels() {
                assert_eq!(p.0, [105, 61, 126, 131]);
            }
        }
    }

    #[test]
    fn other_formats_are_named_in_the_error() {
        let e = decode(b"BM\x36\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00", "t.bmp").unwrap_err();
        assert!(e.contains("Bmp") && e.contains("PNG, JPEG"), "{e}");
        let e = decode(b"not an image", "t.png").unwrap_err();
        assert!(e.contains("supported: PNG, JPEG"), "{e}");
    }
}
