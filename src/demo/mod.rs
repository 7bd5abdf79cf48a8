//! `speculum demo`: the window. A winit window with a swapchain; each frame the same
//! `Renderer` the headless path uses records its passes into the frame slot's command
//! buffer, the result is blitted into the swapchain image and the HUD (egui) drawn
//! over it. Two frames are in flight: each slot has its command buffer, fence and
//! "image acquired" semaphore (`vk::FrameSync`), and the renderer its timestamp
//! queries and pose staging (`Renderer::set_frames_in_flight`); each swapchain image
//! has its "rendered" semaphore (`vk::Swapchain`).
//!
//! Keys, mouse and scripts go through one set of `Action`s and one settings path
//! (`Demo::apply_settings`), so what a script does is what a person does.

pub mod camera;
pub mod hud;
pub mod script;

use crate::error::{Error, Result};
use crate::reflection_maps::ReflectionStats;
use crate::scene::Scene;
use crate::settings::{Mode, Settings};
use crate::vk::swapchain::{self, present_mode_name};
use crate::vk::{Acquired, Buffer, Context, ContextDesc, FrameSync, Swapchain, WindowHandles};
use crate::Renderer;
use ash::vk;
use camera::FlyCamera;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use script::{Action, Step};
use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Frames in flight.
pub const FRAMES_IN_FLIGHT: usize = 2;
/// Frames between readbacks of the reflection counts (each waits for the GPU).
const STATS_EVERY: u64 = 30;

/// What `demo` runs.
pub struct DemoConfig {
    pub scene: Scene,
    /// How `render --scene` names it, for the "reproduce this view" line.
    pub scene_name: String,
    pub settings: Settings,
    pub validation: bool,
    pub device: Option<String>,
    pub present_mode: vk::PresentModeKHR,
    /// Steps to run (a script, or `--frames N --screenshot F`); empty: a person drives.
    pub script: Vec<Step>,
    /// Folder for `P` screenshots and "save settings".
    pub out_dir: PathBuf,
    /// Print a line per script step and the resize times.
    pub verbose: bool,
}

/// What a demo run did, for its caller and tests.
#[derive(Debug, Default)]
pub struct Summary {
    pub frames: u64,
    pub skipped: u64,
    /// Swapchain recreations and how long each took (with the renderer's resize), ms.
    pub recreate_ms: Vec<f64>,
    /// Median GPU frame ms per mode, over the frames rendered in it.
    pub mode_frame_ms: BTreeMap<&'static str, Vec<f64>>,
    pub validation_messages: u32,
}

