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
mod frame;
pub mod hud;
mod input;
pub mod script;
mod setup;
mod shots;

use crate::error::{Error, Result};
use crate::reflection_maps::ReflectionStats;

/// The demo's last readback of the frame's counts (`refresh_stats`).
type Stats = (ReflectionStats, ShadowStats, Option<crate::headless::HybridSplit>);
use crate::scene::Scene;
use crate::settings::{Mode, Settings};
use crate::shadow_maps::ShadowStats;
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
    history: History,
    /// The last counts of the reflections and the shadows, and the hybrid's split
    /// (`refresh_stats`).
    stats: Option<Stats>,
    /// A frame was submitted since the renderer's images were last made (the counts
    /// read them).
    rendered_since_change: bool,
    compare: Option<(f64, f64, Mode)>,
    message: String,
    looking: Option<(f64, f64)>,
    cursor: (f64, f64),
    script: ScriptRun,
    shots: Shots,
    verbose: bool,
    summary: Summary,
    quit: bool,
}

/// The frames the HUD's graphs and medians read: GPU frame ms, wall-clock frame
/// interval ms, and each frame's passes (the last `hud::HISTORY`).
#[derive(Default)]
struct History {
    gpu_ms: VecDeque<f64>,
    wall_ms: VecDeque<f64>,
    passes: VecDeque<Vec<(&'static str, f64)>>,
}

/// The script being run: steps left, frames to wait before the next, and whether the
/// demo quits when they run out (it was started with a script).
struct ScriptRun {
    steps: VecDeque<Step>,
    waiting: u32,
    scripted: bool,
}

/// Where screenshots go and the window shot under way.
struct Shots {
    out_dir: PathBuf,
    /// `P` screenshots taken (their file numbers).
    taken: u32,
    /// A window shot asked for: copied out of the next drawn frame.
    window_shot: Option<PathBuf>,
    /// The copy in flight: its path, buffer, size and slot.
    copy: Option<(PathBuf, Buffer, vk::Extent2D, usize)>,
}

fn window_size(window: &Window) -> (u32, u32) {
    let s = window.inner_size();
    (s.width, s.height)
}

fn push<T>(q: &mut VecDeque<T>, v: T) {
    if q.len() == hud::HISTORY {
        q.pop_front();
    }
    q.push_back(v);
}
