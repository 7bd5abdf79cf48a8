//! The demo's HUD (egui): what the frame costs and shows, and every setting. It draws
//! from a snapshot (`HudInfo`) and answers with requests the demo applies after the
//! UI pass, through the same paths as keys and scripts.

use super::script::Action;
use crate::headless::StageReport;
use crate::reflection_maps::{FAIL_COLOURS, FAIL_REASONS, SSR_OK_COLOUR};
use crate::scene::Camera;
use crate::settings::{
    Applies, Field, Hud, HybridPolicy, Mode, Settings, Shadows, Tracer, Value, Visibility, WalkLayout, FIELDS,
};
use crate::vk::swapchain::present_mode_name;
use ash::vk;
use egui::{Color32, RichText};

/// Frames the graph and the statistics cover.
pub const HISTORY: usize = 300;

/// What the HUD shows this frame.
pub struct HudInfo<'a> {
    pub scene: &'a str,
    pub device: &'a str,
    pub settings: &'a Settings,
    pub window: (u32, u32),
    pub follow_window: bool,
    pub present_mode: vk::PresentModeKHR,
    pub present_modes: &'a [vk::PresentModeKHR],
    /// GPU "frame" scope and wall-clock frame interval, ms, oldest first.
    pub gpu_ms: &'a [f64],
    pub wall_ms: &'a [f64],
    /// Median ms per pass over the history, in frame order.
    pub passes: &'a [(&'static str, f64)],
    pub stats: Option<&'a super::Stats>,
    /// The adaptive stages' ways and prices: the G-buffer's and the shadows' (`None`
    /// where the setting is fixed).
    pub stages: &'a (Option<StageReport>, Option<StageReport>),
    /// With `static_ploc`: the static tree kept and both trees' prices.
    pub static_tree: Option<&'a crate::renderer::static_tree::StaticTreeChoice>,
    /// The measured choice of the static walk's nodes (`static_layout = fastest`).
    pub static_layout: Option<&'a crate::renderer::static_tree::StaticLayoutChoice>,
    pub camera: Camera,
    pub speed: f32,
    pub dynamic: bool,
    pub paused: bool,
    pub sim_steps: u64,
    /// The animated model's time in its animation, if the scene has one.
    pub animation_time: Option<f32>,
    pub fail_mask: bool,
    /// SSIM and RMSE of the last "compare with rt", and the mode compared.
    pub compare: Option<(f64, f64, Mode)>,
    pub message: &'a str,
    pub command_line: &'a str,
}

/// What the person asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    Settings(Box<Settings>),
    Action(Action),
    PresentMode(vk::PresentModeKHR),
    FollowWindow(bool),
    SaveSettings,
}

