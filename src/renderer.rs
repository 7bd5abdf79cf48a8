//! Owns the passes and records one frame top to bottom: every pass under its timer
//! scope, every barrier with the hazard it resolves.
//!
//! Frame: uniforms → `shadow.map` → `gbuffer` → `light.direct` → (by mode)
//! `ssr.classify` → `ssr.trace` → `ssr.compact` → `rt.trace` → `reflect.merge` →
//! `compose` (the `rt` mode has no `ssr.trace`: it marches nothing).
//! The static BVH is built once, when the renderer is created.

use crate::error::{Error, Result, VkContext};
use crate::gpu_types::{FrameUniforms, GpuMaterial};
use crate::passes::lbvh::{Bvh, Geometry, LbvhBuilder, MortonBits};
use crate::passes::reflect_merge::{self, BlurParams, MergePass};
use crate::passes::rt_reflect::{self, ReflectInputs, RtReflectPass};
use crate::passes::rt_trace::{TraceScene, Traceable};
use crate::passes::ssr_compact::{self, CompactPass};
use crate::passes::ssr_trace::{self, SsrParams, SsrPass};
use crate::passes::{compose, gbuffer, light_direct, shadow_map, SceneGeometry};
use crate::scene::Scene;
use crate::settings::Mode;
use crate::settings::Settings;
use crate::shader_defines::{COMPOSE_PLAIN, COMPOSE_PROVENANCE, COMPOSE_REFLECT};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Image};
use ash::vk;
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// Pixel counts of a frame's reflections.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReflectionStats {
    /// Pixels whose surface reflects (reflectivity above `reflective_min`).
    pub reflective_pixels: u64,
    /// Reflective pixels SSR failed on (ray traced in hybrid; all of them in rt).
    pub failed_pixels: u64,
    /// Failed pixels by reason (a pixel may have one reason).
    pub fail_reasons: std::collections::BTreeMap<&'static str, u64>,
}

impl ReflectionStats {
    /// failed / reflective pixels: the share of reflections the ray tracer produced.
    pub fn rt_pixel_fraction(&self) -> f64 {
        self.failed_pixels as f64 / self.reflective_pixels.max(1) as f64
    }
}

/// Per-pixel reflection state of a frame, row-major.
pub struct ReflectionMaps {
    /// The pixel's surface reflects (reflectivity above `reflective_min`).
    pub reflective: Vec<bool>,
    /// `FAIL_*` bits written by `ssr.classify` and `ssr.trace` (0: SSR succeeded or
    /// nothing to reflect).
    pub mask: Vec<u32>,
}

impl ReflectionMaps {
    pub fn stats(&self) -> ReflectionStats {
        let failed = || self.mask.iter().zip(&self.reflective).filter(|(m, r)| **m != 0 && **r);
        let mut fail_reasons = std::collections::BTreeMap::new();
        for (&m, _) in failed() {
            for (bit, name) in FAIL_REASONS {
                if m & bit != 0 {
                    *fail_reasons.entry(name).or_insert(0) += 1;
                }
            }
        }
        ReflectionStats {
            reflective_pixels: self.reflective.iter().filter(|r| **r).count() as u64,
            failed_pixels: failed().count() as u64,
            fail_reasons,
        }
    }

    /// The fail mask as tightly packed RGBA8, one colour per reason (the lowest set
    /// bit wins; `FAIL_COLOURS`), SSR successes dark blue, non-reflective pixels black.
    pub fn fail_mask_rgba(&self) -> Vec<u8> {
        self.mask
            .iter()
            .zip(&self.reflective)
            .flat_map(|(&m, &r)| {
                let rgb = if !r {
                    [0, 0, 0]
                } else if m == 0 {
                    SSR_OK_COLOUR
                } else {
                    FAIL_COLOURS[m.trailing_zeros() as usize % FAIL_COLOURS.len()]
                };
                [rgb[0], rgb[1], rgb[2], 255]
            })
            .collect()
    }
}

/// Colour of a reflective pixel SSR answered, in `--fail-mask` images.
pub const SSR_OK_COLOUR: [u8; 3] = [30, 50, 140];
/// Colour of each fail reason in `--fail-mask` images, indexed by bit position (the
/// order of `FAIL_REASONS`): yellow, orange, red, magenta, cyan, green, white, light
/// blue (an SSR hit blended with the ray tracer's).
pub const FAIL_COLOURS: [[u8; 3]; 8] = [
    [240, 220, 40],
    [250, 130, 20],
    [220, 30, 30],
    [230, 40, 230],
    [40, 220, 230],
    [40, 200, 60],
    [255, 255, 255],
    [120, 170, 255],
];

