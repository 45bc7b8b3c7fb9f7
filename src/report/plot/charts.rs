//! The charts of a recording: μ of each event (the seed's Figure 8) and the velocities against
//! time (Figures 10–11).

use super::*;

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_event_kind_has_its_own_marker_shape() {
        let shapes: Vec<Vec<(i32, i32)>> = EventKind::ALL.iter().map(|&k| marker_outline(k, 4)).collect();
        for (i, shape) in shapes.iter().enumerate() {
            assert!(shape.len() >= 3, "{:?}", EventKind::ALL[i]);
            assert!(shapes[i + 1..].iter().all(|other| other != shape), "{:?} repeats a shape", EventKind::ALL[i]);
        }
    }
}
