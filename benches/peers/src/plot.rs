//! Log-log figures of the comparison: one per analytic case (error against wall time) and one
//! of step time against pile size. The legend sits beside the plot, never on the data; every
//! engine keeps one colour in every figure.

use std::path::Path;

use plotters::prelude::*;

use crate::engine::Peer;

/// The bundled font, registered with plotters as `sans-serif` (no system font needed).
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// How a line is drawn: the engine's exact shapes, fine polygons, coarse polygons.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stroke {
    /// Thick solid line, filled markers.
    Bold,
    /// Thin solid line, hollow markers.
    Thin,
    /// Faint line, small markers.
    Faint,
}

/// One line of a log-log plot.
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points `(x, y)`; those not positive are left out.
    pub points: Vec<(f64, f64)>,
    /// The engine (its colour).
    pub peer: Peer,
    /// The stroke.
    pub stroke: Stroke,
}

/// One colour per engine, the same in every figure.
#[must_use]
pub fn colour(peer: Peer) -> RGBColor {
    match peer {
        Peer::Rugosa => RGBColor(214, 39, 40),
        Peer::Box2d => RGBColor(44, 160, 44),
        Peer::RapierF32 => RGBColor(31, 119, 180),
        Peer::RapierF64 => RGBColor(148, 103, 189),
    }
}

/// Axis titles and the plot's title.
pub struct Axes<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// x-axis title, with its unit.
    pub x: &'a str,
    /// y-axis title, with its unit.
    pub y: &'a str,
}

/// Writes one log-log plot with its legend to the right of it.
///
/// # Errors
/// The plotting error, as text.
pub fn write(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).map_err(|_| "font".to_owned())?;
    let root = BitMapBackend::new(path, (1100, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (plot, legend) = root.split_horizontally(760);
    let mut chart = ChartBuilder::on(&plot)
        .caption(axes.title, ("sans-serif", 19))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(76)
        .build_cartesian_2d(range(series, |p| p.0).log_scale(), range(series, |p| p.1).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(axes.x)
        .y_desc(axes.y)
        .x_labels(6)
        .y_labels(7)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    for s in series {
        let (line, marker) = style(s);
        let points: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| p.0 > 0.0 && p.1 > 0.0).collect();
        chart.draw_series(LineSeries::new(points.iter().copied(), line)).map_err(|e| e.to_string())?;
        chart.draw_series(points.iter().map(|&p| Circle::new(p, marker.0, marker.1))).map_err(|e| e.to_string())?;
    }
    draw_legend(&legend, series)?;
    root.present().map_err(|e| e.to_string())
}

fn style(s: &Series) -> (ShapeStyle, (i32, ShapeStyle)) {
    let c = colour(s.peer);
    match s.stroke {
        Stroke::Bold => (c.stroke_width(3), (5, c.filled())),
        Stroke::Thin => (c.stroke_width(1), (4, c.stroke_width(1))),
        Stroke::Faint => (c.mix(0.45).stroke_width(1), (2, c.mix(0.45).filled())),
    }
}

fn draw_legend(area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>, series: &[Series]) -> Result<(), String> {
    let font = ("sans-serif", 14).into_font().color(&BLACK);
    for (k, s) in series.iter().enumerate() {
        let y = 60 + 24 * k as i32;
        let (line, marker) = style(s);
        area.draw(&PathElement::new(vec![(10, y), (46, y)], line)).map_err(|e| e.to_string())?;
        area.draw(&Circle::new((28, y), marker.0, marker.1)).map_err(|e| e.to_string())?;
        area.draw(&Text::new(s.label.clone(), (54, y - 8), font.clone())).map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn range(series: &[Series], pick: impl Fn(&(f64, f64)) -> f64) -> std::ops::Range<f64> {
    let values = series.iter().flat_map(|s| s.points.iter().map(&pick)).filter(|v| *v > 0.0);
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo.is_finite() { lo / 1.5..hi * 1.5 } else { 0.1..10.0 }
}

/// A log-axis tick: whole numbers from 1 up, one significant digit below.
fn tick(value: f64) -> String {
    if value >= 1.0 { format!("{value:.0}") } else { format!("{value:.0e}") }
}
