//! Owns the passes and records one frame top to bottom, each pass under its timer
//! scope. Every pass's `record` places its own barriers (see `passes`); this file only
//! does what spans passes: the uniform upload, which passes a mode runs, and the scopes.
//!
//! Frame: `uniforms` → (a dynamic scene: `sim.rigid` on the CPU before recording,
//! `sim.transform`, the dynamic BVH's `lbvh.*`) → `shadow.map` → `gbuffer` →
//! `light.direct` → (by mode) `ssr.classify` → `ssr.trace` → `ssr.compact` →
//! `rt.reflect` → `reflect.merge` → `compose`. The static BVH is built once, when the
//! renderer is created; the dynamic one every frame, over that frame's geometry.
//!
//! Frames in flight: `render_frame` submits and waits (the headless path);
//! `record_frame` records into a caller's command buffer with a frame slot (its own
//! timestamp queries and pose staging) and `frame_finished` reads the slot back after
//! the caller's fence, so several frames can be on the queue at once (the demo's two).
//! The screen-sized images are shared by all slots: each pass's entry barriers order
//! a frame after the one submitted before it on the queue.

use crate::error::{Result, VkContext};
use crate::gpu_types::{FrameUniforms, GpuMaterial};
use crate::passes::compose::{self, ComposeInputs, ComposeMode};
use crate::passes::lbvh::{Bvh, Geometry, LbvhBuilder, MortonBits, RefitSchedule};
use crate::passes::reflect_merge::{self, BlurParams, MergePass};
use crate::passes::rt_reflect::{self, ReflectInputs, RtReflectPass};
use crate::passes::rt_trace::{TraceScene, Traceable};
use crate::passes::sim_cloth::{ClothPass, ClothState};
use crate::passes::sim_transform::{self, SimTransformPass};
use crate::passes::ssr_compact::{self, CompactPass};
use crate::passes::ssr_trace::{self, SsrParams, SsrPass};
use crate::passes::{gbuffer, light_direct, shadow_map, SceneGeometry, Surfaces};
use crate::reflection_maps::{ReflectionMaps, ReflectionStats};
use crate::scene::{texture, Camera, Light, Scene, Sky};
use crate::settings::{Mode, Settings};
use crate::sim::rigid::RigidWorld;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Image, Sampler, TimerReadout, Wall};
use ash::vk;
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// Timer scope of the whole frame.
pub const FRAME: &str = "frame";
/// Timer scope of the per-frame uniform upload.
pub const UNIFORMS: &str = "uniforms";
/// The rigid bodies' time step on the CPU (wall clock, before the frame is recorded).
pub const SIM_RIGID: &str = "sim.rigid";
/// Every timer scope a frame can have, in frame order (`FRAME` last): the keys of every
/// report's `passes_ms`, a pass a mode (or a static scene) does not run reported as
/// `null`. All are GPU time but `sim.rigid`, the CPU's; the dynamic BVH's stages are
/// `lbvh.*` (the static BVH's, built once, are reported apart).
pub const SCOPES: [&str; 20] = [
    UNIFORMS,
    SIM_RIGID,
    sim_transform::NAME,
    crate::passes::sim_cloth::NAME,
    crate::passes::lbvh::BOUNDS,
    crate::passes::lbvh::MORTON,
    crate::passes::lbvh::SORT,
    crate::passes::lbvh::HIERARCHY,
    crate::passes::lbvh::FIT,
    crate::passes::lbvh::REFIT,
    shadow_map::NAME,
    gbuffer::NAME,
    light_direct::NAME,
    ssr_trace::CLASSIFY_NAME,
    ssr_trace::NAME,
    ssr_compact::NAME,
    rt_reflect::NAME,
    reflect_merge::NAME,
    compose::NAME,
    FRAME,
];

/// Indexed triangles on the GPU, as the raster passes draw them and the BVH builder and
/// traversal read them: world-space vertices (relative to the renderer's origin), their
/// texture coordinates, indices.
struct MeshBuffers {
    vertices: Buffer,
    uvs: Buffer,
    indices: Buffer,
    index_count: u32,
}

