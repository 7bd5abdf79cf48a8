//! The renderer's readbacks of the last frame: its images and per-pixel maps, for
//! reports, stats, debug images and tests.

use super::Renderer;
use crate::error::Result;
use crate::passes::light_direct;
use crate::reflection_maps::{ReflectionMaps, ReflectionStats};
use crate::settings::Mode;
use crate::shadow_maps::ShadowMaps;
use crate::vk::Image;
use ash::vk;
use glam::Vec3;

/// The adaptive hybrid's tiles (`Renderer::tile_census`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileCensus {
    /// Tiles marching first, sending their pixels straight to rays, and not known yet
    /// (no pixel marched there yet: nothing to reflect, or only just seen; they march
    /// first).
    pub ssr_first: u64,
    pub rays_only: u64,
    pub unknown: u64,
    /// Changes of class since the tiles were reset: over all tiles, and of the tile
    /// that changed most (each tile's count holds at `TILE_FLIPS_MAX`).
    pub flips: u64,
    pub most_flips: u64,
}

impl Renderer {
    /// Per pixel of the last frame: whether it reflects, and its fail-mask bits (0 in
    /// `raster` mode). A readback, for stats, debug images and tests.
    pub fn reflection_maps(&self) -> Result<ReflectionMaps> {
        let (normal, material) = self.read_normals_and_materials()?;
        let min = self.settings.reflective_min;
        let reflective = normal
            .iter()
            .zip(&material)
            .map(|(n, &m)| m != crate::shader_defines::MATERIAL_NONE && n[3] > min)
            .collect();
        let mask = if self.settings.mode == Mode::Raster {
            vec![0; material.len()]
        } else {
            bytemuck::pod_collect_to_vec(&self.reflections.ssr.out.mask.read(vk::ImageLayout::GENERAL)?)
        };
        Ok(ReflectionMaps {
            reflective,
            mask,
            traced: self.settings.mode.traces(),
        })
    }

    /// The last frame's G-buffer normals (xyz; w: reflectivity) and material ids.
    fn read_normals_and_materials(&self) -> Result<(Vec<[f32; 4]>, Vec<u32>)> {
        let normal = crate::gpu_types::rgba16f_to_f32(&self.read_target(&self.lighting.gbuffer.out.normal)?);
        let material = bytemuck::pod_collect_to_vec(&self.read_target(&self.lighting.gbuffer.out.material)?);
        Ok((normal, material))
    }

    /// The last frame's shadow state (a readback: for stats, tests and images).
    pub fn shadow_maps(&self) -> Result<ShadowMaps> {
        let (normal, material) = self.read_normals_and_materials()?;
        let l = self.uniforms.light_dir.truncate();
        let lit = normal
            .iter()
            .zip(&material)
            .map(|(n, &m)| {
                m != crate::shader_defines::MATERIAL_NONE && Vec3::new(n[0], n[1], n[2]).normalize().dot(l) > 0.0
            })
            .collect();
        let read = |image: &Image| image.read(vk::ImageLayout::GENERAL);
        let mask = if self.last_plan.is_some_and(|p| p.shadows.traces()) {
            bytemuck::pod_collect_to_vec(&read(&self.lighting.shadow_trace.out.mask)?)
        } else {
            vec![0; material.len()]
        };
        Ok(ShadowMaps {
            lit,
            mask,
            visibility: bytemuck::pod_collect_to_vec(&read(&self.lighting.shadow_trace.out.visibility)?),
        })
    }

    /// Reflective pixels and failed (ray-traced) pixels of the last frame, counted from
    /// the G-buffer and the fail mask (a readback: for stats and tests).
    pub fn reflection_stats(&self) -> Result<ReflectionStats> {
        Ok(self.reflection_maps()?.stats())
    }

    /// The adaptive hybrid's tiles after the last hybrid frame: their classes and how
    /// often they have changed class since the tiles were reset.
    pub fn tile_census(&self) -> Result<TileCensus> {
        use crate::shader_defines::{TILE_FLIPS_SHIFT, TILE_KNOWN, TILE_RAYS_ONLY, TILE_WORDS};
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&self.reflections.ssr.tiles_written().read()?);
        let mut c = TileCensus::default();
        for &s in words.iter().step_by(TILE_WORDS as usize) {
            *match (s & TILE_KNOWN != 0, s & TILE_RAYS_ONLY != 0) {
                (true, false) => &mut c.ssr_first,
                (_, true) => &mut c.rays_only,
                (false, false) => &mut c.unknown,
            } += 1;
            let flips = (s >> TILE_FLIPS_SHIFT) as u64;
            c.flips += flips;
            c.most_flips = c.most_flips.max(flips);
        }
        Ok(c)
    }

    /// The last frame's tonemapped image as tightly packed RGBA8 (sRGB-encoded).
    pub fn read_output(&self) -> Result<Vec<u8>> {
        self.compose.out.read(vk::ImageLayout::GENERAL)
    }

    /// The last frame's lit HDR image as RGBA f32.
    pub fn read_lit(&self) -> Result<Vec<[f32; 4]>> {
        let raw = self.lighting.light.out.read(vk::ImageLayout::GENERAL)?;
        debug_assert_eq!(light_direct::FORMAT, vk::Format::R32G32B32A32_SFLOAT);
        Ok(bytemuck::pod_collect_to_vec(&raw))
    }

    /// Reads a G-buffer (or shadow map) image left in `SHADER_READ_ONLY_OPTIMAL`.
    pub fn read_target(&self, image: &Image) -> Result<Vec<u8>> {
        image.read(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
    }
}
