//! PNG plots of a [`Recording`]: the friction coefficient of each event (the seed's Figure 8),
//! the velocities of the dynamic bodies against time (Figures 10–11), and animation frames
//! with each body's rugosity band (Figure 12).
//!
//! Every picture is meant to be read without the code: each names its bodies (their
//! [`Recording::body_name`]), gives each body the one colour of [`body_colour`] (the viewer's
//! too), states its units, and keeps its legend in a column beside the data.
//!
//! Text uses DejaVu Sans, bundled in `assets/fonts/` (Bitstream Vera licence, beside it), so
//! no system font is needed.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use glam::DVec2;
use plotters::coord::Shift;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rand_distr::{Distribution, Normal};

use super::{BodyInfo, Recording, ReportError, StateSample, body_colour, create_dir};
use crate::components::RigidState;
use crate::events::EventKind;

/// The bundled font, registered with plotters as `sans-serif` on first use.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FONT_FAMILY: &str = "sans-serif";

/// Width of the legend column beside a plot's data (px).
const LEGEND_WIDTH: u32 = 290;
/// Height of a plot's header: its title and a line saying what is drawn (px).
const HEADER_HEIGHT: u32 = 56;
/// Height of one legend line (px).
const LEGEND_LINE: i32 = 21;
/// Grey of secondary text (notes, empty legend entries).
const NOTE_GREY: RGBColor = RGBColor(100, 100, 100);

/// How animation frames are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStyle {
    /// Image width (px); the height follows the scene's aspect ratio, within 300..=900 px, plus
    /// a strip at the top for the time and the scale bar.
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

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The colour of body `body` of `recording` ([`body_colour`]).
fn colour_of(recording: &Recording, body: usize) -> RGBColor {
    let (r, g, b) = body_colour(body, is_static(recording, body));
    RGBColor(r, g, b)
}

fn is_static(recording: &Recording, body: usize) -> bool {
    recording.bodies.get(body).is_some_and(|b| b.is_static)
}

fn font(size: u32, colour: &RGBColor) -> TextStyle<'_> {
    (FONT_FAMILY, size).into_font().color(colour)
}

/// Draws a title and, under it in grey, what the picture shows; returns the area below.
fn draw_header<'a>(area: &Area<'a>, title: &str, subtitle: &str) -> Result<Area<'a>, Box<dyn std::error::Error>> {
    let (header, rest) = area.split_vertically(HEADER_HEIGHT);
    let centre = i32::try_from(header.dim_in_pixel().0 / 2)?;
    let centred = Pos::new(HPos::Center, VPos::Top);
    header.draw_text(title, &font(22, &BLACK).pos(centred), (centre, 6))?;
    header.draw_text(subtitle, &font(14, &NOTE_GREY).pos(centred), (centre, 34))?;
    Ok(rest)
}

/// A legend drawn line by line down a column of its own, beside the data.
struct Legend<'a, 'b> {
    area: &'a Area<'b>,
    y: i32,
}

impl<'a, 'b> Legend<'a, 'b> {
    fn new(area: &'a Area<'b>) -> Self {
        Self { area, y: 14 }
    }

    /// Whether `lines` more lines fit in the column.
    fn fits(&self, lines: i32) -> bool {
        i64::from(self.y + lines * LEGEND_LINE) <= i64::from(self.area.dim_in_pixel().1)
    }

    /// A heading, with a gap above it unless it is the first line.
    fn heading(&mut self, text: &str) -> DrawResult {
        if self.y > 14 {
            self.y += LEGEND_LINE / 2;
        }
        self.text(text, 0, &BLACK, 15)
    }

    /// An indented line of grey text.
    fn note(&mut self, text: &str) -> DrawResult {
        self.text(text, 8, &NOTE_GREY, 13)
    }

