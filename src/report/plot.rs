//! PNG plots of a [`Recording`]: the friction coefficient of each event (the seed's Figure 8),
//! the velocities of the dynamic bodies against normalized time (Figures 10–11), and
//! animation frames with each body's rugosity band (Figure 12).
//!
//! Text uses DejaVu Sans, bundled in `assets/fonts/` (Bitstream Vera licence, beside it), so
//! no system font is needed.

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use glam::DVec2;
use plotters::coord::Shift;
use plotters::prelude::*;
use rand_distr::{Distribution, Normal};

use super::{BodyInfo, Recording, ReportError, StateSample, create_dir};
use crate::components::RigidState;
use crate::events::EventKind;

/// The bundled font, registered with plotters as `sans-serif` on first use.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FONT_FAMILY: &str = "sans-serif";

/// How animation frames are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStyle {
    /// Image width (px); the height follows the scene's aspect ratio, within 300..=900 px.
    pub width: u32,
    /// Factor applied to the tolerance when drawing the band (1 = true scale). Bands of a few
    /// millimetres are under a pixel wide in a metre-wide view; the factor is printed on the frame.
    pub band_scale: f64,
    /// Outline samples per segment.
    pub samples_per_segment: usize,
    /// Seed of the synthesized surface perturbation.
    pub seed: u64,
}

impl Default for FrameStyle {
    fn default() -> Self {
        Self { width: 1200, band_scale: 4.0, samples_per_segment: 12, seed: 1 }
    }
}

/// Writes `dir/friction.png`, `dir/velocity.png` and `frames` animation frames in
/// `dir/frames/NNNN.png`. Returns the number of frames written.
///
/// # Errors
/// [`ReportError`] naming the file that could not be written.
pub fn write_plots(recording: &Recording, dir: &Path, frames: usize, style: &FrameStyle) -> Result<usize, ReportError> {
    create_dir(dir)?;
    plot_friction(recording, &dir.join("friction.png"))?;
    plot_velocity(recording, &dir.join("velocity.png"))?;
    render_frames(recording, &dir.join("frames"), frames, style)
}

fn register_font() {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    REGISTERED.get_or_init(|| plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT).is_ok());
}

fn plot_error(path: &Path, error: impl std::fmt::Display) -> ReportError {
    ReportError::Plot { path: path.to_owned(), message: error.to_string() }
}

fn kind_colour(kind: EventKind) -> RGBColor {
    match kind {
        EventKind::Collision => RGBColor(90, 90, 90),
        EventKind::Sticking => RGBColor(31, 119, 180),
        EventKind::Sliding => RGBColor(214, 39, 40),
        EventKind::MicroCollision => RGBColor(44, 160, 44),
        EventKind::Resting => RGBColor(148, 103, 189),
    }
}