/// (median, p95) of `v`; zeros when empty.
pub fn median_p95(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |q: f64| s[((s.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.95))
}

const RESOLUTIONS: [(u32, u32); 6] = [
    (320, 180),
    (480, 270),
    (640, 360),
    (960, 540),
    (1280, 720),
    (1920, 1080),
];

fn rgb(c: [u8; 3]) -> Color32 {
    Color32::from_rgb(c[0], c[1], c[2])
}

/// Draws the HUD; returns the requests of this frame.
pub fn draw(ctx: &egui::Context, info: &HudInfo<'_>) -> Vec<Request> {
    let mut out = Vec::new();
    let mut s = info.settings.clone();
    let screen = ctx.content_rect();
    egui::Window::new("Speculum")
        .default_pos([8.0, 8.0])
        .default_width(330.0)
        .default_height((screen.height() - 24.0).max(120.0))
        .resizable(true)
        .vscroll(true)
        .show(ctx, |ui| {
            ui.label(format!("{} on {}", info.scene, info.device));
            let (gpu_med, gpu_p95) = median_p95(info.gpu_ms);
            let (wall_med, _) = median_p95(info.wall_ms);
            ui.label(format!(
                "render {}x{} in a {}x{} window · GPU frame {gpu_med:.2} ms (p95 {gpu_p95:.2}) · {:.1} fps",
                s.width,
                s.height,
                info.window.0,
                info.window.1,
                if wall_med > 0.0 { 1e3 / wall_med } else { 0.0 }
            ));
            if !info.message.is_empty() {
                ui.label(RichText::new(info.message).color(Color32::from_rgb(250, 200, 80)));
            }
            mode_panel(ui, info, &mut s, &mut out);
            egui::CollapsingHeader::new("Timings")
                .default_open(true)
                .show(ui, |ui| timings_panel(ui, info));
            egui::CollapsingHeader::new("Reflections")
                .default_open(true)
                .show(ui, |ui| reflections_panel(ui, info, &mut out));
            if info.dynamic {
                egui::CollapsingHeader::new("Animation")
                    .default_open(true)
                    .show(ui, |ui| {
                        ui.label(format!(
                            "step {} · t = {:.2} s{}{}",
                            info.sim_steps,
                            info.sim_steps as f32 * s.sim_dt,
                            info.animation_time
                                .map_or(String::new(), |t| format!(" · animation at {t:.2} s")),
                            if info.paused { " · paused" } else { "" }
                        ));
                        ui.horizontal(|ui| {
                            if ui.button(if info.paused { "play" } else { "pause" }).clicked() {
                                out.push(Request::Action(Action::Pause));
                            }
                            if ui.add_enabled(info.paused, egui::Button::new("step")).clicked() {
                                out.push(Request::Action(Action::Step));
                            }
                            if ui.button("restart").clicked() {
                                out.push(Request::Action(Action::Restart));
                            }
                        });
                    });
            }
            egui::CollapsingHeader::new("Camera")
                .default_open(false)
                .show(ui, |ui| camera_panel(ui, info, &mut out));
            egui::CollapsingHeader::new("Settings")
                .default_open(false)
                .show(ui, |ui| settings_panel(ui, info, &mut s, &mut out));
            egui::CollapsingHeader::new("Display")
                .default_open(false)
                .show(ui, |ui| {
                    egui::ComboBox::from_label("present mode")
                        .selected_text(present_mode_name(info.present_mode))
                        .show_ui(ui, |ui| {
                            for &m in info.present_modes {
                                if ui
                                    .selectable_label(m == info.present_mode, present_mode_name(m))
                                    .clicked()
                                {
                                    out.push(Request::PresentMode(m));
                                }
                            }
                        });
                    ui.horizontal(|ui| {
                        if ui.button("screenshot (P)").clicked() {
                            out.push(Request::Action(Action::Screenshot));
                        }
                        if ui.button("save settings").clicked() {
                            out.push(Request::SaveSettings);
                        }
                    });
                });
        });
    if s != *info.settings {
        out.push(Request::Settings(Box::new(s)));
    }
    out
}

fn mode_panel(ui: &mut egui::Ui, info: &HudInfo<'_>, s: &mut Settings, out: &mut Vec<Request>) {
    ui.horizontal(|ui| {
        for (i, m) in Mode::ALL.into_iter().enumerate() {
            if ui
                .selectable_label(s.mode == m, format!("{} {}", i + 1, m.name()))
                .clicked()
            {
                s.mode = m;
            }
        }
    });
    ui.horizontal(|ui| {
        ui.label("shadows");
        for sh in Shadows::ALL {
            ui.selectable_value(&mut s.shadows, sh, sh.name())
                .on_hover_text(sh.about());
        }
    });
    if let Some(v) = &info.stages.1 {
        ui.label(format!("  {}", v.summary()));
    }
    ui.horizontal(|ui| {
        ui.label("visibility");
        for v in Visibility::ALL {
            ui.selectable_value(&mut s.visibility, v, v.name())
                .on_hover_text(v.about());
        }
    });
    if let Some(v) = &info.stages.0 {
        ui.label(format!("  {}", v.summary()));
    }
    ui.horizontal(|ui| {
        ui.label("tracer");
        for t in Tracer::ALL {
            ui.selectable_value(&mut s.tracer, t, t.name()).on_hover_text(t.about());
        }
    });
    if let Some(t) = info.static_tree {
        ui.label(format!("  static tree: {}", t.summary()));
    }
    ui.horizontal(|ui| {
        ui.label("static nodes");
        for l in WalkLayout::ALL {
            ui.selectable_value(&mut s.static_layout, l, l.name())
                .on_hover_text(l.about());
        }
    });
    if let Some(l) = info.static_layout {
        ui.label(format!("  {}", l.summary()));
    }
    ui.horizontal(|ui| {
        ui.label("hybrid");
        for p in HybridPolicy::ALL {
            ui.selectable_value(&mut s.hybrid_policy, p, p.name())
                .on_hover_text(p.about());
        }
    });
    let mut fail = info.fail_mask;
    if ui.checkbox(&mut fail, "fail-mask view (F)").changed() {
        out.push(Request::Action(Action::FailMask));
    }
    if info.fail_mask {
        if s.mode == Mode::Raster {
            ui.label("raster mode has no fail mask");
        }
        let swatch = |ui: &mut egui::Ui, c: [u8; 3], name: &str| {
            ui.horizontal(|ui| {
                let (rect, _) = ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
                ui.painter().rect_filled(rect, 2.0, rgb(c));
                ui.label(name);
            });
        };
        ui.columns(2, |cols| {
            swatch(&mut cols[0], SSR_OK_COLOUR, "SSR answered");
            swatch(&mut cols[0], [0, 0, 0], "not reflective");
            for (i, ((_, name), c)) in FAIL_REASONS.iter().zip(FAIL_COLOURS).enumerate() {
                swatch(&mut cols[(i + 2) / 6], c, name);
            }
        });
    }
}

fn timings_panel(ui: &mut egui::Ui, info: &HudInfo<'_>) {
    egui::Grid::new("passes").striped(true).show(ui, |ui| {
        ui.label(RichText::new("pass").strong());
        ui.label(RichText::new("median ms").strong());
        ui.end_row();
        for (name, ms) in info.passes {
            ui.label(*name);
            ui.label(format!("{ms:.3}"));
            ui.end_row();
        }
    });
    // The rolling GPU frame time, with its median and p95.
    let (med, p95) = median_p95(info.gpu_ms);
    let top = info.gpu_ms.iter().copied().fold(p95 * 1.2, f64::max).max(1e-3);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width().max(200.0), 70.0), egui::Sense::hover());
    let p = ui.painter_at(rect);
    p.rect_filled(rect, 2.0, Color32::from_black_alpha(120));
    let y = |ms: f64| rect.bottom() - (ms / top) as f32 * rect.height();
    let n = info.gpu_ms.len();
    let x = |i: usize| rect.left() + rect.width() * i as f32 / (HISTORY - 1) as f32;
    let points: Vec<egui::Pos2> = info
        .gpu_ms
        .iter()
        .enumerate()
        .map(|(i, &ms)| egui::pos2(x(i + HISTORY.saturating_sub(n)), y(ms)))
        .collect();
    p.add(egui::Shape::line(
        points,
        egui::Stroke::new(1.5, Color32::from_rgb(120, 220, 120)),
    ));
    for (ms, c) in [(med, Color32::WHITE), (p95, Color32::from_rgb(250, 160, 60))] {
        p.hline(rect.x_range(), y(ms), egui::Stroke::new(1.0, c));
    }
    ui.label(format!(
        "GPU frame, last {n} frames: median {med:.2} ms (white), p95 {p95:.2} ms (orange), top {top:.1} ms"
    ));
}