    /// An entry: `swatch` is drawn centred at the given pixel, the text to its right.
    fn entry(
        &mut self,
        text: &str,
        colour: &RGBColor,
        swatch: impl FnOnce(&Area<'b>, (i32, i32)) -> DrawResult,
    ) -> DrawResult {
        swatch(self.area, (22, self.y))?;
        self.text(text, 40, colour, 14)
    }

    fn text(&mut self, text: &str, x: i32, colour: &RGBColor, size: u32) -> DrawResult {
        let style = font(size, colour).pos(Pos::new(HPos::Left, VPos::Center));
        self.area.draw_text(text, &style, (x, self.y))?;
        self.y += LEGEND_LINE;
        Ok(())
    }
}

/// An event marker: a filled outline and its edge, in pixels about a point of type `C`.
type Marker<C, DB> = ComposedElement<C, DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>>;

/// `(event index, μ)` of a pair's events, by kind in [`EventKind::ALL`] order.
type PointsByKind = [Vec<(f64, f64)>; 5];

/// A marker of an event of `kind` at `at`, filled with `colour`; `size` is its half-width (px).
/// Its shape tells the kind.
fn event_marker<C, DB: DrawingBackend>(at: C, kind: EventKind, size: i32, colour: RGBColor) -> Marker<C, DB> {
    let outline = marker_outline(kind, size);
    let mut closed = outline.clone();
    closed.extend(outline.first().copied());
    EmptyElement::at(at) + Polygon::new(outline, colour.filled()) + PathElement::new(closed, colour.stroke_width(1))
}

/// Draws markers of `kind` at `points` on `area` in a pair's colours: with an edge, every
/// marker's edge goes down before any fill, so that a dense run of markers reads as a line of
/// the fill colour edged in the other, not as the edge colour alone.
fn draw_pair_markers<C: Clone, CT: CoordTranslate<From = C>>(
    area: &DrawingArea<BitMapBackend<'_>, CT>,
    points: &[C],
    kind: EventKind,
    size: i32,
    (fill, edge): (RGBColor, Option<RGBColor>),
) -> DrawResult {
    if let Some(edge) = edge {
        for at in points {
            area.draw(&event_marker(at.clone(), kind, size + 2, edge))?;
        }
    }
    for at in points {
        area.draw(&event_marker(at.clone(), kind, size, fill))?;
    }
    Ok(())
}

/// The outline of an event marker of half-width `size` (px) about its centre: a disc for resting
/// contacts, a triangle for sticking, a square for sliding, a diamond for micro-collisions and
/// a cross for frictionless collisions.
fn marker_outline(kind: EventKind, size: i32) -> Vec<(i32, i32)> {
    let s = f64::from(size);
    let polar = |radius: f64, degrees: f64| {
        let (sin, cos) = degrees.to_radians().sin_cos();
        ((radius * cos).round() as i32, (-radius * sin).round() as i32)
    };
    match kind {
        EventKind::Resting => (0..12).map(|k| polar(s, 30.0 * f64::from(k))).collect(),
        EventKind::Sticking => [90.0, 210.0, 330.0].map(|d| polar(1.25 * s, d)).to_vec(),
        EventKind::Sliding => [45.0, 135.0, 225.0, 315.0].map(|d| polar(1.2 * s, d)).to_vec(),
        EventKind::MicroCollision => [0.0, 90.0, 180.0, 270.0].map(|d| polar(1.3 * s, d)).to_vec(),
        EventKind::Collision => (0..4)
            .flat_map(|arm| {
                let d = 45.0 + 90.0 * f64::from(arm);
                [polar(1.3 * s, d - 20.0), polar(1.3 * s, d + 20.0), polar(0.5 * s, d + 45.0)]
            })
            .collect(),
    }
}

/// The pair of an event in the order a legend names it: a moving body before a static one,
/// else the lower spawn index first.
fn ordered_pair(recording: &Recording, a: usize, b: usize) -> (usize, usize) {
    let key = |body| (is_static(recording, body), body);
    if key(a) <= key(b) { (a, b) } else { (b, a) }
}

/// μ of every event against its index (the seed's Figure 8): one colour per body pair (the
/// first body's; an edge in the second's when both move), one marker shape per event kind.
///
/// # Errors
/// [`ReportError::Plot`] naming `path`.
pub fn plot_friction(recording: &Recording, path: &Path) -> Result<(), ReportError> {
    register_font();
    let pairs = friction_series(recording).len();
    // Room for every pair in the legend, up to 900 px.
    let height = (330 + LEGEND_LINE * i32::try_from(pairs).unwrap_or(i32::MAX)).clamp(450, 900);
    let root = BitMapBackend::new(path, (1200, height as u32)).into_drawing_area();
    draw_friction(&root, recording).map_err(|e| plot_error(path, e))?;
    root.present().map_err(|e| plot_error(path, e))
}

/// The events of one body pair.
struct PairSeries {
    pair: (usize, usize),
    by_kind: PointsByKind,
}

impl PairSeries {
    fn count(&self) -> usize {
        self.by_kind.iter().map(Vec::len).sum()
    }
}

/// The events grouped by body pair, pairs in legend order.
fn friction_series(recording: &Recording) -> Vec<PairSeries> {
    let mut pairs: BTreeMap<(usize, usize), PointsByKind> = BTreeMap::new();
    for (index, record) in recording.events.iter().enumerate() {
        let pair = ordered_pair(recording, record.body_a, record.body_b);
        let kind = EventKind::ALL.iter().position(|&k| k == record.event.kind).unwrap_or(0);
        pairs.entry(pair).or_default()[kind].push((index as f64, record.event.mu));
    }
    pairs.into_iter().map(|(pair, by_kind)| PairSeries { pair, by_kind }).collect()
}

fn draw_friction(root: &Area<'_>, recording: &Recording) -> DrawResult {
    root.fill(&WHITE)?;
    let series = friction_series(recording);
    let subtitle = match (recording.events.first(), recording.events.last()) {
        (Some(first), Some(last)) => format!(
            "{} events between t = {:.3} s and {:.3} s, numbered in the order they were applied",
            recording.events.len(),
            first.event.time,
            last.event.time
        ),
        _ => "no contact events in this run".to_owned(),
    };
    let body = draw_header(root, "Friction coefficient μ of each contact event", &subtitle)?;
    let (data, legend) = body.split_horizontally(body.dim_in_pixel().0 - LEGEND_WIDTH);
    let count = recording.events.len().max(1);
    let mu_max = recording.events.iter().map(|e| e.event.mu).fold(0.0, f64::max);
    let y_top = if mu_max > 0.0 { 1.1 * mu_max } else { 1.0 };
    let mut chart = ChartBuilder::on(&data)
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(62)
        .build_cartesian_2d(0.0..count as f64, 0.0..y_top)?;
    chart
        .configure_mesh()
        .x_desc("event number (–)")
        .y_desc("friction coefficient μ (–)")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .label_style((FONT_FAMILY, 14))
        .axis_desc_style((FONT_FAMILY, 15))
        .draw()?;
    // The biggest groups first, so that rare pairs and kinds stay visible on top.
    let mut groups: Vec<(&PairSeries, usize)> =
        series.iter().flat_map(|s| (0..EventKind::ALL.len()).map(move |k| (s, k))).collect();
    groups.sort_by_key(|(s, k)| std::cmp::Reverse(s.by_kind[*k].len()));
    for (pair, k) in groups {
        let colours = pair_colours(recording, pair.pair);
        draw_pair_markers(chart.plotting_area(), &pair.by_kind[k], EventKind::ALL[k], 3, colours)?;
    }
    draw_friction_legend(&legend, recording, &series)
}

/// Fill and edge of a pair's markers: the first body's colour, and the second body's as the
/// edge when it moves too.
fn pair_colours(recording: &Recording, (a, b): (usize, usize)) -> (RGBColor, Option<RGBColor>) {
    (colour_of(recording, a), (!is_static(recording, b)).then(|| colour_of(recording, b)))
}

fn draw_friction_legend(area: &Area<'_>, recording: &Recording, series: &[PairSeries]) -> DrawResult {
    let mut legend = Legend::new(area);
    legend.heading("body pair (marker colour)")?;
    // Keep room for the kinds' six lines and the notes below.
    let room = (area.dim_in_pixel().1 as i32 / LEGEND_LINE - 11).max(1) as usize;
    let shown = if series.len() > room { room - 1 } else { series.len() };
    for pair in &series[..shown] {
        let colours = pair_colours(recording, pair.pair);
        let text = format!("{} ({})", recording.pair_name(pair.pair.0, pair.pair.1), pair.count());
        legend.entry(&text, &BLACK, |area, at| draw_pair_markers(area, &[at], EventKind::Resting, 5, colours))?;
    }
    if series.is_empty() {
        legend.note("none: no contact events")?;
    }
    if series.len() > shown {
        let rest: usize = series[shown..].iter().map(PairSeries::count).sum();
        legend.note(&format!("and {} more pairs ({rest} events)", series.len() - shown))?;
    }
    if series.iter().any(|s| !is_static(recording, s.pair.1)) {
        legend.note("fill: first body's colour; edge: second's")?;
    }
    legend.heading("event kind (marker shape)")?;
    for (kind, n) in recording.events_by_kind() {
        let colour = if n == 0 { NOTE_GREY } else { BLACK };
        legend.entry(&format!("{} ({n})", kind.name()), &colour, |area, at| {
            area.draw(&event_marker(at, kind, 5, RGBColor(70, 70, 70)))?;
            Ok(())
        })?;
    }
    if legend.fits(2) {
        legend.note("(number of events in brackets)")?;
    }
    Ok(())
}

/// `vx`, `vy` and `ω` of every dynamic body against time in seconds (the seed's Figures 10–11
/// plot the same against `t / T`), one panel each, one line colour per body.
///
/// # Errors
/// [`ReportError::Plot`] naming `path`.
pub fn plot_velocity(recording: &Recording, path: &Path) -> Result<(), ReportError> {
    register_font();
    let root = BitMapBackend::new(path, (1200, 960)).into_drawing_area();
    draw_velocity(&root, recording).map_err(|e| plot_error(path, e))?;
    root.present().map_err(|e| plot_error(path, e))
}

/// A plotted quantity: panel title, axis description and accessor.
type Panel = (&'static str, &'static str, fn(&RigidState) -> f64);

/// The three plotted quantities.
const VELOCITY_PANELS: [Panel; 3] = [
    ("horizontal velocity of the centre of mass", "vx (m/s)", |s| s.linear_velocity.x),
    ("vertical velocity of the centre of mass (up is positive)", "vy (m/s)", |s| s.linear_velocity.y),
    ("angular velocity (counter-clockwise is positive)", "ω (rad/s)", |s| s.angular_velocity),
];

fn draw_velocity(root: &Area<'_>, recording: &Recording) -> DrawResult {
    root.fill(&WHITE)?;
    let end = recording.end_time();
    let dynamic: Vec<usize> = (0..recording.bodies.len()).filter(|&b| !is_static(recording, b)).collect();
    let subtitle = format!(
        "{} moving {}, sampled from t = 0 to {end:.3} s",
        dynamic.len(),
        if dynamic.len() == 1 { "body" } else { "bodies" }
    );
    let body = draw_header(root, "Velocities of the moving bodies against time", &subtitle)?;
    let (panels, legend) = body.split_horizontally(body.dim_in_pixel().0 - LEGEND_WIDTH);
    for (panel, (title, axis, value)) in panels.split_evenly((3, 1)).iter().zip(VELOCITY_PANELS) {
        let series: Vec<(usize, Vec<(f64, f64)>)> = dynamic
            .iter()
            .map(|&b| (b, body_samples(recording, b).map(|s| (s.time, value(&s.state))).collect()))
            .collect();
        let range = padded_range(series.iter().flat_map(|(_, points)| points.iter().map(|p| p.1)));
        let mut chart = ChartBuilder::on(panel)
            .caption(title, (FONT_FAMILY, 17))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(62)
            .build_cartesian_2d(0.0..end.max(f64::MIN_POSITIVE), range)?;
        chart
            .configure_mesh()
            .x_desc("time t (s)")
            .y_desc(axis)
            .label_style((FONT_FAMILY, 13))
            .axis_desc_style((FONT_FAMILY, 14))
            .draw()?;
        for (b, points) in series {
            chart.draw_series(LineSeries::new(points, colour_of(recording, b).stroke_width(2)))?;
        }
    }
    draw_velocity_legend(&legend, recording, &dynamic)
}

fn draw_velocity_legend(area: &Area<'_>, recording: &Recording, dynamic: &[usize]) -> DrawResult {
    let mut legend = Legend::new(area);
    legend.heading("body (line colour)")?;
    for (shown, &b) in dynamic.iter().enumerate() {
        if !legend.fits(3) {
            legend.note(&format!("and {} more bodies", dynamic.len() - shown))?;
            break;
        }
        let colour = colour_of(recording, b);
        legend.entry(&recording.body_name(b), &BLACK, |area, (x, y)| {
            area.draw(&PathElement::new([(x - 12, y), (x + 12, y)], colour.stroke_width(3)))?;
            Ok(())
        })?;
    }
    let statics: Vec<String> =
        (0..recording.bodies.len()).filter(|&b| is_static(recording, b)).map(|b| recording.body_name(b)).collect();
    if !statics.is_empty() && legend.fits(2) {
        legend.heading("static, not drawn")?;
        legend.note(&statics.join(", "))?;
    }
    Ok(())
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

/// Height of the strip above a frame's world view: time, band scale and scale bar (px).
const FRAME_STRIP: u32 = 36;

/// Writes `count` frames evenly spaced over the recording into `dir/NNNN.png`; returns how many.
/// Each shows the bodies with their bands and names, and above them the simulated time, the
/// band's drawing scale and a scale bar.
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
        let root = BitMapBackend::new(&path, (view.width, view.height + FRAME_STRIP)).into_drawing_area();
        draw_frame(&root, recording, &bands, states, *time, &view, style).map_err(|e| plot_error(&path, e))?;
        root.present().map_err(|e| plot_error(&path, e))?;
    }
    Ok(count)
}