impl MeshBuffers {
    /// `vertices` (already made) with `uvs` and `indices` uploaded beside them.
    fn new(ctx: &Arc<Context>, name: &str, vertices: Buffer, uvs: &[[f32; 2]], indices: &[u32]) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            vertices,
            uvs: Buffer::with_data(ctx, &format!("{name}.uvs"), storage, bytemuck::cast_slice(uvs))?,
            indices: Buffer::with_data(
                ctx,
                &format!("{name}.indices"),
                vk::BufferUsageFlags::INDEX_BUFFER | storage,
                bytemuck::cast_slice(indices),
            )?,
            index_count: indices.len() as u32,
        })
    }

    fn geometry(&self) -> SceneGeometry<'_> {
        SceneGeometry {
            vertices: &self.vertices,
            uvs: &self.uvs,
            indices: &self.indices,
            index_count: self.index_count,
        }
    }

    /// The triangles as the BVH builder and the traversal read them.
    fn triangles(&self) -> Geometry<'_> {
        Geometry {
            vertices: &self.vertices,
            indices: &self.indices,
            tri_count: self.index_count / 3,
        }
    }
}

/// The scene's buffers and textures on the GPU.
struct SceneBuffers {
    mesh: MeshBuffers,
    materials: Buffer,
    textures: Image,
    texture_sampler: Sampler,
}

impl SceneBuffers {
    /// The surfaces, with the dynamic geometry's texture coordinates when there is any.
    fn surfaces<'a>(&'a self, dynamic: Option<&'a DynamicGeometry>) -> Surfaces<'a> {
        Surfaces {
            materials: &self.materials,
            uvs: [&self.mesh.uvs, dynamic.map_or(&self.mesh.uvs, |d| &d.mesh.uvs)],
            textures: &self.textures,
            sampler: &self.texture_sampler,
        }
    }
}

/// The moving geometry of a scene with bodies: its simulation, the bodies' meshes in
/// their own spaces, their poses (written by the host each frame, copied to the GPU in
/// the frame), the world-space vertices `sim.transform` writes, and the BVH over them,
/// rebuilt every frame.
struct DynamicGeometry {
    world: RigidWorld,
    objects: Buffer,
    /// The world-space vertices `sim.transform` and `sim.cloth` write.
    mesh: MeshBuffers,
    /// The poses as the host writes them, one buffer per frame slot (a frame in
    /// flight still copies from its own while the next one's are written).
    poses_staging: Vec<Buffer>,
    poses: Buffer,
    bvh: Bvh,
    /// Vertices `sim.transform` moves (the rigid bodies'); the cloths' follow.
    vertex_count: u32,
    cloths: Vec<ClothState>,
    /// Refit the BVH instead of rebuilding it (cloth only, unless `cloth_rebuild`),
    /// rebuilding every `rebuild_every` frames all the same.
    refit: bool,
    rebuild_every: u32,
    /// Frames since the BVH was last built (0: build in the next frame).
    since_build: u32,
    /// The refit order of the BVH as last built (made after the frame that built it).
    schedule: Option<RefitSchedule>,
    /// Wall-clock milliseconds of the last `sim.rigid` step.
    sim_ms: f64,
}

