//! One frame of the window: wait for the slot, acquire, record the renderer's frame,
//! blit, HUD, present; and the frame history the HUD shows.

use super::*;

impl Demo {
    /// Waits for every frame in flight and takes their timings.
    pub(super) fn drain(&mut self) -> Result<()> {
        self.ctx.wait_idle()?;
        for i in 0..self.slots.len() {
            self.finish_slot(i)?;
        }
        Ok(())
    }

    /// After slot `i`'s fence: its frame's timings go into the history.
    pub(super) fn finish_slot(&mut self, i: usize) -> Result<()> {
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
            push(&mut self.history.gpu_ms, ms);
            self.summary.mode_frame_ms.entry(mode.name()).or_default().push(ms);
        }
        push(&mut self.history.passes, times.scopes);
        Ok(())
    }

    pub(super) fn recreate_swapchain(&mut self) -> Result<()> {
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
    pub(super) fn draw(&mut self) -> Result<()> {
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
        let shot = match self.shots.window_shot.take() {
            Some(path) => Some((sc.shot_buffer(&path.display().to_string())?, path)),
            None => None,
        };
        let cmd = self.sync.begin(i)?;
        self.slots[i].mode = self.renderer.settings().mode;
        self.renderer.record_frame(cmd, i);
        sc.record_blit(cmd, image, &self.renderer.compose.out);
        if let Some(primitives) = &primitives {
            let ppp = self.hud.ctx.pixels_per_point();
            let hud = &mut self.hud.renderer;
            sc.record_overlay(cmd, image, || hud.cmd_draw(cmd, sc.extent, ppp, primitives))
                .map_err(|e| Error::Window(format!("HUD draw: {e}")))?;
        }
        sc.record_finish(cmd, image, shot.as_ref().map(|s| &s.0));
        self.recreate |= self.sync.submit_present(i, sc, image)?;
        self.shots.copy = shot.map(|(buffer, path)| (path, buffer, sc.extent, i));
        self.slots[i].pending = true;
        self.rendered_since_change = true;
        self.frame += 1;
        self.summary.frames += 1;
        self.save_window_shot()
    }

    /// The camera moves by the time since the last frame.
    pub(super) fn advance_camera(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f64();
        self.last_frame = now;
        push(&mut self.history.wall_ms, dt * 1e3);
        self.camera.update(dt as f32);
        self.renderer.set_camera(self.camera.camera());
    }

    /// Saves the window shot copied out of the frame just submitted (waits for it).
    pub(super) fn save_window_shot(&mut self) -> Result<()> {
        let (Some((path, buffer, e, slot)), Some(sc)) = (self.shots.copy.take(), &self.swapchain) else {
            return Ok(());
        };
        self.sync.wait(slot)?;
        crate::output::save_png(&path, &sc.rgba_of_shot(&buffer), e.width, e.height)?;
        eprintln!(
            "demo: saved the window ({}x{}) to {}",
            e.width,
            e.height,
            path.display()
        );
        Ok(())
    }

    /// The reflection and shadow counts of the last frame (waits for the GPU).
    pub(super) fn refresh_stats(&mut self) -> Result<()> {
        if !self.rendered_since_change {
            return Ok(());
        }
        self.drain()?;
        let shadows = self.renderer.shadow_maps()?.stats();
        let hybrid = crate::headless::hybrid_split(&self.renderer, self.renderer.settings())?;
        self.stats = Some((self.renderer.reflection_stats()?, shadows, hybrid));
        Ok(())
    }

    /// Runs the HUD for this frame and applies what it asked for; the primitives to
    /// draw, or `None` when the HUD is hidden.
    pub(super) fn run_hud(&mut self, slot: usize) -> Result<Option<Vec<egui::ClippedPrimitive>>> {
        let input = self.hud.state.take_egui_input(&self.window);
        let passes = self.pass_medians();
        let settings = self.renderer.settings().clone();
        let cmdline = self.command_line();
        let gpu: Vec<f64> = self.history.gpu_ms.iter().copied().collect();
        let wall: Vec<f64> = self.history.wall_ms.iter().copied().collect();
        let stages = crate::headless::stage_reports(&self.renderer, &settings);
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
            stages: &stages,
            static_tree: self.renderer.static_tree.as_ref(),
            static_layout: self.renderer.static_layout.as_ref(),
            camera: self.camera.camera(),
            speed: self.camera.speed,
            dynamic: self.renderer.is_dynamic(),
            paused: self.renderer.paused(),
            sim_steps: self.renderer.sim_steps(),
            animation_time: self.renderer.animation_time(),
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
                    let path = self.shots.out_dir.join("demo_settings.json");
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
    pub(super) fn pass_medians(&self) -> Vec<(&'static str, f64)> {
        let mut names: Vec<&'static str> = Vec::new();
        let mut samples: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
        for frame in self.history.passes.iter().rev().take(60) {
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
}
