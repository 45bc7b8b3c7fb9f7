//! Animation frames of a recording with each body's rugosity band (the seed's Figure 12).

use super::*;

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
}