impl DynamicGeometry {
    /// The dynamic geometry of `scene`, simulated relative to `origin` (the renderer's).
    fn new(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, origin: Vec3) -> Result<Self> {
        use vk::BufferUsageFlags as U;
        let meshes = scene.dynamic_meshes();
        let vertex_count = meshes.rigid_vertices as u32;
        ctx.check_limit(
            || "the dynamic geometry".to_string(),
            vertex_count as u64,
            "vertices",
            "sim.transform's dispatch (65535 workgroups)",
            sim_transform::MAX_VERTICES as u64,
        )?;
        let tris = (meshes.indices.len() / 3) as u32;
        let storage = U::STORAGE_BUFFER;
        let pose_bytes = (scene.bodies.len() * std::mem::size_of::<Mat4>()) as u64;
        let world_vertices = Buffer::new(
            ctx,
            "dynamic.vertices",
            std::mem::size_of_val(meshes.vertices.as_slice()) as u64,
            storage | U::TRANSFER_SRC,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            world: RigidWorld::relative_to(scene, settings.sim_dt, origin)?,
            objects: Buffer::with_data(ctx, "dynamic.objects", storage, bytemuck::cast_slice(&meshes.vertices))?,
            mesh: MeshBuffers::new(ctx, "dynamic", world_vertices, &meshes.uvs, &meshes.indices)?,
            poses_staging: vec![pose_staging(ctx, pose_bytes)?],
            poses: Buffer::new(
                ctx,
                "dynamic.poses",
                pose_bytes,
                storage | U::TRANSFER_DST,
                gpu_allocator::MemoryLocation::GpuOnly,
            )?,
            bvh: Bvh::new(ctx, tris, MortonBits::Bits30)?,
            vertex_count,
            cloths: {
                let mut base = vertex_count;
                let mut states = Vec::new();
                for c in &scene.cloths {
                    states.push(ClothState::new(ctx, c, settings.sim_dt, base, origin)?);
                    base += c.resolution * c.resolution;
                }
                states
            },
            refit: scene.bodies.is_empty() && !settings.cloth_rebuild,
            rebuild_every: settings.refit_rebuild_every,
            since_build: 0,
            schedule: None,
            sim_ms: 0.0,
        })
    }

    /// Back to the initial state: the world, the cloths, and a fresh build next frame.
    fn reset(&mut self) -> Result<()> {
        self.world.reset();
        for slot in 0..self.poses_staging.len() {
            self.write_poses(slot);
        }
        for c in &self.cloths {
            c.reset()?;
        }
        self.since_build = 0;
        self.schedule = None;
        Ok(())
    }

    fn traceable(&self) -> Traceable<'_> {
        Traceable {
            bvh: &self.bvh,
            geometry: self.mesh.triangles(),
        }
    }

    /// One `sim.rigid` step (timed), its poses written for the next frame's upload
    /// (the world is simulated relative to the renderer's origin already).
    fn step(&mut self, slot: usize) {
        let start = std::time::Instant::now();
        self.world.step();
        self.sim_ms = start.elapsed().as_secs_f64() * 1e3;
        self.write_poses(slot);
    }

    fn write_poses(&mut self, slot: usize) {
        let poses = self.world.poses();
        let bytes: &[u8] = bytemuck::cast_slice(&poses);
        self.poses_staging[slot].mapped_mut().expect("CpuToGpu is mapped")[..bytes.len()].copy_from_slice(bytes);
    }

    /// Records `sim.transform` (the poses copied in first), the cloths' step
    /// (`sim.cloth`), then the dynamic BVH's rebuild or refit, each under its scope.
    fn record(
        &mut self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        slot: usize,
        timer: &mut GpuTimer,
        passes: (&SimTransformPass, &ClothPass, &LbvhBuilder),
    ) {
        let (transform, cloth, builder) = passes;
        if self.vertex_count > 0 {
            timer.scope(cmd, sim_transform::NAME, || {
                // WAR: the previous frame's transform read the poses before they change.
                barrier::global(d, cmd, access::COMPUTE_READ, access::TRANSFER_WRITE);
                let region = vk::BufferCopy::default().size(self.poses.size);
                unsafe { d.cmd_copy_buffer(cmd, self.poses_staging[slot].raw, self.poses.raw, &[region]) };
                // RAW: the transform reads the poses just copied.
                barrier::global(d, cmd, access::TRANSFER_WRITE, access::COMPUTE_READ);
                transform.record(cmd, &self.objects, &self.poses, &self.mesh.vertices, self.vertex_count);
            });
        }
        if !self.cloths.is_empty() {
            timer.scope(cmd, crate::passes::sim_cloth::NAME, || {
                for c in &self.cloths {
                    cloth.record(cmd, c, &self.mesh.vertices);
                }
            });
        }
        // WAR: the previous frame's traversal of the dynamic BVH is done before it changes.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        let t = self.traceable();
        match &self.schedule {
            Some(schedule) if self.refit && self.since_build < self.rebuild_every => {
                builder.record_refit_scheduled(cmd, timer, t.geometry, &self.bvh, schedule);
                self.since_build += 1;
            }
            _ => {
                builder.record_build(cmd, timer, t.geometry, &self.bvh);
                self.since_build = 1;
                self.schedule = None;
            }
        }
    }
}

fn pose_staging(ctx: &Arc<Context>, bytes: u64) -> Result<Buffer> {
    Buffer::new(
        ctx,
        "dynamic.poses_staging",
        bytes,
        vk::BufferUsageFlags::TRANSFER_SRC,
        gpu_allocator::MemoryLocation::CpuToGpu,
    )
}