/// Names of the fail-mask reason bits, for reports.
pub const FAIL_REASONS: [(u32, &str); 8] = [
    (crate::shader_defines::FAIL_LEFT_SCREEN, "left_screen"),
    (crate::shader_defines::FAIL_BEHIND, "behind_geometry"),
    (crate::shader_defines::FAIL_OUT_OF_STEPS, "out_of_steps"),
    (crate::shader_defines::FAIL_BACK_FACE, "back_face"),
    (crate::shader_defines::FAIL_LOW_CONFIDENCE, "low_confidence"),
    (crate::shader_defines::FAIL_HIT_REFLECTIVE, "hit_reflective"),
    (crate::shader_defines::FAIL_FORCED, "forced"),
    (crate::shader_defines::FAIL_BLEND, "ssr_blend"),
];

/// Timer scope of the whole frame.
pub const FRAME: &str = "frame";
/// Timer scope of the per-frame uniform upload.
pub const UNIFORMS: &str = "uniforms";

/// The scene's buffers on the GPU.
struct SceneBuffers {
    vertices: Buffer,
    indices: Buffer,
    materials: Buffer,
    index_count: u32,
}

pub struct Renderer {
    ctx: Arc<Context>,
    settings: Settings,
    scene: SceneBuffers,
    frame_ubo: Buffer,
    uniforms: FrameUniforms,
    pub shadow: shadow_map::ShadowMapPass,
    pub gbuffer: gbuffer::GBufferPass,
    pub light: light_direct::LightDirectPass,
    pub ssr: SsrPass,
    pub compact: CompactPass,
    pub rt: RtReflectPass,
    pub merge: MergePass,
    pub compose: compose::ComposePass,
    /// BVH over the scene's (static) triangles, built at creation.
    pub static_bvh: Bvh,
    /// GPU milliseconds per stage of the static BVH build.
    pub static_bvh_build: Vec<(&'static str, f64)>,
    timer: GpuTimer,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

/// The light's world → clip transform: an orthographic box around the scene's
/// bounding sphere, looking along the light direction.
fn light_view_proj(direction: Vec3, lo: Vec3, hi: Vec3) -> Mat4 {
    let center = 0.5 * (lo + hi);
    let r = (0.5 * (hi - lo).length()).max(1e-3) * 1.01;
    let up = if direction.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let view = glam::camera::rh::view::look_at_mat4(center + direction * 2.0 * r, center, up);
    glam::camera::rh::proj::vulkan::orthographic(-r, r, -r, r, r, 3.0 * r) * view
}

/// Frame uniforms for `scene` seen with `settings`.
pub fn frame_uniforms(scene: &Scene, settings: &Settings) -> FrameUniforms {
    let aspect = settings.width as f32 / settings.height as f32;
    let view_proj = scene.camera.view_proj(aspect);
    let (lo, hi) = scene.bounds();
    let light = &scene.light;
    FrameUniforms {
        view_proj,
        inv_view_proj: view_proj.inverse(),
        light_view_proj: light_view_proj(light.direction, lo, hi),
        view: scene.camera.view(),
        proj: scene.camera.projection(aspect),
        camera_pos: scene.camera.position.extend(1.0),
        light_dir: light.direction.normalize().extend(0.0),
        light_color: (light.color * light.intensity).extend(0.0),
        sky_zenith: scene.sky.zenith.extend(0.0),
        sky_horizon: scene.sky.horizon.extend(0.0),
        resolution: [settings.width, settings.height],
        shadow_map_size: settings.shadow_map_size,
        pcf_radius: settings.pcf_radius,
        shadow_bias: settings.shadow_bias,
        exposure: settings.exposure,
        ambient: settings.ambient,
        _pad0: 0.0,
    }
}

impl Renderer {
    /// Uploads the scene and creates every pass at the settings' resolution.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: &Settings) -> Result<Self> {
        settings.validate()?;
        scene.validate()?;
        let max = ctx.limits.max_image_dimension2_d;
        if settings.width > max || settings.height > max || settings.shadow_map_size > max {
            return Err(Error::Settings(format!(
                "resolution {}x{} (shadow map {}) exceeds this device's maxImageDimension2D {max}",
                settings.width, settings.height, settings.shadow_map_size
            )));
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
        let scene_buffers = SceneBuffers {
            vertices: Buffer::with_data(ctx, "scene.vertices", storage, bytemuck::cast_slice(&scene.vertices))?,
            indices: Buffer::with_data(
                ctx,
                "scene.indices",
                vk::BufferUsageFlags::INDEX_BUFFER | storage,
                bytemuck::cast_slice(&scene.indices),
            )?,
            materials: Buffer::with_data(ctx, "scene.materials", storage, bytemuck::cast_slice(&materials))?,
            index_count: scene.indices.len() as u32,
        };
        let frame_ubo = Buffer::new(
            ctx,
            "frame.uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        let extent = vk::Extent2D {
            width: settings.width,
            height: settings.height,
        };
        // The static BVH, once: the scene has no dynamic geometry yet.
        let static_bvh = Bvh::new(ctx, scene_buffers.index_count / 3, MortonBits::Bits30)?;
        let mut build_timer = GpuTimer::new(ctx, 8)?;
        {
            let builder = LbvhBuilder::new(ctx)?;
            let geometry = Geometry {
                vertices: &scene_buffers.vertices,
                indices: &scene_buffers.indices,
                tri_count: static_bvh.tri_count,
            };
            ctx.one_shot(|cmd| {
                build_timer.reset(cmd);
                builder.record_build(cmd, &mut build_timer, geometry, &static_bvh);
            })?;
        }
        let static_bvh_build = build_timer.results()?;
        let cmd = ctx.allocate_command_buffer()?;
        let fence = unsafe { ctx.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let renderer = Self {
            ctx: ctx.clone(),
            settings: settings.clone(),
            scene: scene_buffers,
            frame_ubo,
            uniforms: frame_uniforms(scene, settings),
            shadow: shadow_map::ShadowMapPass::new(ctx, settings.shadow_map_size, settings.shadow_slope_bias)?,
            gbuffer: gbuffer::GBufferPass::new(ctx, extent)?,
            light: light_direct::LightDirectPass::new(ctx, extent)?,
            ssr: SsrPass::new(ctx, extent)?,
            compact: CompactPass::new(ctx, extent)?,
            rt: RtReflectPass::new(ctx, extent)?,
            merge: MergePass::new(ctx, extent)?,
            compose: compose::ComposePass::new(ctx, extent)?,
            static_bvh,
            static_bvh_build,
            timer: GpuTimer::new(ctx, 16)?,
            cmd,
            fence,
        };
        Ok(renderer)
    }

    /// The uniforms the next frame uses.
    pub fn uniforms(&self) -> &FrameUniforms {
        &self.uniforms
    }

    /// Replaces the camera (e.g. for an animated or interactive view).
    pub fn set_uniforms(&mut self, uniforms: FrameUniforms) {
        self.uniforms = uniforms;
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Records, submits and waits for one frame; returns its GPU time per scope (ms).
    pub fn render_frame(&mut self) -> Result<Vec<(&'static str, f64)>> {
        let device = self.ctx.device.clone();
        unsafe {
            device
                .reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            device
                .begin_command_buffer(self.cmd, &begin)
                .vk("vkBeginCommandBuffer")?;
        }
        self.record(self.cmd);
        unsafe {
            device.end_command_buffer(self.cmd).vk("vkEndCommandBuffer")?;
            device.reset_fences(&[self.fence]).vk("vkResetFences")?;
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            device
                .queue_submit2(self.ctx.queue, &submit, self.fence)
                .vk("vkQueueSubmit2")?;
            device
                .wait_for_fences(&[self.fence], true, u64::MAX)
                .vk("vkWaitForFences")?;
        }
        self.timer.results()
    }

    /// Records one frame into `cmd`.
    fn record(&mut self, cmd: vk::CommandBuffer) {
        use vk::ImageLayout as L;
        let device = self.ctx.device.clone();
        let d = &device;
        let geometry = SceneGeometry {
            vertices: &self.scene.vertices,
            indices: &self.scene.indices,
            index_count: self.scene.index_count,
        };
        let color = vk::ImageAspectFlags::COLOR;
        let depth = vk::ImageAspectFlags::DEPTH;
        let timer = &mut self.timer;
        timer.reset(cmd);
        timer.begin(cmd, FRAME);

        timer.begin(cmd, UNIFORMS);
        // WAR: the previous frame's shader reads of the uniforms finish before they change.
        barrier::record(
            d,
            cmd,
            &[barrier::memory(access::ANY_SHADER_READ, access::TRANSFER_WRITE)],
            &[],
        );
        unsafe { d.cmd_update_buffer(cmd, self.frame_ubo.raw, 0, bytemuck::bytes_of(&self.uniforms)) };
        // RAW: every pass below reads the uniforms just written.
        barrier::record(
            d,
            cmd,
            &[barrier::memory(access::TRANSFER_WRITE, access::ANY_SHADER_READ)],
            &[],
        );
        timer.end(cmd, UNIFORMS);

        timer.begin(cmd, shadow_map::NAME);
        let map = self.shadow.map.raw;
        // WAR: the previous frame's light.direct reads finish before the map is cleared (old contents discarded).
        let to_attachment = barrier::image(
            map,
            depth,
            access::COMPUTE_READ,
            access::DEPTH_WRITE,
            L::UNDEFINED,
            L::DEPTH_ATTACHMENT_OPTIMAL,
        );
        barrier::record(d, cmd, &[], &[to_attachment]);
        self.shadow.record(cmd, &self.frame_ubo, &geometry);
        // RAW: light.direct samples the depth written above.
        let to_read = barrier::image(
            map,
            depth,
            access::DEPTH_WRITE,
            access::COMPUTE_READ,
            L::DEPTH_ATTACHMENT_OPTIMAL,
            L::SHADER_READ_ONLY_OPTIMAL,
        );
        barrier::record(d, cmd, &[], &[to_read]);
        timer.end(cmd, shadow_map::NAME);

        timer.begin(cmd, gbuffer::NAME);
        let t = &self.gbuffer.targets;
        // WAR: the previous frame's light.direct reads finish before the targets are cleared.
        let mut into: Vec<_> = t
            .colors()
            .iter()
            .map(|i| {
                barrier::image(
                    i.raw,
                    color,
                    access::COMPUTE_READ,
                    access::COLOR_WRITE,
                    L::UNDEFINED,
                    L::COLOR_ATTACHMENT_OPTIMAL,
                )
            })
            .collect();
        into.push(barrier::image(
            t.depth.raw,
            depth,
            access::COMPUTE_READ,
            access::DEPTH_WRITE,
            L::UNDEFINED,
            L::DEPTH_ATTACHMENT_OPTIMAL,
        ));
        barrier::record(d, cmd, &[], &into);
        self.gbuffer
            .record(cmd, &self.frame_ubo, &self.scene.materials, &geometry);
        // RAW: light.direct reads the G-buffer written above.
        let mut out: Vec<_> = t
            .colors()
            .iter()
            .map(|i| {
                barrier::image(
                    i.raw,
                    color,
                    access::COLOR_WRITE,
                    access::COMPUTE_READ,
                    L::COLOR_ATTACHMENT_OPTIMAL,
                    L::SHADER_READ_ONLY_OPTIMAL,
                )
            })
            .collect();
        out.push(barrier::image(
            t.depth.raw,
            depth,
            access::DEPTH_WRITE,
            access::COMPUTE_READ,
            L::DEPTH_ATTACHMENT_OPTIMAL,
            L::SHADER_READ_ONLY_OPTIMAL,
        ));
        barrier::record(d, cmd, &[], &out);
        timer.end(cmd, gbuffer::NAME);

        timer.begin(cmd, light_direct::NAME);
        // WAR: the previous frame's ssr.trace and compose reads of `lit` finish before it is overwritten.
        let lit_in = barrier::image(
            self.light.lit.raw,
            color,
            access::COMPUTE_READ,
            access::COMPUTE_WRITE,
            L::UNDEFINED,
            L::GENERAL,
        );
        barrier::record(d, cmd, &[], &[lit_in]);
        self.light
            .record(cmd, &self.frame_ubo, &self.gbuffer.targets, &self.shadow.map);
        // RAW: ssr.trace and compose read the lit colour written above.
        let lit_out = barrier::image(
            self.light.lit.raw,
            color,
            access::COMPUTE_WRITE,
            access::COMPUTE_READ,
            L::GENERAL,
            L::GENERAL,
        );
        barrier::record(d, cmd, &[], &[lit_out]);
        timer.end(cmd, light_direct::NAME);

        let mode = self.settings.mode;
        let reflections = mode != Mode::Raster;
        let traced = matches!(mode, Mode::Hybrid | Mode::Rt | Mode::Provenance);
        let seams = matches!(mode, Mode::Hybrid | Mode::Provenance);
        let st = &self.settings;
        // WAR/WAW: the previous frame's reads and writes of the reflection images are
        // done before this frame rewrites them (old contents discarded).
        let reflection_images = [
            &self.ssr.out.color,
            &self.ssr.out.mask,
            &self.rt.color,
            self.merge.reflection(),
            self.merge.scratch(),
        ];
        let into: Vec<_> = reflection_images
            .iter()
            .map(|i| {
                barrier::image(
                    i.raw,
                    color,
                    access::ALL_READ_WRITE,
                    access::ALL_READ_WRITE,
                    L::UNDEFINED,
                    L::GENERAL,
                )
            })
            .collect();
        barrier::record(d, cmd, &[], &into);

        if reflections {
            let params = SsrParams::from_settings(st);
            timer.begin(cmd, ssr_trace::CLASSIFY_NAME);
            let mask_only = mode == Mode::Rt;
            self.ssr
                .classify(cmd, &self.frame_ubo, &self.gbuffer.targets, &params, mask_only);
            timer.end(cmd, ssr_trace::CLASSIFY_NAME);
            // The rt mode has nothing to march: its list is empty.
            if !mask_only {
                timer.begin(cmd, ssr_trace::NAME);
                self.ssr
                    .trace(cmd, &self.frame_ubo, &self.gbuffer.targets, &self.light.lit, &params);
                timer.end(cmd, ssr_trace::NAME);
            }
            // RAW: compaction and merge read the fail mask and SSR colour.
            barrier::record(
                d,
                cmd,
                &[barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ)],
                &[],
            );
        }
        if traced {
            timer.begin(cmd, ssr_compact::NAME);
            self.compact.record(cmd, &self.ssr.out.mask);
            timer.end(cmd, ssr_compact::NAME);

            timer.begin(cmd, rt_reflect::NAME);
            let geometry = Geometry {
                vertices: &self.scene.vertices,
                indices: &self.scene.indices,
                tri_count: self.static_bvh.tri_count,
            };
            let inputs = ReflectInputs {
                frame: &self.frame_ubo,
                gbuffer: &self.gbuffer.targets,
                materials: &self.scene.materials,
                shadow_map: &self.shadow.map,
                list: &self.compact.out,
                scene: TraceScene {
                    static_bvh: Some(Traceable {
                        bvh: &self.static_bvh,
                        geometry,
                    }),
                    dynamic_bvh: None,
                },
            };
            self.rt.record(cmd, &inputs, st.max_bounces, st.shadow_rays);
            // RAW: the merge reads the ray-traced colour.
            barrier::record(
                d,
                cmd,
                &[barrier::memory(access::COMPUTE_WRITE, access::COMPUTE_READ)],
                &[],
            );
            timer.end(cmd, rt_reflect::NAME);
        }
        if reflections {
            timer.begin(cmd, reflect_merge::NAME);
            self.merge.record(
                cmd,
                &self.frame_ubo,
                &self.gbuffer.targets,
                &self.ssr.out.mask,
                &self.ssr.out.color,
                &self.rt.color,
                traced,
                st.reflective_min,
                BlurParams {
                    // Seams exist only where both sources do.
                    radius: if seams { st.blur_radius } else { 0 },
                    band: st.blur_band,
                },
            );
            timer.end(cmd, reflect_merge::NAME);
        }

        timer.begin(cmd, compose::NAME);
        // WAR: earlier reads of the LDR image (readback copies) finish before it is overwritten.
        let ldr_in = barrier::image(
            self.compose.ldr.raw,
            color,
            access::ALL_READ_WRITE,
            access::COMPUTE_WRITE,
            L::UNDEFINED,
            L::GENERAL,
        );
        barrier::record(d, cmd, &[], &[ldr_in]);
        let compose_mode = match mode {
            Mode::Raster => COMPOSE_PLAIN,
            Mode::Provenance => COMPOSE_PROVENANCE,
            _ => COMPOSE_REFLECT,
        };
        let inputs = compose::ComposeInputs {
            hdr: &self.light.lit,
            reflection: self.merge.reflection(),
            normal: &self.gbuffer.targets.normal,
        };
        self.compose.record(cmd, &inputs, self.settings.exposure, compose_mode);
        timer.end(cmd, compose::NAME);

        timer.end(cmd, FRAME);
    }

    /// Switches the reflection mode for the next frames (for reference renders).
    pub fn set_mode(&mut self, mode: Mode) {
        self.settings.mode = mode;
    }

    /// Per pixel of the last frame: whether it reflects, and its fail-mask bits (0 in
    /// `raster` mode). A readback, for stats, debug images and tests.
    pub fn reflection_maps(&self) -> Result<ReflectionMaps> {
        let normal = crate::cpu_ref::rgba16f_to_f32(&self.read_target(&self.gbuffer.targets.normal)?);
        let material: Vec<u32> = bytemuck::pod_collect_to_vec(&self.read_target(&self.gbuffer.targets.material)?);
        let min = self.settings.reflective_min;
        let reflective = normal
            .iter()
            .zip(&material)
            .map(|(n, &m)| m != crate::shader_defines::MATERIAL_NONE && n[3] > min)
            .collect();
        let mask = if self.settings.mode == Mode::Raster {
            vec![0; material.len()]
        } else {
            bytemuck::pod_collect_to_vec(&self.ssr.out.mask.read(vk::ImageLayout::GENERAL)?)
        };
        Ok(ReflectionMaps { reflective, mask })
    }

    /// Reflective pixels and failed (ray-traced) pixels of the last frame, counted from
    /// the G-buffer and the fail mask (a readback: for stats and tests).
    pub fn reflection_stats(&self) -> Result<ReflectionStats> {
        Ok(self.reflection_maps()?.stats())
    }

    /// The last frame's tonemapped image as tightly packed RGBA8 (sRGB-encoded).
    pub fn read_output(&self) -> Result<Vec<u8>> {
        self.compose.ldr.read(vk::ImageLayout::GENERAL)
    }

    /// The last frame's lit HDR image as RGBA f32.
    pub fn read_lit(&self) -> Result<Vec<[f32; 4]>> {
        let raw = self.light.lit.read(vk::ImageLayout::GENERAL)?;
        debug_assert_eq!(light_direct::FORMAT, vk::Format::R32G32B32A32_SFLOAT);
        Ok(bytemuck::pod_collect_to_vec(&raw))
    }

    /// Reads a G-buffer (or shadow map) image left in `SHADER_READ_ONLY_OPTIMAL`.
    pub fn read_target(&self, image: &Image) -> Result<Vec<u8>> {
        image.read(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            self.ctx.device.destroy_fence(self.fence, None);
        }
        self.ctx.free_command_buffer(self.cmd);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `FAIL_REASONS` lists the fail bits in bit order, so a reason's colour index in
    /// `FAIL_COLOURS` is its bit position.
    #[test]
    fn fail_reasons_are_in_bit_order() {
        for (i, (bit, _)) in FAIL_REASONS.iter().enumerate() {
            assert_eq!(*bit, 1 << i);
        }
        assert_eq!(FAIL_REASONS.len(), FAIL_COLOURS.len());
    }

    /// Stats and the debug image agree with a hand-made mask.
    #[test]
    fn maps_count_and_colour_each_reason() {
        let maps = ReflectionMaps {
            reflective: vec![false, true, true, true, true],
            mask: vec![
                0,
                0,
                crate::shader_defines::FAIL_BACK_FACE,
                crate::shader_defines::FAIL_LEFT_SCREEN | crate::shader_defines::FAIL_BEHIND,
                crate::shader_defines::FAIL_FORCED,
            ],
        };
        let s = maps.stats();
        assert_eq!((s.reflective_pixels, s.failed_pixels), (4, 3));
        assert_eq!(s.fail_reasons["back_face"], 1);
        assert_eq!(s.fail_reasons["left_screen"], 1);
        assert_eq!(s.fail_reasons["behind_geometry"], 1);
        let rgba = maps.fail_mask_rgba();
        assert_eq!(&rgba[0..4], &[0, 0, 0, 255]);
        assert_eq!(&rgba[4..7], &SSR_OK_COLOUR);
        assert_eq!(&rgba[8..11], &FAIL_COLOURS[3]);
        assert_eq!(&rgba[12..15], &FAIL_COLOURS[0]);
        assert_eq!(&rgba[16..19], &FAIL_COLOURS[6]);
    }
}
