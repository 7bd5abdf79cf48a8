//! What the demo writes and measures on request: screenshots with their JSON, the
//! settings, the `render` command line of the view, and the comparison with `rt`.

use super::*;

impl Demo {
    /// A `speculum render` command line for this view and these settings.
    pub(super) fn command_line(&self) -> String {
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
    pub(super) fn screenshot(&mut self, path: &Path) -> Result<()> {
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
        let (gpu_med, gpu_p95) = hud::median_p95(&self.history.gpu_ms.iter().copied().collect::<Vec<_>>());
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
            "gpu_frame_ms": {"median": gpu_med, "p95": gpu_p95, "frames": self.history.gpu_ms.len()},
            "passes_median_ms": passes,
            "reflections": stats,
            "sim_steps": self.renderer.sim_steps(),
        });
        let mut batch = crate::output::Batch::default();
        batch.add(path, crate::output::png_bytes(&rgba, s.width, s.height)?);
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

    pub(super) fn save_settings(&mut self, path: &Path) -> Result<()> {
        crate::output::check(path, crate::output::Kind::Json)?;
        let json = crate::report::to_json(self.renderer.settings());
        crate::output::write_atomic(path, json.as_bytes())?;
        self.message = format!("saved settings to {}", path.display());
        eprintln!("demo: {}", self.message);
        Ok(())
    }

    /// Renders this view in the current mode and in `rt` (the animation held still)
    /// and compares them.
    pub(super) fn compare_with_rt(&mut self) -> Result<()> {
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
}
