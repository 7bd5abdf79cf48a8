//! Owns the passes and the scene on the GPU, and records frames (`table.rs`: the frame
//! table as data; `plan.rs`: each frame's decisions; `frame.rs`: the function that
//! records the plan's rows; `view.rs`: camera, light and origin maths; `gpu_scene.rs`:
//! the scene's buffers and the moving geometry; `tracer.rs`: the tracer's kernels and
//! structures as one value; `passes.rs`: the screen passes in two groups, each made and
//! resized in one place).
//!
//! Frame: `uniforms` → (a dynamic scene: `sim.rigid` on the CPU, `sim.transform`,
//! `sim.cloth`, the dynamic BVH's `lbvh.*`) → `shadow.map` (unless the shadows are
//! `rays`) → `gbuffer` → (shadows `rays` or `hybrid`) `shadow.classify` →
//! `shadow.compact` → `shadow.trace` → `light.direct` → (by mode) `ssr.hiz` → `ssr.classify` → `ssr.trace` → `ssr.compact` →
//! `rt.reflect` → `reflect.merge` → `reflect.denoise` → `compose`. The static BVH is built once, when the
//! renderer is created; the dynamic one every frame, over that frame's geometry.
//!
//! Frames in flight: `render_frame` submits and waits (the headless path);
//! `record_frame` records into a caller's command buffer with a frame slot (its own
//! timestamp queries and pose staging) and `frame_finished` reads the slot back after
//! the caller's fence, so several frames can be on the queue at once (the demo's two).
//! The screen-sized images are shared by all slots: each pass's entry barriers order
//! a frame after the one submitted before it on the queue.

mod adaptive;
pub mod exchange;
mod frame;
mod gpu_scene;
mod passes;
pub mod plan;
mod readback;
pub mod stages;
pub mod static_tree;
pub mod table;
mod tracer;
mod view;

pub use exchange::PROBE_EVERY;
pub use table::{Row, FRAME, RECHECK, SCOPES, SIM_RIGID, UNIFORMS};
pub use view::{frame_uniforms, render_origin, View};

use crate::error::Result;
use crate::gpu_types::FrameUniforms;
use crate::passes::compose::ComposePass;
use crate::passes::rt_trace::TracePass;
use crate::passes::sim_cloth::ClothPass;
use crate::passes::sim_skin::SimSkinPass;
use crate::passes::sim_transform::SimTransformPass;
use crate::scene::{Camera, Scene};
use crate::settings::{self, Applies, Mode, Settings};
use crate::tracers::lbvh::{Bvh, LbvhBuilder, MortonBits};
use crate::tracers::Traceable;
use crate::vk::{Buffer, Context, GpuTimer, TimerReadout, Wall};
use ash::vk;
use exchange::{ExchangeRate, FrameCounts, Path, Paths};
use glam::Vec3;
use gpu_scene::{DynamicGeometry, SceneBuffers};
pub use passes::{Lighting, Reflections};
use plan::FramePlan;
use stages::{Stages, Taken};
use std::sync::Arc;
use tracer::FrameTracer;

/// What one frame in flight owns: its timestamp queries and the host's step time.
struct FrameSlot {
    timer: GpuTimer,
    /// Wall-clock milliseconds of the `sim.rigid` step recorded into this slot's frame.
    sim_ms: Option<f64>,
    /// A hybrid frame's path and counts, for the exchange rate and the paths' prices.
    counts: FrameCounts,
    /// The ways the frame took in its adaptive stages, for their prices.
    taken: Taken,
}

impl FrameSlot {
    fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            timer: GpuTimer::new(ctx, SCOPES.len() as u32)?,
            sim_ms: None,
            counts: FrameCounts::new(ctx)?,
            taken: Taken::default(),
        })
    }
}

fn extent(settings: &Settings) -> vk::Extent2D {
    vk::Extent2D {
        width: settings.width,
        height: settings.height,
    }
}

