//! What a person or a script does: window events, keys, script steps, and the one
//! path by which settings change (`apply_settings`).

use super::*;

impl Demo {
    /// A window event; `Ok(false)` to quit.
    pub(super) fn on_window_event(&mut self, event: WindowEvent) -> Result<bool> {
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
    pub(super) fn tick(&mut self) -> Result<bool> {
        while self.script.waiting == 0 && !self.quit {
            let Some(step) = self.script.steps.pop_front() else {
                if self.script.scripted {
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
        self.script.waiting = self.script.waiting.saturating_sub(1);
        Ok(!self.quit)
    }

    pub(super) fn run_step(&mut self, step: Step) -> Result<()> {
        match step {
            Step::Wait(n) => self.script.waiting = n,
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
            Step::WindowShot(path) => self.shots.window_shot = Some(path),
            Step::Compare => self.compare_with_rt()?,
            Step::SaveSettings(path) => self.save_settings(&path)?,
            Step::Quit => self.quit = true,
        }
        Ok(())
    }

    /// What a key (or a HUD button) does.
    pub(super) fn act(&mut self, action: Action) -> Result<()> {
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
                    let p = self.shots.out_dir.join(format!("speculum_{:04}.png", self.shots.taken));
                    self.shots.taken += 1;
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
    pub(super) fn apply_settings(&mut self, s: Settings) -> Result<()> {
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
}

pub(super) fn action_of(code: KeyCode) -> Option<Action> {
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
