//! `docs/img/versus_rapier.png`: step time against N for the pile, and error against cost.

use std::path::Path;

use plotters::prelude::*;

/// The bundled font, registered with plotters as `sans-serif` (no system font needed).
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// One line of a log-log panel.
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points `(x, y)`, both positive.
    pub points: Vec<(f64, f64)>,
    /// Colour index.
    pub colour: usize,
    /// Dashed (drawn as points only) instead of solid.
    pub dashed: bool,
}

const COLOURS: [RGBColor; 4] =
    [RGBColor(214, 39, 40), RGBColor(31, 119, 180), RGBColor(44, 160, 44), RGBColor(90, 90, 90)];

/// Writes two log-log panels side by side.
///
/// # Errors
/// The plotting error, as text.
pub fn write(
    path: &Path,
    left: (&str, &str, &str, &[Series]),
    right: (&str, &str, &str, &[Series]),
) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).map_err(|_| "font".to_owned())?;
    let root = BitMapBackend::new(path, (1400, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (a, b) = root.split_horizontally(700);
    panel(&a, left)?;
    panel(&b, right)?;
    root.present().map_err(|e| e.to_string())
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

fn panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    spec: (&str, &str, &str, &[Series]),
) -> Result<(), String> {
    let (title, x_label, y_label, series) = spec;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(range(series, |p| p.0).log_scale(), range(series, |p| p.1).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_labels(6)
        .y_labels(6)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    for s in series {
        let colour = COLOURS[s.colour % COLOURS.len()];
        let points = s.points.iter().copied().filter(|p| p.0 > 0.0 && p.1 > 0.0);
        let style = if s.dashed { colour.mix(0.5).stroke_width(1) } else { colour.stroke_width(2) };
        chart
            .draw_series(LineSeries::new(points.clone(), style))
            .map_err(|e| e.to_string())?
            .label(s.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        chart.draw_series(points.map(|p| Circle::new(p, 4, colour.filled()))).map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|e| e.to_string())
}