/// The world window shown in every frame, and the size of its part of the image (px), which
/// keeps its aspect ratio.
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
    root: &Area<'_>,
    recording: &Recording,
    bands: &[BandOutline],
    states: &[RigidState],
    time: f64,
    view: &View,
    style: &FrameStyle,
) -> DrawResult {
    root.fill(&WHITE)?;
    let (strip, world_area) = root.split_vertically(FRAME_STRIP);
    let chart = ChartBuilder::on(&world_area).build_cartesian_2d(view.x.clone(), view.y.clone())?;
    for (b, (band, state)) in bands.iter().zip(states).enumerate() {
        let pose = state.pose();
        let world = |points: &[DVec2]| -> Vec<(f64, f64)> {
            points.iter().map(|&p| pose.transform_point(p)).map(|p| (p.x, p.y)).collect()
        };
        let colour = colour_of(recording, b);
        let area = chart.plotting_area();
        area.draw(&Polygon::new(world(&band.outer), colour.mix(0.25).filled()))?;
        area.draw(&Polygon::new(world(&band.inner), WHITE.filled()))?;
        area.draw(&Polygon::new(world(&band.inner), colour.mix(0.55).filled()))?;
        let mut rough = world(&band.rough);
        rough.extend(rough.first().copied());
        area.draw(&PathElement::new(rough, colour.stroke_width(1)))?;
    }
    for (b, state) in states.iter().enumerate() {
        let at = chart.backend_coord(&(state.position.x, state.position.y));
        draw_body_name(root, &recording.body_name(b), colour_of(recording, b), at)?;
    }
    strip.fill(&RGBColor(240, 240, 240))?;
    let left = Pos::new(HPos::Left, VPos::Center);
    let middle = i32::try_from(FRAME_STRIP / 2)?;
    strip.draw_text(&format!("t = {time:.3} s"), &font(18, &BLACK).pos(left), (12, middle))?;
    let band = format!("tolerance bands drawn {}× true width", style.band_scale);
    strip.draw_text(&band, &font(14, &NOTE_GREY).pos(left), (150, middle))?;
    let x_span = view.x.end - view.x.start;
    let metres_per_pixel = x_span / f64::from(view.width);
    draw_scale_bar(&strip, scale_bar_length(0.2 * x_span), metres_per_pixel)
}