/// The glossy rays' sample stream of a reference renderer (`Renderer::reference`).
const REFERENCE_STREAM: u32 = 1;

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
    /// Frames recorded so far: the glossy rays' sample index advances with it.
    frame_index: u32,
    /// The glossy rays' sample stream: 0, or `REFERENCE_STREAM` (`Renderer::reference`).
    sample_stream: u32,
    /// `shadow.map` to `light.direct` (`passes.rs`).
    pub lighting: Lighting,
    /// `ssr.hiz` to `reflect.denoise` (`passes.rs`).
    pub reflections: Reflections,
    pub compose: ComposePass,
    /// BVH over the scene's (static) triangles, built at creation.
    pub static_bvh: Bvh,
    /// GPU milliseconds per stage of the static BVH build (of the tree kept).
    pub static_bvh_build: Vec<(&'static str, f64)>,
    /// With `static_ploc`: PLOC's tree or the LBVH's, whichever walked `static_rays`
    /// faster (`static_tree`).
    pub static_tree: Option<static_tree::StaticTreeChoice>,
    /// With `static_layout = fastest`: the static walk's nodes that walked
    /// `static_rays` fastest (`static_tree::choose_layout`).
    pub static_layout: Option<static_tree::StaticLayoutChoice>,
    /// The reflection and shadow rays of the scene camera's view at load, relative to
    /// the render origin (`static_tree::frame_rays`): what the choice of its tree
    /// times, again when the static BVH is rebuilt.
    static_rays: static_tree::ChoiceRays,
    /// The tracer's kernels and, for the vendor tracer, its acceleration structures.
    tracer: FrameTracer,
    /// What moves, when the scene has bodies.
    dynamic: Option<DynamicGeometry>,
    transform: SimTransformPass,
    cloth: ClothPass,
    skin: SimSkinPass,
    builder: LbvhBuilder,
    /// One per frame that may be in flight (`set_frames_in_flight`); `render_frame`
    /// uses the first.
    slots: Vec<FrameSlot>,
    /// Paint the fail mask instead of the frame (`set_fail_mask_view`).
    fail_mask_view: bool,
    /// Hold a dynamic scene still (`set_paused`); `step_once` advances one frame.
    paused: bool,
    step_once: bool,
    /// The adaptive hybrid's exchange rate, measured from the hybrid frames.
    exchange: ExchangeRate,
    /// The adaptive hybrid's paths: marching with the tiles, or idle (tracing every
    /// pixel) until the next probe frame; and what each has cost.
    paths: Paths,
    /// `visibility` and `shadows = adaptive`: their ways and prices.
    stages: Stages,
    /// The last recorded frame's plan (its adaptive stages' ways among it).
    last_plan: Option<FramePlan>,
    cmd: vk::CommandBuffer,
}