fn reflections_panel(ui: &mut egui::Ui, info: &HudInfo<'_>, out: &mut Vec<Request>) {
    match info.stats {
        Some((st, sh, hybrid)) => {
            ui.label(format!(
                "reflective pixels {} · SSR failed on {} · ray traced {} ({:.1}%)",
                st.reflective_pixels,
                st.ssr_failed_pixels,
                st.traced_pixels,
                100.0 * st.rt_pixel_fraction()
            ));
            ui.label(format!(
                "{} shadows: lit pixels {} · shadow rays {} ({:.1}%)",
                info.settings.shadows.name(),
                sh.lit_pixels,
                sh.traced_pixels,
                100.0 * sh.ray_fraction()
            ));
            if let Some(h) = hybrid {
                let known = (h.ssr_first_tiles + h.rays_only_tiles).max(1) as f64;
                ui.label(format!(
                    "hybrid {}: exchange rate {:.3} · tiles SSR-first {:.0}%, rays-only {:.0}% (of {:.0} known) · path {}",
                    h.policy,
                    h.exchange_rate,
                    100.0 * h.ssr_first_tiles as f64 / known,
                    100.0 * h.rays_only_tiles as f64 / known,
                    known,
                    h.path
                ));
            }
        }
        None => {
            ui.label("reflective pixels: measuring…");
        }
    }
    ui.horizontal(|ui| {
        if ui.button("compare with rt (C)").clicked() {
            out.push(Request::Action(Action::Compare));
        }
        if let Some((ssim, rmse, mode)) = info.compare {
            ui.label(format!("{} vs rt: SSIM {ssim:.4}, RMSE {rmse:.4}", mode.name()));
        }
    });
}

fn camera_panel(ui: &mut egui::Ui, info: &HudInfo<'_>, out: &mut Vec<Request>) {
    let c = info.camera;
    ui.label(format!(
        "position {:.3}, {:.3}, {:.3}",
        c.position.x, c.position.y, c.position.z
    ));
    ui.label(format!(
        "target {:.3}, {:.3}, {:.3}",
        c.target.x, c.target.y, c.target.z
    ));
    ui.label(format!("fov {:.1}° · speed {:.2} units/s", c.fov_y_deg, info.speed));
    ui.label("reproduce this view:");
    let mut line = info.command_line.to_string();
    ui.add(egui::TextEdit::multiline(&mut line).desired_rows(3).code_editor());
    if ui.button("reset camera (R)").clicked() {
        out.push(Request::Action(Action::ResetCamera));
    }
}