/// A body's name centred at pixel `at`, on a pale box edged in the body's colour.
fn draw_body_name(root: &Area<'_>, name: &str, colour: RGBColor, at: (i32, i32)) -> DrawResult {
    let style = font(13, &BLACK).pos(Pos::new(HPos::Center, VPos::Center));
    let (w, h) = root.estimate_text_size(name, &style)?;
    let (half_w, half_h) = (i32::try_from(w / 2)? + 4, i32::try_from(h / 2)? + 2);
    let (width, height) = root.dim_in_pixel();
    // Kept inside the image when a centroid lies near its edge.
    let x = at.0.clamp(half_w, i32::try_from(width)? - half_w);
    let y = at.1.clamp(i32::try_from(FRAME_STRIP)? + half_h, i32::try_from(height)? - half_h);
    let corners = [(x - half_w, y - half_h), (x + half_w, y + half_h)];
    root.draw(&Rectangle::new(corners, WHITE.mix(0.8).filled()))?;
    root.draw(&Rectangle::new(corners, colour.stroke_width(1)))?;
    root.draw_text(name, &style, (x, y))?;
    Ok(())
}

/// A bar `length` metres long at the right end of `strip`, with its length written before it.
fn draw_scale_bar(strip: &Area<'_>, length: f64, metres_per_pixel: f64) -> DrawResult {
    let pixels = (length / metres_per_pixel).round() as i32;
    let right = i32::try_from(strip.dim_in_pixel().0)? - 16;
    let (left, y) = (right - pixels, i32::try_from(FRAME_STRIP / 2)?);
    let ink = BLACK.stroke_width(2);
    strip.draw(&PathElement::new([(left, y), (right, y)], ink))?;
    for x in [left, right] {
        strip.draw(&PathElement::new([(x, y - 6), (x, y + 6)], ink))?;
    }
    let label = font(15, &BLACK).pos(Pos::new(HPos::Right, VPos::Center));
    strip.draw_text(&format_length(length), &label, (left - 8, y))?;
    Ok(())
}