/// What one frame in flight owns: its timestamp queries and the host's step time.
struct FrameSlot {
    timer: GpuTimer,
    /// Wall-clock milliseconds of the `sim.rigid` step recorded into this slot's frame.
    sim_ms: Option<f64>,
}

impl FrameSlot {
    fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            timer: GpuTimer::new(ctx, SCOPES.len() as u32)?,
            sim_ms: None,
        })
    }
}

/// The scene's textures as one array texture (`scene::texture`): layers of the largest
/// texture's power-of-two size (capped by `texture::LAYER_MAX` and the device), each
/// with its mip chain; one white 1x1 layer when the scene has none.
fn upload_textures(ctx: &Arc<Context>, scene: &Scene) -> Result<Image> {
    let max = texture::LAYER_MAX.min(1 << ctx.limits.max_image_dimension2_d.ilog2());
    let (size, chains) = texture::layers(&scene.textures, max);
    let chains: Vec<Vec<&[u8]>> = chains
        .iter()
        .map(|chain| chain.iter().map(|level| level.as_raw().as_slice()).collect())
        .collect();
    Image::texture_array(ctx, "scene.textures", size, &chains)
}

/// What the frame uniforms are made from besides the settings: the scene's camera,
/// light, sky and bounds (the shadow map's box).
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub camera: Camera,
    pub light: Light,
    pub sky: Sky,
    pub bounds: (Vec3, Vec3),
}

impl View {
    pub fn of(scene: &Scene) -> Self {
        Self {
            camera: scene.camera,
            light: scene.light,
            sky: scene.sky,
            bounds: scene.bounds(),
        }
    }

    /// The same view with the world moved by `-origin`.
    fn relative_to(mut self, origin: Vec3) -> Self {
        self.camera.position -= origin;
        self.camera.target -= origin;
        self.bounds = (self.bounds.0 - origin, self.bounds.1 - origin);
        self
    }
}

/// Where the renderer puts its origin for `scene`: the scene's centre when that is
/// farther from the world origin than the scene's own radius (a model at 1e4 units
/// would lose depth and shadow precision in f32 otherwise), else the world origin (a
/// scene around the origin renders in world coordinates, exactly as given).
pub fn render_origin(scene: &Scene) -> Vec3 {
    let (lo, hi) = scene.bounds();
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    if center.length() > radius.max(1e-6) {
        center
    } else {
        Vec3::ZERO
    }
}

pub struct Renderer {
    ctx: Arc<Context>,
    /// World position of the renderer's origin (`render_origin`): the G-buffer, the
    /// BVHs and `uniforms()` are relative to it.
    origin: Vec3,
    settings: Settings,
    view: View,
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
    /// What moves, when the scene has bodies.
    dynamic: Option<DynamicGeometry>,
    transform: SimTransformPass,
    cloth: ClothPass,
    builder: LbvhBuilder,
    /// One per frame that may be in flight (`set_frames_in_flight`); `render_frame`
    /// uses the first.
    slots: Vec<FrameSlot>,
    /// Paint the fail mask instead of the frame (`set_fail_mask_view`).
    fail_mask_view: bool,
    /// Hold a dynamic scene still (`set_paused`); `step_once` advances one frame.
    paused: bool,
    step_once: bool,
    cmd: vk::CommandBuffer,
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
    view_uniforms(&View::of(scene), settings)
}

fn view_uniforms(v: &View, settings: &Settings) -> FrameUniforms {
    let aspect = settings.width as f32 / settings.height as f32;
    let view_proj = v.camera.view_proj(aspect);
    let (lo, hi) = v.bounds;
    FrameUniforms {
        view_proj,
        inv_view_proj: view_proj.inverse(),
        light_view_proj: light_view_proj(v.light.direction, lo, hi),
        view: v.camera.view(),
        proj: v.camera.projection(aspect),
        camera_pos: v.camera.position.extend(1.0),
        light_dir: v.light.direction.normalize().extend(0.0),
        light_color: (v.light.color * v.light.intensity).extend(0.0),
        sky_zenith: v.sky.zenith.extend(0.0),
        sky_horizon: v.sky.horizon.extend(0.0),
        resolution: [settings.width, settings.height],
        shadow_map_size: settings.shadow_map_size,
        pcf_radius: settings.pcf_radius,
        shadow_bias: settings.shadow_bias,
        exposure: settings.exposure,
        ambient: settings.ambient,
        _pad0: 0.0,
    }
}