impl Renderer {
    /// Uploads the scene and creates every pass at the settings' resolution.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: &Settings) -> Result<Self> {
        settings.validate()?;
        scene.validate()?;
        crate::limits::check_frame(ctx, settings)?;
        tracer::check(ctx, settings)?;
        // Every pass works relative to `origin` (see `render_origin`).
        let origin = render_origin(scene);
        let scene_buffers = SceneBuffers::upload(ctx, scene, origin)?;
        let frame_ubo = Buffer::new(
            ctx,
            "frame.uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        // The static BVH, once: the scene has no dynamic geometry yet.
        let tris = scene_buffers.mesh.index_count / 3;
        let static_bvh = Bvh::new_static_in(ctx, tris, MortonBits::Bits30, static_tree::layout(settings))?;
        let builder = LbvhBuilder::new(ctx)?;
        let geom = scene_buffers.mesh.triangles();
        let built = builder.build_now(geom, &static_bvh, static_tree::kind(settings))?;
        // One trace kernel for the view's rays and the choice's rounds.
        let trace = TracePass::<crate::tracers::Lbvh>::new(ctx)?;
        let static_rays = static_tree::frame_rays(ctx, &trace, geom, &static_bvh, scene, settings, origin)?;
        let (static_bvh, static_bvh_build, static_tree, static_layout) = static_tree::choose(
            ctx,
            (&builder, &trace),
            geom,
            (static_bvh, built),
            settings,
            &static_rays,
        )?;
        let dynamic = if scene.is_dynamic() {
            Some(DynamicGeometry::new(ctx, scene, settings, origin)?)
        } else {
            None
        };
        let tracer = FrameTracer::new(ctx, &scene_buffers, dynamic.as_ref(), settings, 1)?;
        let extent = extent(settings);
        let view = View::of(scene).relative_to(origin);
        Ok(Self {
            origin,
            ctx: ctx.clone(),
            settings: settings.clone(),
            view,
            scene: scene_buffers,
            frame_ubo,
            uniforms: view.uniforms(settings),
            frame_index: 0,
            sample_stream: 0,
            lighting: Lighting::new(ctx, settings, extent)?,
            reflections: Reflections::new(ctx, extent)?,
            compose: ComposePass::new(ctx, extent)?,
            static_bvh,
            static_bvh_build,
            static_tree,
            static_layout,
            static_rays,
            tracer,
            dynamic,
            transform: SimTransformPass::new(ctx)?,
            cloth: ClothPass::new(ctx)?,
            skin: SimSkinPass::new(ctx)?,
            builder,
            slots: vec![FrameSlot::new(ctx)?],
            fail_mask_view: false,
            paused: false,
            exchange: ExchangeRate::default(),
            paths: Paths::default(),
            stages: Stages::default(),
            last_plan: None,
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
    /// can apply (`Applies::NewRenderer` in the settings table: the time step and BVH
    /// policy of a dynamic scene, whose simulation is made with them). Every other
    /// field `set_settings` applies in place.
    pub fn needs_new_renderer(&self, settings: &Settings) -> bool {
        self.is_dynamic() && !self.settings.changed(settings, Applies::NewRenderer).is_empty()
    }

    /// Applies `settings` from the next frame on, after checking them (nothing changes
    /// when they are refused), as the settings table says of each field that changed:
    /// `Resize` recreates every screen-sized image and list, `ShadowMap` the shadow
    /// map (both wait for the GPU); `NextFrame` fields are read as each frame is
    /// recorded. The fields of `needs_new_renderer` are refused here.
    pub fn set_settings(&mut self, settings: Settings) -> Result<()> {
        settings.validate()?;
        crate::limits::check_frame(&self.ctx, &settings)?;
        tracer::check(&self.ctx, &settings)?;
        if self.needs_new_renderer(&settings) {
            let fields = self.settings.changed(&settings, Applies::NewRenderer).join(", ");
            return Err(crate::Error::Settings(format!(
                "{fields} of a dynamic scene need a new renderer"
            )));
        }
        let old = &self.settings;
        if !old.changed(&settings, Applies::Resize).is_empty() {
            self.ctx.wait_idle()?;
            let e = extent(&settings);
            self.lighting.resize(e)?;
            self.reflections.resize(e)?;
            self.compose.resize(e)?;
            // A new size starts the glossy rays' sequence over, as a fresh renderer's.
            self.frame_index = 0;
        }
        if !old.changed(&settings, Applies::StaticBvh).is_empty() {
            // WAR: frames in flight still walk the old tree.
            self.ctx.wait_idle()?;
            let tris = self.scene.mesh.index_count / 3;
            let fresh = Bvh::new_static_in(&self.ctx, tris, MortonBits::Bits30, static_tree::layout(&settings))?;
            let geom = self.scene.mesh.triangles();
            let built = static_tree::build(&self.ctx, &self.builder, geom, fresh, &settings, &self.static_rays)?;
            (
                self.static_bvh,
                self.static_bvh_build,
                self.static_tree,
                self.static_layout,
            ) = built;
        }
        if !old.changed(&settings, Applies::Tracer).is_empty() {
            self.ctx.wait_idle()?;
            self.set_tracer(&settings)?;
        }
        let old = &self.settings;
        if !old.changed(&settings, Applies::ShadowMap).is_empty() {
            self.ctx.wait_idle()?;
            self.lighting.shadow = Lighting::shadow_map(&self.ctx, &settings)?;
        }
        // Other settings, other costs: the adaptive hybrid prices its paths anew.
        if settings != self.settings {
            self.paths = Paths::default();
            self.stages = Stages::default();
        }
        self.settings = settings;
        self.uniforms = self.view.uniforms(&self.settings);
        Ok(())
    }

    /// Makes the tracing kernels and structures for `settings.tracer` (the GPU idle),
    /// with as many instance buffers as frames may be in flight.
    fn set_tracer(&mut self, settings: &Settings) -> Result<()> {
        let (scene, dynamic, slots) = (&self.scene, self.dynamic.as_ref(), self.slots.len());
        self.tracer = FrameTracer::new(&self.ctx, scene, dynamic, settings, slots)?;
        Ok(())
    }

    /// The tracer frames trace with (the one `settings.tracer` chose).
    pub fn tracer(&self) -> settings::Tracer {
        self.tracer.setting()
    }

    /// The `rt` reference of `settings` (`Settings::glossy_reference`: with glossy
    /// reflections `spp` rays per glossy pixel and no denoiser, the glossy ground truth),
    /// drawing its glossy rays from a sample stream of its own, so that its samples are
    /// independent of those of the frames it judges (which draw from stream 0).
    pub fn reference(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, spp: u32) -> Result<Self> {
        let mut r = Self::new(ctx, scene, &settings.glossy_reference(spp))?;
        r.sample_stream = REFERENCE_STREAM;
        Ok(r)
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
        self.uniforms = self.view.uniforms(&self.settings);
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
        self.ctx.wait_idle()?;
        self.slots.truncate(n);
        while self.slots.len() < n {
            self.slots.push(FrameSlot::new(&self.ctx)?);
        }
        if let Some(d) = &mut self.dynamic {
            d.set_slots(n)?;
        }
        if let Some(k) = self.tracer.khr_mut() {
            k.set_slots(n)?;
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

    /// The animation's time (seconds) of the last frame rendered, if the scene has an
    /// animated model.
    pub fn animation_time(&self) -> Option<f32> {
        self.dynamic.as_ref().and_then(|d| d.animation_time())
    }

    /// The index of the next frame to be recorded.
    pub fn frame_index(&self) -> u32 {
        self.frame_index
    }

    /// Triangles of the dynamic geometry (0 for a static scene).
    pub fn dynamic_triangles(&self) -> u32 {
        self.dynamic.as_ref().map_or(0, |d| d.bvh.bvh.tri_count)
    }

    /// The static BVH and the scene's triangles (relative to `origin()`), for tracing
    /// them apart (tests, benchmarks).
    pub fn static_traceable(&self) -> Traceable<'_> {
        Traceable {
            bvh: &self.static_bvh,
            geometry: self.scene.mesh.triangles(),
        }
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
    /// time step again; the glossy rays' sequence and the denoiser's history start over
    /// (for a static scene, only they).
    pub fn reset_simulation(&mut self) -> Result<()> {
        if let Some(d) = &mut self.dynamic {
            self.ctx.wait_idle()?;
            d.reset()?;
        }
        if let Some(k) = self.tracer.khr_mut() {
            k.reset();
        }
        // The glossy rays' sequence, the denoiser's history and the adaptive hybrid's
        // tiles start over with it, so frame k is the same image whatever came before.
        self.frame_index = 0;
        self.reflections.denoise.reset_history();
        self.reflections.ssr.reset_tiles();
        // The paths' prices are the device's and the view's: kept.
        self.paths = Paths {
            next: Path::March,
            frames: [0; 3],
            probes: 0,
            probe_every: exchange::PROBE_EVERY,
            last_march: 0,
            ..self.paths
        };
        Ok(())
    }

    /// Records, submits and waits for one frame; returns its time per scope (ms) with
    /// their self-check against the wall clock from submit to fence. A dynamic scene
    /// first advances by one time step (`sim.rigid`, CPU wall clock): frame k after a
    /// reset shows the world at time (k + 1) x `sim_dt`.
    pub fn render_frame(&mut self) -> Result<TimerReadout> {
        let (ctx, cmd) = (self.ctx.clone(), self.cmd);
        ctx.rerecord(cmd, |cmd| self.record_frame(cmd, 0))?;
        let submitted = std::time::Instant::now();
        self.ctx.submit_and_wait(self.cmd)?;
        let wall = Wall {
            ms: submitted.elapsed().as_secs_f64() * 1e3,
            tight: self.ctx.device_type == vk::PhysicalDeviceType::CPU,
        };
        self.read_frame(0, Some(wall))
    }

    /// `render_frame` for a measurement: a static scene's frame (the same work every
    /// time) is rendered again while its readout fails the self-check (`remeasure`),
    /// as the same frame (its glossy samples and the denoiser's history as at the first
    /// try, so the image does not depend on how busy the machine was); a dynamic
    /// scene's frame advances the world, so it is measured once. Returns the readout
    /// and how many failed readouts were discarded before it.
    pub fn render_frame_measured(&mut self) -> Result<(TimerReadout, u32)> {
        if self.is_dynamic() {
            return Ok((self.render_frame()?, 0));
        }
        let (index, history, tiles) = (
            self.frame_index,
            self.reflections.denoise.sequence(),
            self.reflections.ssr.tile_sequence(),
        );
        let paths = self.paths;
        crate::vk::remeasure_readout(|| {
            self.frame_index = index;
            self.paths = paths;
            self.reflections.denoise.restore(history);
            self.reflections.ssr.restore_tiles(tiles);
            self.render_frame()
        })
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
        // The dynamic BVH's refit schedule reads its first build back (the LBVH's only:
        // the vendor tracer's structures keep their own).
        let own_tracer = matches!(self.tracer, FrameTracer::Lbvh(_));
        if let Some(d) = self.dynamic.as_mut().filter(|_| own_tracer) {
            d.bvh.after_frame()?;
        }
        let s = &mut self.slots[slot];
        let mut times = s.timer.read(wall)?;
        if let Some(ms) = s.sim_ms.take() {
            times.scopes.push((SIM_RIGID, ms));
        }
        if let Some(recorded) = s.counts.take() {
            let scopes = table::reflection_rows().iter().flat_map(|r| r.scopes().iter().copied());
            exchange::take_frame((&mut self.exchange, &mut self.paths), recorded, &times, (FRAME, scopes));
        }
        self.stages.take(std::mem::take(&mut s.taken), &times);
        Ok(times)
    }

    /// Switches the reflection mode for the next frames (for reference renders).
    pub fn set_mode(&mut self, mode: Mode) {
        self.settings.mode = mode;
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        self.ctx.free_command_buffer(self.cmd);
    }
}