/// The longest of 1, 2 and 5 times a power of ten (m) that is at most `at_most` metres.
fn scale_bar_length(at_most: f64) -> f64 {
    if !(at_most.is_finite() && at_most > 0.0) {
        return 1.0;
    }
    let power = 10f64.powf(at_most.log10().floor());
    [5.0, 2.0, 1.0].into_iter().map(|m| m * power).find(|&l| l <= at_most * (1.0 + 1e-9)).unwrap_or(power)
}

/// A scale bar's length as text: `"0.5 m"`, `"2 m"`, `"0.05 m"`.
fn format_length(metres: f64) -> String {
    let decimals = (-metres.log10().floor()).max(0.0) as usize;
    format!("{metres:.decimals$} m")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bars_are_one_two_or_five_times_a_power_of_ten() {
        for (at_most, length, text) in [
            (0.73, 0.5, "0.5 m"),
            (2.0, 2.0, "2 m"),
            (0.19, 0.1, "0.1 m"),
            (0.049, 0.02, "0.02 m"),
            (37.0, 20.0, "20 m"),
        ] {
            assert!((scale_bar_length(at_most) - length).abs() < 1e-12, "{at_most}: {}", scale_bar_length(at_most));
            assert_eq!(format_length(scale_bar_length(at_most)), text);
        }
    }

    #[test]
    fn every_event_kind_has_its_own_marker_shape() {
        let shapes: Vec<Vec<(i32, i32)>> = EventKind::ALL.iter().map(|&k| marker_outline(k, 4)).collect();
        for (i, shape) in shapes.iter().enumerate() {
            assert!(shape.len() >= 3, "{:?}", EventKind::ALL[i]);
            assert!(shapes[i + 1..].iter().all(|other| other != shape), "{:?} repeats a shape", EventKind::ALL[i]);
        }
    }
}
