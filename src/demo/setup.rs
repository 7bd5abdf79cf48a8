//! The demo's setup and teardown: the window, the context with its surface, the
//! renderer with its frames in flight, the swapchain and the HUD.

use super::*;
use crate::error::Error;

impl Demo {
    // Long: the window, context, renderer, swapchain and HUD in order, then the Demo literal.
    pub(super) fn new(el: &ActiveEventLoop, config: DemoConfig) -> Result<Self> {
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
            ..Default::default()
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
        let hud = Hud::new(&ctx, &window, format)?;
        let camera = FlyCamera::new(renderer.camera(), config.scene.bounds());
        let scripted = !config.script.is_empty();
        Ok(Self {
            renderer,
            hud,
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
            history: History::default(),
            stats: None,
            rendered_since_change: false,
            compare: None,
            message: String::new(),
            looking: None,
            cursor: (0.0, 0.0),
            script: ScriptRun {
                steps: config.script.into(),
                waiting: 0,
                scripted,
            },
            shots: Shots {
                out_dir: config.out_dir,
                taken: 0,
                window_shot: None,
                copy: None,
            },
            verbose: config.verbose,
            summary: Summary::default(),
            quit: false,
        })
    }

    pub(super) fn minimized(&self) -> bool {
        self.minimized || self.window.is_minimized() == Some(true)
    }

    /// Waits for the GPU and destroys everything; the summary of the run.
    pub(super) fn close(mut self) -> Summary {
        let _ = self.drain();
        self.summary.validation_messages = self.ctx.validation_messages();
        std::mem::take(&mut self.summary)
    }
}

impl Hud {
    /// egui on `window`, drawn by dynamic rendering into images of `format`.
    fn new(ctx: &Context, window: &Window, format: vk::Format) -> Result<Self> {
        let egui_ctx = egui::Context::default();
        let max_side = ctx.limits.max_image_dimension2_d as usize;
        let state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        let renderer = egui_ash_renderer::Renderer::with_default_allocator(
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
        Ok(Self {
            ctx: egui_ctx,
            state,
            renderer,
            visible: true,
        })
    }
}
