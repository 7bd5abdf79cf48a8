//! Reference of `glsl/shared/surface.glsl` (base colours, ray-cone LOD, bent-normal
//! clamping) and of Vulkan's trilinear, repeating lookup in a 2D array texture: colour
//! layers through its `R8G8B8A8_SRGB` view (texels decoded to linear before filtering,
//! as the spec orders), data layers through its `R8G8B8A8_UNORM` view (the bytes / 255).

use crate::gpu_types::GpuMaterial;
use crate::scene::texture::srgb_to_linear;
use crate::shader_defines::TEXTURE_NONE;
use glam::{Vec2, Vec3, Vec4};

/// A texture array as the GPU holds it: layers of `size`², each a mip chain of
/// tightly packed RGBA8 levels (`scene::texture::layers`), and whether each is data
/// (read as UNORM) rather than sRGB colour.
pub struct TextureArray {
    pub size: u32,
    pub layers: Vec<Vec<image::RgbaImage>>,
    pub data: Vec<bool>,
}

impl TextureArray {
    pub fn new(textures: &[crate::scene::Texture], max: u32) -> Self {
        let (size, layers) = crate::scene::texture::layers(textures, max);
        let data = (0..layers.len())
            .map(|i| textures.get(i).is_some_and(|t| t.data))
            .collect();
        Self { size, layers, data }
    }

    fn texel(&self, layer: usize, level: usize, x: i32, y: i32) -> Vec4 {
        let img = &self.layers[layer][level];
        let (w, h) = (img.width() as i32, img.height() as i32);
        let p = img.get_pixel(x.rem_euclid(w) as u32, y.rem_euclid(h) as u32).0;
        let unorm = |c: u8| c as f32 / 255.0;
        let colour = if self.data[layer] { unorm } else { srgb_to_linear };
        Vec4::new(colour(p[0]), colour(p[1]), colour(p[2]), unorm(p[3]))
    }

    fn bilinear(&self, layer: usize, level: usize, uv: Vec2) -> Vec4 {
        let edge = self.layers[layer][level].width() as f32;
        let t = uv * edge - 0.5;
        let i = t.floor();
        let f = t - i;
        let (x, y) = (i.x as i32, i.y as i32);
        let row = |y: i32| {
            self.texel(layer, level, x, y)
                .lerp(self.texel(layer, level, x + 1, y), f.x)
        };
        row(y).lerp(row(y + 1), f.y)
    }

    /// The spread (largest less smallest, per channel) of the four texels a bilinear
    /// lookup at `uv` of level `level` weighs: how far a filter weight's rounding can
    /// move the result, per unit of weight.
    pub fn footprint_range(&self, layer: u32, level: usize, uv: Vec2) -> Vec4 {
        let (layer, edge) = (layer as usize, self.layers[layer as usize][level].width() as f32);
        let i = (uv * edge - 0.5).floor();
        let (x, y) = (i.x as i32, i.y as i32);
        let texels = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| self.texel(layer, level, x + dx, y + dy));
        let (lo, hi) = texels.iter().fold((Vec4::INFINITY, Vec4::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(*t), hi.max(*t))
        });
        hi - lo
    }

    /// `textureLod(textures, vec3(uv, layer), lod)`: the level clamped to the chain,
    /// linear between the two nearest levels.
    pub fn sample_lod(&self, layer: u32, uv: Vec2, lod: f32) -> Vec4 {
        let layer = layer as usize;
        let last = (self.layers[layer].len() - 1) as f32;
        let lod = lod.clamp(0.0, last);
        let d0 = lod.floor();
        let f = lod - d0;
        let a = self.bilinear(layer, d0 as usize, uv);
        if f == 0.0 {
            return a;
        }
        a.lerp(self.bilinear(layer, (d0 + 1.0).min(last) as usize, uv), f)
    }
}

/// `base_color_lod`.
pub fn base_color_lod(m: &GpuMaterial, textures: &TextureArray, uv: Vec2, lod: f32) -> Vec3 {
    let albedo = Vec3::from(m.albedo);
    if m.texture_layer == TEXTURE_NONE {
        return albedo;
    }
    albedo * textures.sample_lod(m.texture_layer, uv, lod).truncate()
}

/// `BENT_NORMAL_MIN_COS`.
pub const BENT_NORMAL_MIN_COS: f32 = 0.01;

/// `clamp_bent_normal`: `n` with its mirror direction for `v` kept above the plane of
/// the geometric normal `g` (facing `v`).
pub fn clamp_bent_normal(n: Vec3, g: Vec3, v: Vec3) -> Vec3 {
    let r = (-v).reflect(n);
    let d = r.dot(g);
    if d >= BENT_NORMAL_MIN_COS {
        return n;
    }
    let lifted = (r + g * (BENT_NORMAL_MIN_COS - d)).normalize();
    (v + lifted).normalize()
}

/// `ray_cone_lod`.
pub fn ray_cone_lod(width: f32, cos_incidence: f32, p: [Vec3; 3], uv: [Vec2; 3], texels: f32) -> f32 {
    let (e1, e2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let t_area = texels * texels * (e1.x * e2.y - e1.y * e2.x).abs();
    let p_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    // `!(x > 0)` as in GLSL: NaN areas take the finest level too.
    if t_area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || p_area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return 0.0;
    }
    0.5 * (t_area / p_area).log2() + (width / cos_incidence.max(1e-4)).log2()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Random normals, facets and views: the clamped normal is unit, its mirror
    /// direction is at least `BENT_NORMAL_MIN_COS` above the facet, and a normal that
    /// already mirrors above it is returned as it was.
    #[test]
    fn clamped_normals_mirror_above_the_facet() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut unit = || {
            Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::Y)
        };
        let (mut changed, mut same) = (0, 0);
        for _ in 0..20000 {
            let g = unit();
            let mut v = unit();
            if v.dot(g) < 0.0 {
                v = -v;
            }
            let mut n = unit();
            if n.dot(v) < 0.0 {
                n = -n;
            }
            let c = clamp_bent_normal(n, g, v);
            assert!((c.length() - 1.0).abs() < 1e-5);
            let up = (-v).reflect(c).dot(g);
            assert!(up >= BENT_NORMAL_MIN_COS - 1e-4, "{n} {g} {v}: {up}");
            if (-v).reflect(n).dot(g) >= BENT_NORMAL_MIN_COS {
                assert_eq!(c, n);
                same += 1;
            } else {
                changed += 1;
            }
        }
        assert!(changed > 1000 && same > 1000, "{changed} {same}");
    }
}
