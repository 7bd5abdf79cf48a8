//! `pareto.png`: every point of a sweep, frame/rt against 1 - SSIM (left) and against
//! mean FLIP (right), the Pareto front drawn through its points, the base settings
//! (`default`) and the `rt` reference marked. One scene per plot (the first one when
//! a sweep has several). Text is drawn with a font the binary holds
//! (Ubuntu Light), so plots need no system font.

use super::{PointResult, DEFAULT_KEY};
use crate::error::{Error, Result};
use plotters::prelude::*;

/// The plot's font, in the binary: Ubuntu Light, which egui ships (the
/// `epaint_default_fonts` crate, Ubuntu Font Licence 1.0), so a plot draws on any
/// machine, with no system font path to find.
const FONT: &[u8] = epaint_default_fonts::UBUNTU_LIGHT;

fn register_font() -> Result<()> {
    static ONCE: std::sync::OnceLock<std::result::Result<(), String>> = std::sync::OnceLock::new();
    ONCE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| "the plot's embedded font did not load".to_string())
    })
    .clone()
    .map_err(Error::Input)
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Input(format!("plot: {e}"))
}

/// Draws one panel: x = frame/rt, y = the quality error `err` (log scale).
fn panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    results: &[&PointResult],
    title: &str,
    y_name: &str,
    err: &dyn Fn(&PointResult) -> f64,
    front: &dyn Fn(&PointResult) -> bool,
) -> Result<()> {
    let xs: Vec<f64> = results.iter().map(|r| r.frame_over_rt.median).collect();
    let ys: Vec<f64> = results.iter().map(|r| err(r)).collect();
    let positive: Vec<f64> = ys.iter().copied().filter(|y| *y > 0.0).collect();
    let y_min = positive.iter().copied().fold(f64::INFINITY, f64::min).min(1e-3) * 0.5;
    let y_max = positive.iter().copied().fold(0.0, f64::max).max(y_min * 10.0) * 2.0;
    let x_max = xs.iter().copied().fold(1.0, f64::max) * 1.08;
    let x_min = xs.iter().copied().fold(1.0, f64::min) * 0.92;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x_min..x_max, (y_min..y_max).log_scale())
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc("frame time / rt frame time")
        .y_desc(y_name)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| format!("{v:.2}"))
        .light_line_style(WHITE)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(plot_err)?;
    let at = |r: &PointResult| (r.frame_over_rt.median, err(r).max(y_min));
    chart
        .draw_series(
            results
                .iter()
                .map(|r| Circle::new(at(r), 3, RGBColor(140, 140, 140).filled())),
        )
        .map_err(plot_err)?
        .label("points")
        .legend(|(x, y)| Circle::new((x, y), 3, RGBColor(140, 140, 140).filled()));
    let mut on_front: Vec<(f64, f64)> = results.iter().filter(|r| front(r)).map(|r| at(r)).collect();
    on_front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let red = RGBColor(220, 40, 40);
    chart
        .draw_series(LineSeries::new(on_front.clone(), red.stroke_width(2)))
        .map_err(plot_err)?
        .label("Pareto front")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], red.stroke_width(2)));
    chart
        .draw_series(on_front.iter().map(|p| Circle::new(*p, 4, red.filled())))
        .map_err(plot_err)?;
    let blue = RGBColor(30, 90, 230);
    chart
        .draw_series(
            results
                .iter()
                .filter(|r| r.key == DEFAULT_KEY)
                .map(|r| TriangleMarker::new(at(r), 8, blue.filled())),
        )
        .map_err(plot_err)?
        .label("default settings")
        .legend(move |(x, y)| TriangleMarker::new((x, y), 6, blue.filled()));
    chart
        .draw_series(std::iter::once(Cross::new((1.0, y_min), 8, BLACK.stroke_width(2))))
        .map_err(plot_err)?
        .label("rt (the reference; error 0)")
        .legend(|(x, y)| Cross::new((x, y), 5, BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(plot_err)?;
    Ok(())
}

/// The plot of `results` (their first scene) as PNG bytes, 1400x600.
pub fn pareto_png(results: &[PointResult]) -> Result<Vec<u8>> {
    register_font()?;
    let scene = results
        .first()
        .map(|r| r.scene.clone())
        .ok_or_else(|| Error::Input("plot: no points".into()))?;
    let mine: Vec<&PointResult> = results.iter().filter(|r| r.scene == scene).collect();
    let (w, h) = (1400u32, 600u32);
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let (left, right) = root.split_horizontally(w / 2);
        panel(
            &left,
            &mine,
            &format!("{scene}: {} points, time vs SSIM", mine.len()),
            "1 - SSIM vs rt",
            &|r| 1.0 - r.ssim,
            &|r| r.pareto_ssim,
        )?;
        panel(
            &right,
            &mine,
            &format!("{scene}: time vs FLIP"),
            "mean FLIP vs rt",
            &|r| r.flip,
            &|r| r.pareto_flip,
        )?;
        root.present().map_err(plot_err)?;
    }
    let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    crate::output::png_bytes(&rgba, w, h)
}