/// μ of every event against its index, coloured by kind (the seed's Figure 8).
///
/// # Errors
/// [`ReportError::Plot`] naming `path`.
pub fn plot_friction(recording: &Recording, path: &Path) -> Result<(), ReportError> {
    register_font();
    let root = BitMapBackend::new(path, (1000, 450)).into_drawing_area();
    draw_friction(&root, recording).map_err(|e| plot_error(path, e))?;
    root.present().map_err(|e| plot_error(path, e))
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn draw_friction(root: &DrawingArea<BitMapBackend<'_>, Shift>, recording: &Recording) -> DrawResult {
    root.fill(&WHITE)?;
    let count = recording.events.len().max(1);
    let mu_max = recording.events.iter().map(|e| e.event.mu).fold(0.0, f64::max);
    let y_top = if mu_max > 0.0 { 1.1 * mu_max } else { 1.0 };
    let mut chart = ChartBuilder::on(root)
        .caption("Friction coefficient of each contact event", (FONT_FAMILY, 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..count as f64, 0.0..y_top)?;
    chart
        .configure_mesh()
        .x_desc("event index")
        .y_desc("μ")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .label_style((FONT_FAMILY, 14))
        .draw()?;
    for (kind, n) in recording.events_by_kind() {
        let colour = kind_colour(kind);
        let points = recording.events.iter().enumerate().filter(|(_, e)| e.event.kind == kind);
        chart
            .draw_series(points.map(|(i, e)| Circle::new((i as f64, e.event.mu), 2, colour.filled())))?
            .label(format!("{} ({n})", kind.name()))
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, colour.filled()));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    Ok(())
}

/// `vx`, `vy` and `ω` of every dynamic body against time reparametrized to `[0, 1]` (the
/// seed's Figures 10–11), one panel each.
///
/// # Errors
/// [`ReportError::Plot`] naming `path`.
pub fn plot_velocity(recording: &Recording, path: &Path) -> Result<(), ReportError> {
    register_font();
    let root = BitMapBackend::new(path, (1000, 900)).into_drawing_area();
    draw_velocity(&root, recording).map_err(|e| plot_error(path, e))?;
    root.present().map_err(|e| plot_error(path, e))
}

/// A plotted quantity: panel title, axis description and accessor.
type Panel = (&'static str, &'static str, fn(&RigidState) -> f64);

/// The three plotted quantities.
const VELOCITY_PANELS: [Panel; 3] = [
    ("horizontal velocity", "vx (m/s)", |s| s.linear_velocity.x),
    ("vertical velocity", "vy (m/s)", |s| s.linear_velocity.y),
    ("angular velocity", "ω (rad/s)", |s| s.angular_velocity),
];

fn draw_velocity(root: &DrawingArea<BitMapBackend<'_>, Shift>, recording: &Recording) -> DrawResult {
    root.fill(&WHITE)?;
    let end = recording.end_time().max(f64::MIN_POSITIVE);
    let dynamic: Vec<usize> = (0..recording.bodies.len()).filter(|&b| !recording.bodies[b].is_static).collect();
    for (panel, (title, axis, value)) in root.split_evenly((3, 1)).iter().zip(VELOCITY_PANELS) {
        let series: Vec<(usize, Vec<(f64, f64)>)> = dynamic
            .iter()
            .map(|&b| (b, body_samples(recording, b).map(|s| (s.time / end, value(&s.state))).collect()))
            .collect();
        let range = padded_range(series.iter().flat_map(|(_, points)| points.iter().map(|p| p.1)));
        let mut chart = ChartBuilder::on(panel)
            .caption(title, (FONT_FAMILY, 18))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, range)?;
        chart.configure_mesh().x_desc("t / T").y_desc(axis).label_style((FONT_FAMILY, 13)).draw()?;
        for (b, points) in series {
            let colour = body_colour(recording, b);
            chart
                .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
                .label(recording.bodies[b].label.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2)));
        }
        chart.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    }
    Ok(())
}

/// Grey for static bodies, else the body's colour in the 99-colour palette.
fn body_colour(recording: &Recording, body: usize) -> RGBColor {
    if recording.bodies[body].is_static {
        return RGBColor(120, 120, 120);
    }
    let (r, g, b) = Palette99::pick(body).rgb();
    RGBColor(r, g, b)
}

fn body_samples(recording: &Recording, body: usize) -> impl Iterator<Item = &StateSample> {
    recording.states.iter().filter(move |s| s.body == body)
}

/// `[min, max]` of `values` widened by 5 % (and to a unit range if they are all equal).
fn padded_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (low, high) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if !(low.is_finite() && high.is_finite()) {
        return -1.0..1.0;
    }
    let pad = if high - low > 1e-9 { 0.05 * (high - low) } else { 0.5 };
    (low - pad)..(high + pad)
}

/// One body's outline in its own frame: the curve, the band's edges and a synthesized rough
/// surface, all sampled at the same parameters.
struct BandOutline {
    inner: Vec<DVec2>,
    outer: Vec<DVec2>,
    rough: Vec<DVec2>,
}

/// Samples a body's band; the rough surface is the curve displaced along the normal by
/// `N(0, (λ/3)²)` noise clamped to the band (the band is `R = 3 S`, MODEL §2), seeded per body.
fn band_outline(body: &BodyInfo, style: &FrameStyle, seed: u64) -> BandOutline {
    let segments = body.spline.segment_count();
    let samples = segments * style.samples_per_segment.max(1);
    let mut rng = crate::random::seeded(seed);
    let unit = Normal::new(0.0, 1.0 / 3.0).ok();
    let mut band = BandOutline { inner: Vec::new(), outer: Vec::new(), rough: Vec::new() };
    for k in 0..samples {
        let u = segments as f64 * k as f64 / samples as f64;
        let (point, normal) = (body.spline.position(u), body.spline.outward_normal(u));
        let lambda = body.rugosity.tolerance_at(u) * style.band_scale;
        let noise: f64 = unit.map_or(0.0, |n| n.sample(&mut rng));
        let noise = noise.clamp(-1.0, 1.0);
        band.inner.push(point - lambda * normal);
        band.outer.push(point + lambda * normal);
        band.rough.push(point + noise * lambda * normal);
    }
    band
}

/// The states of all bodies at each sampled time, in time order.
fn snapshots(recording: &Recording) -> Vec<(f64, Vec<RigidState>)> {
    let mut out: Vec<(f64, Vec<RigidState>)> = Vec::new();
    for sample in &recording.states {
        match out.last_mut() {
            Some((time, states)) if *time == sample.time => states.push(sample.state),
            _ => out.push((sample.time, vec![sample.state])),
        }
    }
    out
}