fn extent(settings: &Settings) -> vk::Extent2D {
    vk::Extent2D {
        width: settings.width,
        height: settings.height,
    }
}

impl Renderer {
    /// Uploads the scene and creates every pass at the settings' resolution.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: &Settings) -> Result<Self> {
        settings.validate()?;
        scene.validate()?;
        crate::limits::check_frame(ctx, settings)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
        // Every pass works relative to `origin` (see `render_origin`).
        let origin = render_origin(scene);
        let shifted;
        let vertices = if origin == Vec3::ZERO {
            &scene.vertices
        } else {
            shifted = scene
                .vertices
                .iter()
                .map(|v| crate::gpu_types::GpuVertex {
                    position: (Vec3::from(v.position) - origin).to_array(),
                    ..*v
                })
                .collect::<Vec<_>>();
            &shifted
        };
        let vertices = Buffer::with_data(ctx, "scene.vertices", storage, bytemuck::cast_slice(vertices))?;
        let scene_buffers = SceneBuffers {
            mesh: MeshBuffers::new(ctx, "scene", vertices, &scene.uvs, &scene.indices)?,
            materials: Buffer::with_data(ctx, "scene.materials", storage, bytemuck::cast_slice(&materials))?,
            textures: upload_textures(ctx, scene)?,
            texture_sampler: Sampler::trilinear_repeat(ctx, "scene.texture_sampler")?,
        };
        let frame_ubo = Buffer::new(
            ctx,
            "frame.uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        // The static BVH, once: the scene has no dynamic geometry yet.
        let static_bvh = Bvh::new(ctx, scene_buffers.mesh.index_count / 3, MortonBits::Bits30)?;
        let mut build_timer = GpuTimer::new(ctx, 8)?;
        let builder = LbvhBuilder::new(ctx)?;
        ctx.one_shot(|cmd| {
            build_timer.reset(cmd);
            builder.record_build(cmd, &mut build_timer, scene_buffers.mesh.triangles(), &static_bvh);
        })?;
        let static_bvh_build = build_timer.results()?;
        let mut dynamic = if scene.is_dynamic() {
            Some(DynamicGeometry::new(ctx, scene, settings, origin)?)
        } else {
            None
        };
        if let Some(d) = &mut dynamic {
            d.write_poses(0);
        }
        let extent = extent(settings);
        let view = View::of(scene).relative_to(origin);
        Ok(Self {
            origin,
            ctx: ctx.clone(),
            settings: settings.clone(),
            view,
            scene: scene_buffers,
            frame_ubo,
            uniforms: view_uniforms(&view, settings),
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
            dynamic,
            transform: SimTransformPass::new(ctx)?,
            cloth: ClothPass::new(ctx)?,
            builder,
            slots: vec![FrameSlot::new(ctx)?],
            fail_mask_view: false,
            paused: false,
            step_once: false,
            cmd: ctx.allocate_command_buffer()?,
        })
    }