/// Opens the window and runs the demo until Esc, the window's close button, or the
/// end of the script.
pub fn run(config: DemoConfig) -> Result<Summary> {
    let event_loop = EventLoop::new().map_err(|e| {
        Error::Window(format!(
            "cannot open a window: {e} (no X11 or Wayland display? set DISPLAY, or run under xvfb-run)"
        ))
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        config: Some(config),
        demo: None,
        result: Ok(Summary::default()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Window(format!("event loop: {e}")))?;
    app.result
}

struct App {
    config: Option<DemoConfig>,
    demo: Option<Demo>,
    result: Result<Summary>,
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        self.finish(el);
    }

    fn finish(&mut self, el: &ActiveEventLoop) {
        if let Some(demo) = self.demo.take() {
            let summary = demo.close();
            if let Ok(s) = &mut self.result {
                *s = summary;
            }
        }
        el.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if let Some(config) = self.config.take() {
            match Demo::new(el, config) {
                Ok(d) => self.demo = Some(d),
                Err(e) => self.fail(el, e),
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(demo) = &mut self.demo else { return };
        match demo.on_window_event(event) {
            Ok(true) => {}
            Ok(false) => self.finish(el),
            Err(e) => self.fail(el, e),
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(demo) = &mut self.demo else { return };
        match demo.tick() {
            Ok(true) => {
                // A minimized window renders nothing: wake up now and then for the script.
                if demo.minimized() {
                    el.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(16)));
                } else {
                    el.set_control_flow(ControlFlow::Poll);
                }
            }
            Ok(false) => self.finish(el),
            Err(e) => self.fail(el, e),
        }
    }

    fn exiting(&mut self, el: &ActiveEventLoop) {
        self.finish(el);
    }
}

/// What the demo keeps per frame in flight (`FrameSync` has its Vulkan side).
struct Slot {
    /// A frame was submitted with this slot and its timings not read yet.
    pending: bool,
    /// The mode it was rendered in (for the per-mode frame times).
    mode: Mode,
    /// egui textures to free once this slot's frame is done.
    free: Vec<egui::TextureId>,
}

struct Hud {
    ctx: egui::Context,
    state: egui_winit::State,
    renderer: egui_ash_renderer::Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
    visible: bool,
}

/// The running demo. Fields drop in order: everything Vulkan before the context,
/// the context (and its surface) before the window.
struct Demo {
    renderer: Renderer,
    hud: Hud,
    swapchain: Option<Swapchain>,
    sync: FrameSync,
    slots: Vec<Slot>,
    ctx: Arc<Context>,
    window: Window,

    scene: Scene,
    scene_name: String,
    camera: FlyCamera,
    present_mode: vk::PresentModeKHR,
    present_modes: Vec<vk::PresentModeKHR>,
    follow_window: bool,
    /// The window is minimized (by the window system, or by a script's `minimize`
    /// where the window system ignores it, as X servers without a window manager do).
    minimized: bool,
    recreate: bool,
    frame: u64,
    last_frame: Instant,
    /// GPU frame ms and wall-clock frame interval ms, and each frame's passes.
    gpu_ms: VecDeque<f64>,
    wall_ms: VecDeque<f64>,
    passes: VecDeque<Vec<(&'static str, f64)>>,
    stats: Option<ReflectionStats>,
    /// A frame was submitted since the renderer's images were last made (the counts
    /// read them).
    rendered_since_change: bool,
    compare: Option<(f64, f64, Mode)>,
    message: String,
    looking: Option<(f64, f64)>,
    cursor: (f64, f64),
    script: VecDeque<Step>,
    waiting: u32,
    scripted: bool,
    out_dir: PathBuf,
    screenshots: u32,
    verbose: bool,
    summary: Summary,
    quit: bool,
    /// A window shot asked for: copied out of the next drawn frame.
    window_shot: Option<PathBuf>,
    /// The copy in flight: its path, buffer, size and slot.
    shot_copy: Option<(PathBuf, Buffer, vk::Extent2D, usize)>,
}

fn window_size(window: &Window) -> (u32, u32) {
    let s = window.inner_size();
    (s.width, s.height)
}

impl Demo {
    fn new(el: &ActiveEventLoop, config: DemoConfig) -> Result<Self> {
        let s = &config.settings;
        let attrs = Window::default_attributes()
            .with_title(format!("Speculum — {}", config.scene_name))
            .with_inner_size(winit::dpi::PhysicalSize::new(s.width, s.height));
        let window = el
            .create_window(attrs)
            .map_err(|e| Error::Window(format!("cannot create the window: {e}")))?;
        let handles = WindowHandles {
            display: window
                .display_handle()
                .map_err(|e| Error::Window(e.to_string()))?
                .as_raw(),
            window: window
                .window_handle()
                .map_err(|e| Error::Window(e.to_string()))?
                .as_raw(),
        };
        let ctx = Context::new(&ContextDesc {
            validation: config.validation,
            device: config.device.clone(),
            window: Some(handles),
        })?;
        // The window may not have the asked size (a tiling window manager, a small
        // screen): render at the size it has.
        let mut settings = config.settings.clone();
        let (w, h) = window_size(&window);
        if w > 0 && h > 0 {
            (settings.width, settings.height) = (w, h);
        }
        let mut renderer = Renderer::new(&ctx, &config.scene, &settings)?;
        renderer.set_frames_in_flight(FRAMES_IN_FLIGHT)?;
        let present_modes = swapchain::supported_present_modes(&ctx)?;
        let swapchain = Swapchain::new(&ctx, (w, h), config.present_mode, None)?;
        let format = swapchain.as_ref().map_or(vk::Format::B8G8R8A8_UNORM, |s| s.format);
        let sync = FrameSync::new(&ctx, FRAMES_IN_FLIGHT)?;
        let slot = || Slot {
            pending: false,
            mode: settings.mode,
            free: Vec::new(),
        };
        let slots = (0..FRAMES_IN_FLIGHT).map(|_| slot()).collect();
        let egui_ctx = egui::Context::default();
        let max_side = ctx.limits.max_image_dimension2_d as usize;
        let state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        let hud_renderer = egui_ash_renderer::Renderer::with_default_allocator(
            &ctx.instance,
            ctx.physical_device,
            ctx.device.clone(),
            egui_ash_renderer::RenderMode::DynamicRendering(egui_ash_renderer::DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            egui_ash_renderer::Options {
                in_flight_frames: FRAMES_IN_FLIGHT,
                srgb_framebuffer: false,
                ..Default::default()
            },
        )
        .map_err(|e| Error::Window(format!("HUD renderer: {e}")))?;
        let camera = FlyCamera::new(renderer.camera(), config.scene.bounds());
        let scripted = !config.script.is_empty();
        Ok(Self {
            renderer,
            hud: Hud {
                ctx: egui_ctx,
                state,
                renderer: hud_renderer,
                visible: true,
            },
            swapchain,
            sync,
            slots,
            ctx,
            window,
            scene: config.scene,
            scene_name: config.scene_name,
            camera,
            present_mode: config.present_mode,
            present_modes,
            follow_window: true,
            minimized: false,
            recreate: false,
            frame: 0,
            last_frame: Instant::now(),
            gpu_ms: VecDeque::new(),
            wall_ms: VecDeque::new(),
            passes: VecDeque::new(),
            stats: None,
            rendered_since_change: false,
            compare: None,
            message: String::new(),
            looking: None,
            cursor: (0.0, 0.0),
            script: config.script.into(),
            waiting: 0,
            scripted,
            out_dir: config.out_dir,
            screenshots: 0,
            verbose: config.verbose,
            summary: Summary::default(),
            quit: false,
            window_shot: None,
            shot_copy: None,
        })
    }

    fn minimized(&self) -> bool {
        self.minimized || self.window.is_minimized() == Some(true)
    }

    /// A window event; `Ok(false)` to quit.
    fn on_window_event(&mut self, event: WindowEvent) -> Result<bool> {
        let response = self.hud.state.on_window_event(&self.window, &event);
        let hud_has = |wants: bool| response.consumed || wants;
        match event {
            WindowEvent::CloseRequested => return Ok(false),
            WindowEvent::Resized(size) => {
                if size.width == 0 || size.height == 0 {
                    // Minimized to nothing: keep the swapchain, skip frames.
                    return Ok(true);
                }
                self.recreate = true;
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return Ok(true);
                };
                let pressed = event.state == ElementState::Pressed;
                let h = &mut self.camera.held;
                match code {
                    KeyCode::KeyW => h.forward = pressed,
                    KeyCode::KeyS => h.back = pressed,
                    KeyCode::KeyA => h.left = pressed,
                    KeyCode::KeyD => h.right = pressed,
                    KeyCode::KeyQ => h.down = pressed,
                    KeyCode::KeyE => h.up = pressed,
                    KeyCode::ShiftLeft | KeyCode::ShiftRight => h.fast = pressed,
                    _ => {}
                }
                if pressed && !event.repeat && !hud_has(self.hud.ctx.egui_wants_keyboard_input()) {
                    if let Some(action) = action_of(code) {
                        self.act(action)?;
                    }
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Right,
                ..
            } => {
                self.looking = (state == ElementState::Pressed && !response.consumed).then_some(self.cursor);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = (position.x, position.y);
                if let Some((x, y)) = self.looking {
                    self.camera.look((position.x - x) as f32, (position.y - y) as f32);
                    self.looking = Some(self.cursor);
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !hud_has(self.hud.ctx.egui_wants_pointer_input()) => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.camera.scroll(notches);
            }
            _ => {}
        }
        Ok(!self.quit)
    }

    /// Runs due script steps and draws a frame; `Ok(false)` to quit.
    fn tick(&mut self) -> Result<bool> {
        while self.waiting == 0 && !self.quit {
            let Some(step) = self.script.pop_front() else {
                if self.scripted {
                    self.quit = true;
                }
                break;
            };
            if self.verbose {
                eprintln!("demo: frame {}: {step:?}", self.frame);
            }
            self.run_step(step)?;
        }
        if self.quit {
            return Ok(false);
        }
        self.draw()?;
        self.waiting = self.waiting.saturating_sub(1);
        Ok(!self.quit)
    }

    fn run_step(&mut self, step: Step) -> Result<()> {
        match step {
            Step::Wait(n) => self.waiting = n,
            Step::Key(a) => self.act(a)?,
            Step::Set(name, value) => {
                let s = self.renderer.settings().with_field(&name, &value)?;
                if matches!(name.as_str(), "width" | "height") {
                    self.follow_window = false;
                }
                self.apply_settings(s)?;
            }
            Step::Resize(w, h) => {
                let _ = self.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
            }
            Step::Minimize => {
                self.window.set_minimized(true);
                self.minimized = true;
            }
            Step::Restore => {
                self.window.set_minimized(false);
                self.minimized = false;
                self.recreate = true;
            }
            Step::Camera(p, t) => {
                let mut c = self.camera.camera();
                (c.position, c.target) = (p, t);
                self.camera.set(c);
            }
            Step::Screenshot(path) => self.screenshot(&path)?,
            Step::WindowShot(path) => self.window_shot = Some(path),
            Step::Compare => self.compare_with_rt()?,
            Step::SaveSettings(path) => self.save_settings(&path)?,
            Step::Quit => self.quit = true,
        }
        Ok(())
    }

    /// What a key (or a HUD button) does.
    fn act(&mut self, action: Action) -> Result<()> {
        match action {
            Action::Mode(m) => {
                let s = Settings {
                    mode: m,
                    ..self.renderer.settings().clone()
                };
                self.apply_settings(s)?;
            }
            Action::FailMask => {
                let on = !self.renderer.fail_mask_view();
                self.renderer.set_fail_mask_view(on);
            }
            Action::Hud => self.hud.visible = !self.hud.visible,
            Action::Screenshot => {
                let path = loop {
                    let p = self.out_dir.join(format!("speculum_{:04}.png", self.screenshots));
                    self.screenshots += 1;
                    if !p.exists() {
                        break p;
                    }
                };
                self.screenshot(&path)?;
            }
            Action::Pause => {
                let p = !self.renderer.paused();
                self.renderer.set_paused(p);
            }
            Action::Step => self.renderer.step_once(),
            Action::Restart => {
                self.drain()?;
                self.renderer.reset_simulation()?;
            }
            Action::ResetCamera => self.camera.reset(),
            Action::Compare => self.compare_with_rt()?,
            Action::PresentMode => {
                let i = self
                    .present_modes
                    .iter()
                    .position(|m| *m == self.present_mode)
                    .unwrap_or(0);
                self.present_mode = self.present_modes[(i + 1) % self.present_modes.len()];
                self.recreate = true;
            }
            Action::Quit => self.quit = true,
        }
        Ok(())
    }

    /// The one path by which settings change (HUD, keys, scripts): in place where the
    /// renderer can, else with a new renderer for the same scene and view.
    fn apply_settings(&mut self, s: Settings) -> Result<()> {
        if self.renderer.needs_new_renderer(&s) {
            self.drain()?;
            let mut scene = self.scene.clone();
            scene.camera = self.camera.camera();
            let (fail, paused) = (self.renderer.fail_mask_view(), self.renderer.paused());
            // The old renderer goes first: two scenes' buffers need not fit at once.
            let old = std::mem::replace(&mut self.renderer, Renderer::new(&self.ctx, &scene, &s)?);
            drop(old);
            self.renderer.set_frames_in_flight(FRAMES_IN_FLIGHT)?;
            self.renderer.set_fail_mask_view(fail);
            self.renderer.set_paused(paused);
            self.message = "new time step or BVH policy: the animation restarted".into();
        } else {
            if (s.width, s.height) != (self.renderer.settings().width, self.renderer.settings().height) {
                self.drain()?;
            }
            self.renderer.set_settings(s)?;
        }
        self.stats = None;
        self.rendered_since_change = false;
        Ok(())
    }

    /// Waits for every frame in flight and takes their timings.
    fn drain(&mut self) -> Result<()> {
        self.ctx.wait_idle()?;
        for i in 0..self.slots.len() {
            self.finish_slot(i)?;
        }
        Ok(())
    }

    /// After slot `i`'s fence: its frame's timings go into the history.
    fn finish_slot(&mut self, i: usize) -> Result<()> {
        let slot = &mut self.slots[i];
        for id in slot.free.drain(..) {
            self.hud
                .renderer
                .free_texture(id)
                .map_err(|e| Error::Window(format!("HUD texture: {e}")))?;
        }
        if !std::mem::take(&mut slot.pending) {
            return Ok(());
        }
        let mode = slot.mode;
        let times = self.renderer.frame_finished(i)?;
        if let Some(ms) = times.get(crate::renderer::FRAME) {
            push(&mut self.gpu_ms, ms);
            self.summary.mode_frame_ms.entry(mode.name()).or_default().push(ms);
        }
        push(&mut self.passes, times.scopes);
        Ok(())
    }

    fn recreate_swapchain(&mut self) -> Result<()> {
        let start = Instant::now();
        self.drain()?;
        let size = window_size(&self.window);
        let new = Swapchain::new(&self.ctx, size, self.present_mode, self.swapchain.as_ref())?;
        // The old swapchain is retired by the new one's creation; no frame uses it now.
        self.swapchain = None;
        self.swapchain = new;
        if let Some(sc) = &self.swapchain {
            self.present_mode = sc.present_mode;
            if self.follow_window {
                let e = sc.extent;
                let s = &self.renderer.settings().clone();
                if (s.width, s.height) != (e.width, e.height) {
                    self.renderer.set_settings(Settings {
                        width: e.width,
                        height: e.height,
                        ..s.clone()
                    })?;
                    self.stats = None;
                    self.rendered_since_change = false;
                }
            }
            self.recreate = false;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            if self.verbose {
                eprintln!("demo: swapchain {}x{} in {ms:.1} ms", sc.extent.width, sc.extent.height);
            }
            self.summary.recreate_ms.push(ms);
        }
        Ok(())
    }

    /// One frame: the renderer's passes, the blit, the HUD, the present.
    fn draw(&mut self) -> Result<()> {
        let i = (self.frame % self.slots.len() as u64) as usize;
        self.sync.wait(i)?;
        self.finish_slot(i)?;
        if self.minimized() {
            self.summary.skipped += 1;
            return Ok(());
        }
        if self.recreate || self.swapchain.is_none() {
            self.recreate_swapchain()?;
        }
        let Some(sc) = &self.swapchain else {
            self.summary.skipped += 1;
            return Ok(());
        };
        let image = match self.sync.acquire(i, sc)? {
            Acquired::Image { index, suboptimal } => {
                self.recreate |= suboptimal;
                index
            }
            Acquired::OutOfDate => {
                self.recreate = true;
                self.summary.skipped += 1;
                return Ok(());
            }
        };
        self.advance_camera();
        if self.stats.is_none() || self.frame.is_multiple_of(STATS_EVERY) {
            self.refresh_stats()?;
        }
        let primitives = self.run_hud(i)?;
        let Some(sc) = &self.swapchain else { return Ok(()) };
        let shot = match self.window_shot.take() {
            Some(path) => Some((sc.shot_buffer(&path.display().to_string())?, path)),
            None => None,
        };
        let cmd = self.sync.begin(i)?;
        self.slots[i].mode = self.renderer.settings().mode;
        self.renderer.record_frame(cmd, i);
        sc.record_blit(cmd, image, &self.renderer.compose.ldr);
        if let Some(primitives) = &primitives {
            let ppp = self.hud.ctx.pixels_per_point();
            let hud = &mut self.hud.renderer;
            sc.record_overlay(cmd, image, || hud.cmd_draw(cmd, sc.extent, ppp, primitives))
                .map_err(|e| Error::Window(format!("HUD draw: {e}")))?;
        }
        sc.record_finish(cmd, image, shot.as_ref().map(|s| &s.0));
        self.recreate |= self.sync.submit_present(i, sc, image)?;
        self.shot_copy = shot.map(|(buffer, path)| (path, buffer, sc.extent, i));
        self.slots[i].pending = true;
        self.rendered_since_change = true;
        self.frame += 1;
        self.summary.frames += 1;
        self.save_window_shot()
    }

    /// The camera moves by the time since the last frame.
    fn advance_camera(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f64();
        self.last_frame = now;
        push(&mut self.wall_ms, dt * 1e3);
        self.camera.update(dt as f32);
        self.renderer.set_camera(self.camera.camera());
    }

    /// Saves the window shot copied out of the frame just submitted (waits for it).
    fn save_window_shot(&mut self) -> Result<()> {
        let (Some((path, buffer, e, slot)), Some(sc)) = (self.shot_copy.take(), &self.swapchain) else {
            return Ok(());
        };
        self.sync.wait(slot)?;
        crate::headless::save_png(&path, &sc.rgba_of_shot(&buffer), e.width, e.height)?;
        eprintln!(
            "demo: saved the window ({}x{}) to {}",
            e.width,
            e.height,
            path.display()
        );
        Ok(())
    }

    /// The reflection counts of the last frame (waits for the GPU).
    fn refresh_stats(&mut self) -> Result<()> {
        if !self.rendered_since_change {
            return Ok(());
        }
        self.drain()?;
        self.stats = Some(self.renderer.reflection_stats()?);
        Ok(())
    }

    /// Runs the HUD for this frame and applies what it asked for; the primitives to
    /// draw, or `None` when the HUD is hidden.
    fn run_hud(&mut self, slot: usize) -> Result<Option<Vec<egui::ClippedPrimitive>>> {
        let input = self.hud.state.take_egui_input(&self.window);
        let passes = self.pass_medians();
        let settings = self.renderer.settings().clone();
        let cmdline = self.command_line();
        let gpu: Vec<f64> = self.gpu_ms.iter().copied().collect();
        let wall: Vec<f64> = self.wall_ms.iter().copied().collect();
        let info = hud::HudInfo {
            scene: &self.scene_name,
            device: &self.ctx.device_name,
            settings: &settings,
            window: window_size(&self.window),
            follow_window: self.follow_window,
            present_mode: self.present_mode,
            present_modes: &self.present_modes,
            gpu_ms: &gpu,
            wall_ms: &wall,
            passes: &passes,
            stats: self.stats.as_ref(),
            camera: self.camera.camera(),
            speed: self.camera.speed,
            dynamic: self.renderer.is_dynamic(),
            paused: self.renderer.paused(),
            sim_steps: self.renderer.sim_steps(),
            fail_mask: self.renderer.fail_mask_view(),
            compare: self.compare,
            message: &self.message,
            command_line: &cmdline,
        };
        let visible = self.hud.visible;
        let mut requests = Vec::new();
        let output = self.hud.ctx.run_ui(input, |ui| {
            if visible {
                requests = hud::draw(ui.ctx(), &info);
            }
        });
        self.hud
            .state
            .handle_platform_output(&self.window, output.platform_output);
        for (id, delta) in &output.textures_delta.set {
            for delta in delta {
                self.hud
                    .renderer
                    .set_texture(self.ctx.queue, self.sync.pool(), *id, delta)
                    .map_err(|e| Error::Window(format!("HUD texture: {e}")))?;
            }
        }
        self.slots[slot].free.extend(output.textures_delta.free.iter().copied());
        let primitives = self.hud.ctx.tessellate(output.shapes, output.pixels_per_point);
        for r in requests {
            let applied = match r {
                hud::Request::Settings(s) => {
                    if (s.width, s.height) != (settings.width, settings.height) {
                        self.follow_window = false;
                    }
                    self.apply_settings(*s)
                }
                hud::Request::Action(a) => self.act(a),
                hud::Request::PresentMode(m) => {
                    self.present_mode = m;
                    self.recreate = true;
                    Ok(())
                }
                hud::Request::FollowWindow(on) => {
                    self.follow_window = on;
                    self.recreate = true;
                    Ok(())
                }
                hud::Request::SaveSettings => {
                    let path = self.out_dir.join("demo_settings.json");
                    self.save_settings(&path)
                }
            };
            // A person's mistake is shown, not fatal.
            if let Err(e) = applied {
                self.message = e.to_string();
            }
        }
        Ok(visible.then_some(primitives))
    }

    /// Median ms per pass over the history, in frame order.
    fn pass_medians(&self) -> Vec<(&'static str, f64)> {
        let mut names: Vec<&'static str> = Vec::new();
        let mut samples: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
        for frame in self.passes.iter().rev().take(60) {
            for &(n, ms) in frame {
                if !names.contains(&n) {
                    names.push(n);
                }
                samples.entry(n).or_default().push(ms);
            }
        }
        names.sort_by_key(|n| crate::renderer::SCOPES.iter().position(|s| s == n));
        names.into_iter().map(|n| (n, hud::median_p95(&samples[n]).0)).collect()
    }

    /// A `speculum render` command line for this view and these settings.
    fn command_line(&self) -> String {
        let c = self.camera.camera();
        let v = |v: glam::Vec3| format!("{:.4},{:.4},{:.4}", v.x, v.y, v.z);
        let s = self.renderer.settings();
        format!(
            "speculum render --scene {} --mode {} --width {} --height {} --camera-pos {} --camera-target {} \
             --fov {:.2} [--settings demo_settings.json]",
            self.scene_name,
            s.mode.name(),
            s.width,
            s.height,
            v(c.position),
            v(c.target),
            c.fov_y_deg
        )
    }

    /// The last frame without the HUD as a PNG, and beside it a JSON of the settings,
    /// the camera and the timings.
    fn screenshot(&mut self, path: &Path) -> Result<()> {
        crate::output::check(path, crate::output::Kind::Png)?;
        if !self.rendered_since_change {
            return Err(Error::Input(format!(
                "screenshot {}: no frame rendered since the last change (wait a frame first)",
                path.display()
            )));
        }
        self.drain()?;
        let s = self.renderer.settings().clone();
        let rgba = self.renderer.read_output()?;
        let stats = self.renderer.reflection_stats()?;
        let c = self.camera.camera();
        let (gpu_med, gpu_p95) = hud::median_p95(&self.gpu_ms.iter().copied().collect::<Vec<_>>());
        let passes: BTreeMap<&str, f64> = self.pass_medians().into_iter().collect();
        let json = serde_json::json!({
            "scene": self.scene_name,
            "device": self.ctx.device_name,
            "frame": self.frame,
            "mode": s.mode.name(),
            "fail_mask_view": self.renderer.fail_mask_view(),
            "window": window_size(&self.window),
            "present_mode": present_mode_name(self.present_mode),
            "camera": {"position": c.position.to_array(), "target": c.target.to_array(), "fov_y_deg": c.fov_y_deg},
            "render_command": self.command_line(),
            "settings": s,
            "gpu_frame_ms": {"median": gpu_med, "p95": gpu_p95, "frames": self.gpu_ms.len()},
            "passes_median_ms": passes,
            "reflections": stats,
            "sim_steps": self.renderer.sim_steps(),
        });
        let mut batch = crate::output::Batch::default();
        batch.add(path, crate::headless::png_bytes(&rgba, s.width, s.height)?);
        batch.add(
            &path.with_extension("json"),
            serde_json::to_string_pretty(&json).expect("serializes").into_bytes(),
        );
        batch.commit()?;
        self.message = format!("saved {}", path.display());
        eprintln!(
            "demo: saved {} ({}x{}) and its .json",
            path.display(),
            s.width,
            s.height
        );
        Ok(())
    }

    fn save_settings(&mut self, path: &Path) -> Result<()> {
        crate::output::check(path, crate::output::Kind::Json)?;
        let json = crate::report::to_json(self.renderer.settings());
        crate::output::write_atomic(path, json.as_bytes())?;
        self.message = format!("saved settings to {}", path.display());
        eprintln!("demo: {}", self.message);
        Ok(())
    }

    /// Renders this view in the current mode and in `rt` (the animation held still)
    /// and compares them.
    fn compare_with_rt(&mut self) -> Result<()> {
        self.drain()?;
        let mode = self.renderer.settings().mode;
        let (fail, paused) = (self.renderer.fail_mask_view(), self.renderer.paused());
        self.renderer.set_fail_mask_view(false);
        self.renderer.set_paused(true);
        let result = (|| {
            self.renderer.render_frame()?;
            let a = self.renderer.read_output()?;
            self.renderer.set_mode(Mode::Rt);
            self.renderer.render_frame()?;
            let b = self.renderer.read_output()?;
            let s = self.renderer.settings();
            crate::metrics::compare_rgba8(&a, &b, s.width, s.height)
        })();
        self.renderer.set_mode(mode);
        self.renderer.set_fail_mask_view(fail);
        self.renderer.set_paused(paused);
        let c = result?;
        self.compare = Some((c.ssim, c.rmse, mode));
        println!("demo: {} vs rt: SSIM {:.4}, RMSE {:.4}", mode.name(), c.ssim, c.rmse);
        Ok(())
    }

    /// Waits for the GPU and destroys everything; the summary of the run.
    fn close(mut self) -> Summary {
        let _ = self.drain();
        self.summary.validation_messages = self.ctx.validation_messages();
        std::mem::take(&mut self.summary)
    }
}

fn push<T>(q: &mut VecDeque<T>, v: T) {
    if q.len() == hud::HISTORY {
        q.pop_front();
    }
    q.push_back(v);
}

fn action_of(code: KeyCode) -> Option<Action> {
    let name = match code {
        KeyCode::Digit1 => "1",
        KeyCode::Digit2 => "2",
        KeyCode::Digit3 => "3",
        KeyCode::Digit4 => "4",
        KeyCode::Digit5 => "5",
        KeyCode::KeyF => "f",
        KeyCode::KeyH => "h",
        KeyCode::KeyP => "p",
        KeyCode::Space => "space",
        KeyCode::Period => ".",
        KeyCode::Backspace => "backspace",
        KeyCode::KeyR => "r",
        KeyCode::KeyC => "c",
        KeyCode::KeyM => "m",
        KeyCode::Escape => "escape",
        _ => return None,
    };
    Action::from_key(name)
}