/// Writes `count` frames evenly spaced over the recording into `dir/NNNN.png`; returns how many.
///
/// # Errors
/// [`ReportError`] naming the directory or the frame that could not be written.
pub fn render_frames(
    recording: &Recording,
    dir: &Path,
    count: usize,
    style: &FrameStyle,
) -> Result<usize, ReportError> {
    let snapshots = snapshots(recording);
    if count == 0 || snapshots.is_empty() {
        return Ok(0);
    }
    register_font();
    create_dir(dir)?;
    let bands: Vec<BandOutline> =
        recording.bodies.iter().enumerate().map(|(i, b)| band_outline(b, style, style.seed + i as u64)).collect();
    let view = View::fit(recording, &snapshots, style);
    for frame in 0..count {
        let pick = if count == 1 { 0 } else { frame * (snapshots.len() - 1) / (count - 1) };
        let (time, states) = &snapshots[pick];
        let path = dir.join(format!("{frame:04}.png"));
        let root = BitMapBackend::new(&path, (view.width, view.height)).into_drawing_area();
        draw_frame(&root, recording, &bands, states, *time, &view, style).map_err(|e| plot_error(&path, e))?;
        root.present().map_err(|e| plot_error(&path, e))?;
    }
    Ok(count)
}

/// The world window shown in every frame, and the image size that keeps its aspect ratio.
struct View {
    x: Range<f64>,
    y: Range<f64>,
    width: u32,
    height: u32,
}

impl View {
    /// A window holding every body at every sampled time, with a 5 % margin.
    fn fit(recording: &Recording, snapshots: &[(f64, Vec<RigidState>)], style: &FrameStyle) -> Self {
        let corners: Vec<[DVec2; 4]> = recording.bodies.iter().map(|b| body_box_corners(b, style.band_scale)).collect();
        let (mut low, mut high) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for (_, states) in snapshots {
            for (state, corners) in states.iter().zip(&corners) {
                let pose = state.pose();
                for corner in corners {
                    low = low.min(pose.transform_point(*corner));
                    high = high.max(pose.transform_point(*corner));
                }
            }
        }
        let width = style.width;
        let size = (high - low).max(DVec2::splat(1e-3));
        let (low, size) = (low - 0.05 * size, 1.1 * size);
        let height = (f64::from(width) * size.y / size.x).clamp(300.0, 900.0);
        // Widen the shorter side so one metre is as long on both axes.
        let scale = (f64::from(width) / size.x).min(height / size.y);
        let (half_x, half_y) = (0.5 * f64::from(width) / scale, 0.5 * height / scale);
        let centre = low + 0.5 * size;
        Self {
            x: (centre.x - half_x)..(centre.x + half_x),
            y: (centre.y - half_y)..(centre.y + half_y),
            width,
            height: height as u32,
        }
    }
}

/// Corners of a body's bounding box in its own frame, widened by its drawn band.
fn body_box_corners(body: &BodyInfo, band_scale: f64) -> [DVec2; 4] {
    let (low, high) = body.spline.bounds();
    let band = DVec2::splat(body.rugosity.max_tolerance() * band_scale);
    let (low, high) = (low - band, high + band);
    [low, DVec2::new(high.x, low.y), high, DVec2::new(low.x, high.y)]
}

fn draw_frame(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    recording: &Recording,
    bands: &[BandOutline],
    states: &[RigidState],
    time: f64,
    view: &View,
    style: &FrameStyle,
) -> DrawResult {
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root).margin(4).build_cartesian_2d(view.x.clone(), view.y.clone())?;
    for (b, (band, state)) in bands.iter().zip(states).enumerate() {
        let pose = state.pose();
        let world = |points: &[DVec2]| -> Vec<(f64, f64)> {
            points.iter().map(|&p| pose.transform_point(p)).map(|p| (p.x, p.y)).collect()
        };
        let colour = body_colour(recording, b);
        chart.draw_series(std::iter::once(Polygon::new(world(&band.outer), colour.mix(0.25).filled())))?;
        chart.draw_series(std::iter::once(Polygon::new(world(&band.inner), WHITE.filled())))?;
        chart.draw_series(std::iter::once(Polygon::new(world(&band.inner), colour.mix(0.55).filled())))?;
        let mut rough = world(&band.rough);
        rough.extend(rough.first().copied());
        chart.draw_series(std::iter::once(PathElement::new(rough, colour.stroke_width(1))))?;
    }
    let text = format!("t = {time:.3} s    rugosity band drawn ×{}", style.band_scale);
    root.draw_text(&text, &(FONT_FAMILY, 18).into_font().color(&BLACK), (12, 10))?;
    Ok(())
}