    /// World position of the origin the renderer works relative to.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The uniforms the next frame uses.
    pub fn uniforms(&self) -> &FrameUniforms {
        &self.uniforms
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Renders at a new resolution from the next frame on: every screen-sized image and
    /// list is recreated (the static BVH and the shadow map are kept). Waits for the GPU.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        self.set_settings(Settings {
            width,
            height,
            ..self.settings.clone()
        })
    }

    /// Whether `settings` differ from the current ones in a field only a new renderer
    /// can apply: the time step and BVH policy of a dynamic scene (its simulation is
    /// made with them). Every other field `set_settings` applies in place.
    pub fn needs_new_renderer(&self, settings: &Settings) -> bool {
        let s = &self.settings;
        self.is_dynamic()
            && (s.sim_dt != settings.sim_dt
                || s.cloth_rebuild != settings.cloth_rebuild
                || s.refit_rebuild_every != settings.refit_rebuild_every)
    }

    /// Applies `settings` from the next frame on, after checking them (nothing changes
    /// when they are refused): a new resolution recreates every screen-sized image and
    /// list, a new shadow-map size or slope bias the shadow map (both wait for the
    /// GPU); the other fields are read as each frame is recorded. The fields of
    /// `needs_new_renderer` are refused here.
    pub fn set_settings(&mut self, settings: Settings) -> Result<()> {
        settings.validate()?;
        crate::limits::check_frame(&self.ctx, &settings)?;
        if self.needs_new_renderer(&settings) {
            return Err(crate::Error::Settings(
                "sim_dt, cloth_rebuild and refit_rebuild_every of a dynamic scene need a new renderer".into(),
            ));
        }
        let old = &self.settings;
        if (old.width, old.height) != (settings.width, settings.height) {
            unsafe { self.ctx.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
            let e = extent(&settings);
            self.gbuffer.resize(e)?;
            self.light.resize(e)?;
            self.ssr.resize(e)?;
            self.compact.resize(e)?;
            self.rt.resize(e)?;
            self.merge.resize(e)?;
            self.compose.resize(e)?;
        }
        if (old.shadow_map_size, old.shadow_slope_bias) != (settings.shadow_map_size, settings.shadow_slope_bias) {
            unsafe { self.ctx.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
            self.shadow =
                shadow_map::ShadowMapPass::new(&self.ctx, settings.shadow_map_size, settings.shadow_slope_bias)?;
        }
        self.settings = settings;
        self.uniforms = view_uniforms(&self.view, &self.settings);
        Ok(())
    }

    /// The camera, in world space.
    pub fn camera(&self) -> Camera {
        let mut c = self.view.camera;
        c.position += self.origin;
        c.target += self.origin;
        c
    }

    /// Views the scene through `camera` (world space) from the next frame on.
    pub fn set_camera(&mut self, camera: Camera) {
        self.view.camera = Camera {
            position: camera.position - self.origin,
            target: camera.target - self.origin,
            ..camera
        };
        self.uniforms = view_uniforms(&self.view, &self.settings);
    }

    /// Paints each reflective pixel by its fail-mask reason instead of the frame (as
    /// `--fail-mask` images do), in the modes that reflect; `raster` has no fail mask
    /// and is shown as it is.
    pub fn set_fail_mask_view(&mut self, on: bool) {
        self.fail_mask_view = on;
    }

    /// Whether the fail-mask view is on (`set_fail_mask_view`).
    pub fn fail_mask_view(&self) -> bool {
        self.fail_mask_view
    }

    /// Frames that may be in flight at once (the demo's 2): each gets its own
    /// timestamp queries and pose staging, indexed by `slot` in `record_frame`.
    pub fn set_frames_in_flight(&mut self, n: usize) -> Result<()> {
        let n = n.max(1);
        unsafe { self.ctx.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
        self.slots.truncate(n);
        while self.slots.len() < n {
            self.slots.push(FrameSlot::new(&self.ctx)?);
        }
        if let Some(d) = &mut self.dynamic {
            d.poses_staging.truncate(n);
            while d.poses_staging.len() < n {
                d.poses_staging.push(pose_staging(&self.ctx, d.poses.size)?);
            }
        }
        Ok(())
    }

    /// Whether the scene moves (has bodies): each frame then advances it by `sim_dt`.
    pub fn is_dynamic(&self) -> bool {
        self.dynamic.is_some()
    }

    /// Time steps the dynamic scene has taken since its initial state (0 for a static one).
    pub fn sim_steps(&self) -> u64 {
        self.dynamic.as_ref().map_or(0, |d| d.world.steps())
    }

    /// Triangles of the dynamic geometry (0 for a static scene).
    pub fn dynamic_triangles(&self) -> u32 {
        self.dynamic.as_ref().map_or(0, |d| d.bvh.tri_count)
    }

    /// The dynamic BVH and the world-space geometry it was built over in the last
    /// frame (relative to `origin()`), for tracing it apart (tests, benchmarks).
    pub fn dynamic_traceable(&self) -> Option<Traceable<'_>> {
        self.dynamic.as_ref().map(|d| d.traceable())
    }

    /// The last frame's world-space dynamic vertices (relative to `origin()`), read back.
    pub fn read_dynamic_vertices(&self) -> Result<Option<Vec<crate::gpu_types::GpuVertex>>> {
        self.dynamic
            .as_ref()
            .map(|d| Ok(bytemuck::pod_collect_to_vec(&d.mesh.vertices.read()?)))
            .transpose()
    }

    /// Puts a dynamic scene back to its initial state: the next frame is its first
    /// time step again. Nothing changes for a static scene.
    pub fn reset_simulation(&mut self) -> Result<()> {
        if let Some(d) = &mut self.dynamic {
            unsafe { self.ctx.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
            d.reset()?;
        }
        Ok(())
    }

    /// Records, submits and waits for one frame; returns its time per scope (ms) with
    /// their self-check against the wall clock from submit to fence. A dynamic scene
    /// first advances by one time step (`sim.rigid`, CPU wall clock): frame k after a
    /// reset shows the world at time (k + 1) x `sim_dt`.
    pub fn render_frame(&mut self) -> Result<TimerReadout> {
        let device = self.ctx.device.clone();
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe {
            device
                .reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            device
                .begin_command_buffer(self.cmd, &begin)
                .vk("vkBeginCommandBuffer")?;
        }
        self.record_frame(self.cmd, 0);
        unsafe { device.end_command_buffer(self.cmd) }.vk("vkEndCommandBuffer")?;
        let submitted = std::time::Instant::now();
        self.ctx.submit_and_wait(self.cmd)?;
        let wall = Wall {
            ms: submitted.elapsed().as_secs_f64() * 1e3,
            tight: self.ctx.device_type == vk::PhysicalDeviceType::CPU,
        };
        self.read_frame(0, Some(wall))
    }

    /// Records one frame into `cmd` (begun, not ended), with frame slot `slot`'s
    /// queries and staging: a dynamic scene first advances by one time step. The
    /// caller submits it, and must have seen the slot's previous frame finish (a
    /// fence) before; several slots' frames may be in flight on the queue at once.
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, slot: usize) {
        let advance = !self.paused || std::mem::take(&mut self.step_once);
        if let Some(d) = &mut self.dynamic {
            if advance {
                // The slot's previous frame has finished: nothing reads its staging poses.
                d.step(slot);
                self.slots[slot].sim_ms = Some(d.sim_ms);
            }
        }
        self.record(cmd, slot, advance);
    }

    /// Holds a dynamic scene still from the next frame on (its geometry and BVH stay
    /// as the last frame left them), or lets it move again.
    pub fn set_paused(&mut self, paused: bool) {
        self.paused = paused;
    }

    /// Whether the dynamic scene is held still.
    pub fn paused(&self) -> bool {
        self.paused
    }

    /// While paused, advances the next frame by one time step.
    pub fn step_once(&mut self) {
        self.step_once = true;
    }

    /// After the frame recorded with `slot` has finished on the GPU: its time per
    /// scope (ms), self-checked without a wall clock (the window's frames overlap). The
    /// first frame after a rebuild of a refit BVH also makes the refit schedule here,
    /// from the built tree (waiting for the GPU: every frame recorded without a
    /// schedule rebuilds, so the tree then is the last one built).
    pub fn frame_finished(&mut self, slot: usize) -> Result<TimerReadout> {
        self.read_frame(slot, None)
    }

    fn read_frame(&mut self, slot: usize, wall: Option<Wall>) -> Result<TimerReadout> {
        if let Some(d) = &mut self.dynamic {
            if d.refit && d.schedule.is_none() {
                unsafe { self.ctx.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
                d.schedule = Some(RefitSchedule::of(&self.ctx, &d.bvh)?);
            }
        }
        let s = &mut self.slots[slot];
        let mut times = s.timer.read(wall)?;
        if let Some(ms) = s.sim_ms.take() {
            times.scopes.push((SIM_RIGID, ms));
        }
        Ok(times)
    }

    /// Records one frame into `cmd`: DESIGN.md's frame table, pass by pass.
    fn record(&mut self, cmd: vk::CommandBuffer, slot: usize, advance: bool) {
        let Self {
            ctx,
            settings: st,
            scene,
            frame_ubo: ubo,
            uniforms,
            shadow,
            gbuffer,
            light,
            ssr,
            compact,
            rt,
            merge,
            compose,
            static_bvh,
            dynamic,
            transform,
            cloth,
            builder,
            slots,
            fail_mask_view,
            ..
        } = self;
        let timer = &mut slots[slot].timer;
        let (d, mode, g) = (&ctx.device, st.mode, &gbuffer.targets);
        timer.reset(cmd);
        timer.begin(cmd, FRAME);
        timer.scope(cmd, UNIFORMS, || upload_uniforms(d, cmd, ubo, uniforms));
        if let Some(dy) = dynamic.as_mut().filter(|_| advance) {
            dy.record(d, cmd, slot, timer, (transform, cloth, builder));
        }
        let dynamic = dynamic.as_ref();
        let geometries: Vec<SceneGeometry<'_>> = std::iter::once(scene.mesh.geometry())
            .chain(dynamic.map(|dy| dy.mesh.geometry()))
            .collect();
        timer.scope(cmd, shadow_map::NAME, || shadow.record(cmd, ubo, &geometries));
        let surfaces = scene.surfaces(dynamic);
        timer.scope(cmd, gbuffer::NAME, || gbuffer.record(cmd, ubo, &surfaces, &geometries));
        timer.scope(cmd, light_direct::NAME, || {
            light.record(cmd, ubo, g, &shadow.map, &scene.materials)
        });
        let params = SsrParams::from_settings(st);
        if mode.reflects() {
            let mask_only = !mode.marches();
            timer.scope(cmd, ssr_trace::CLASSIFY_NAME, || {
                ssr.classify(cmd, ubo, g, &params, mask_only)
            });
        }
        if mode.marches() {
            timer.scope(cmd, ssr_trace::NAME, || {
                ssr.trace(cmd, ubo, g, &light.lit, &scene.materials, &params)
            });
        }
        if mode.traces() {
            timer.scope(cmd, ssr_compact::NAME, || compact.record(cmd, &ssr.out.mask));
            let inputs = ReflectInputs {
                frame: ubo,
                gbuffer: g,
                surfaces,
                shadow_map: &shadow.map,
                list: &compact.out,
                scene: TraceScene {
                    static_bvh: Some(Traceable {
                        bvh: static_bvh,
                        geometry: scene.mesh.triangles(),
                    }),
                    dynamic_bvh: dynamic.map(|dy| dy.traceable()),
                },
            };
            timer.scope(cmd, rt_reflect::NAME, || {
                rt.record(cmd, &inputs, st.max_bounces, st.shadow_rays)
            });
        }
        if mode.reflects() {
            // Seams exist only where both sources do.
            let blur = BlurParams {
                radius: if mode.has_seams() { st.blur_radius } else { 0 },
                band: st.blur_band,
            };
            let (mask, ssr_color) = (&ssr.out.mask, &ssr.out.color);
            timer.scope(cmd, reflect_merge::NAME, || {
                let traced = mode.traces();
                merge.record(cmd, ubo, g, mask, ssr_color, &rt.color, traced, st.reflective_min, blur)
            });
        }
        let inputs = ComposeInputs {
            frame: ubo,
            hdr: &light.lit,
            reflection: merge.reflection(),
            gbuffer: g,
            materials: &scene.materials,
            fail_mask: &ssr.out.mask,
            reflective_min: st.reflective_min,
        };
        let compose_mode = match mode {
            Mode::Raster => ComposeMode::Plain,
            _ if *fail_mask_view => ComposeMode::FailMask,
            Mode::Provenance => ComposeMode::Provenance,
            Mode::Ssr | Mode::Hybrid | Mode::Rt => ComposeMode::Reflect,
        };
        timer.scope(cmd, compose::NAME, || {
            compose.record(cmd, &inputs, st.exposure, compose_mode)
        });
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
        Ok(ReflectionMaps {
            reflective,
            mask,
            traced: self.settings.mode.traces(),
        })
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

/// Writes this frame's uniforms: spans passes, since every pass reads them.
fn upload_uniforms(d: &ash::Device, cmd: vk::CommandBuffer, ubo: &Buffer, uniforms: &FrameUniforms) {
    // WAR: the previous frame's shader reads of the uniforms finish before they change.
    barrier::global(d, cmd, access::ANY_SHADER_READ, access::TRANSFER_WRITE);
    unsafe { d.cmd_update_buffer(cmd, ubo.raw, 0, bytemuck::bytes_of(uniforms)) };
    // RAW: every pass below reads the uniforms just written.
    barrier::global(d, cmd, access::TRANSFER_WRITE, access::ANY_SHADER_READ);
}

impl Drop for Renderer {
    fn drop(&mut self) {
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
        self.ctx.free_command_buffer(self.cmd);
    }
}