fn settings_panel(ui: &mut egui::Ui, info: &HudInfo<'_>, s: &mut Settings, out: &mut Vec<Request>) {
    let mut follow = info.follow_window;
    if ui.checkbox(&mut follow, "render at the window's size").changed() {
        out.push(Request::FollowWindow(follow));
    }
    egui::ComboBox::from_label("resolution")
        .selected_text(format!("{}x{}", s.width, s.height))
        .show_ui(ui, |ui| {
            for (w, h) in RESOLUTIONS {
                if ui
                    .selectable_label((s.width, s.height) == (w, h), format!("{w}x{h}"))
                    .clicked()
                {
                    (s.width, s.height) = (w, h);
                }
            }
        });
    // The rest from the settings table, each with what it trades as its tooltip.
    let mut dynamic_label = false;
    for f in FIELDS {
        if f.applies == Applies::NewRenderer && !dynamic_label {
            ui.separator();
            ui.label("dynamic scenes (a change restarts the animation):");
            dynamic_label = true;
        }
        let trades = f.trades_line();
        if let Some(v) = field_control(ui, f, (f.get)(s), &trades) {
            (f.set)(s, v);
        }
    }
    if ui.button("defaults").clicked() {
        *s = Settings {
            width: s.width,
            height: s.height,
            mode: s.mode,
            ..Settings::default()
        };
    }
}

/// The HUD control of one setting (`Field::hud`); the new value when it was changed.
fn field_control(ui: &mut egui::Ui, f: &Field, value: Value, trades: &str) -> Option<Value> {
    let slider = |ui: &mut egui::Ui, s: egui::Slider<'_>, log: bool| {
        ui.add(s.logarithmic(log).clamping(egui::SliderClamping::Edits).text(f.name))
            .on_hover_text(trades)
            .changed()
    };
    match (f.hud, value) {
        (Hud::Slider { min, max, log }, Value::U32(mut v)) => {
            slider(ui, egui::Slider::new(&mut v, min as u32..=max as u32), log).then_some(Value::U32(v))
        }
        (Hud::Slider { min, max, log }, Value::F32(mut v)) => {
            slider(ui, egui::Slider::new(&mut v, min as f32..=max as f32), log).then_some(Value::F32(v))
        }
        (Hud::Checkbox, Value::Bool(mut v)) => ui
            .checkbox(&mut v, f.name)
            .on_hover_text(trades)
            .changed()
            .then_some(Value::Bool(v)),
        (Hud::Choice(list), Value::U32(v)) => {
            let mut picked = None;
            egui::ComboBox::from_label(f.name)
                .selected_text(v.to_string())
                .show_ui(ui, |ui| {
                    for &x in list {
                        if ui.selectable_label(x == v, x.to_string()).clicked() {
                            picked = Some(Value::U32(x));
                        }
                    }
                })
                .response
                .on_hover_text(trades);
            picked
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p95() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(median_p95(&v), (51.0, 95.0));
        assert_eq!(median_p95(&[]), (0.0, 0.0));
        assert_eq!(median_p95(&[3.0]), (3.0, 3.0));
    }

    /// A HUD pass with no input asks for nothing (the settings are drawn as they are).
    #[test]
    fn an_idle_hud_requests_nothing() {
        let ctx = egui::Context::default();
        let settings = Settings::default();
        let camera = Camera::framing(glam::Vec3::splat(-1.0), glam::Vec3::ONE);
        let stage = crate::renderer::stages::Stage::<2>::new(0);
        let stages = (
            Some(StageReport::of(&stage, ["raster", "rays"], 0)),
            Some(StageReport::of(&stage, ["hybrid", "rays"], 0)),
        );
        let tree = crate::renderer::static_tree::StaticTreeChoice {
            kept: "ploc",
            ploc_ms: 1.0,
            lbvh_ms: 1.5,
            rays: 16_384,
        };
        let layout = crate::renderer::static_tree::StaticLayoutChoice {
            kept: "binary",
            binary_ms: Some(1.0),
            wide_ms: Some(1.1),
            wide8_ms: None,
            rays: 16_384,
        };
        let info = HudInfo {
            scene: "room",
            device: "test",
            settings: &settings,
            window: (960, 540),
            follow_window: true,
            present_mode: vk::PresentModeKHR::FIFO,
            present_modes: &[vk::PresentModeKHR::FIFO],
            gpu_ms: &[1.0, 2.0, 3.0],
            wall_ms: &[16.0],
            passes: &[("gbuffer", 1.0)],
            stats: None,
            stages: &stages,
            static_tree: Some(&tree),
            static_layout: Some(&layout),
            camera,
            speed: 1.0,
            dynamic: true,
            paused: false,
            sim_steps: 3,
            animation_time: Some(0.05),
            fail_mask: true,
            compare: Some((0.99, 0.01, Mode::Hybrid)),
            message: "",
            command_line: "speculum render",
        };
        for _ in 0..3 {
            let mut requests = Vec::new();
            let _ = ctx.run_ui(egui::RawInput::default(), |ui| requests = draw(ui.ctx(), &info));
            assert!(requests.is_empty(), "{requests:?}");
        }
    }
}
