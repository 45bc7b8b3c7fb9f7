//! A window that runs a RON scene in real time and draws every body with its rugosity band.
//!
//! Run: `cargo run --release --features viewer --example viewer -- [SCENE] [--band-scale K]
//! [--screenshot PNG [--after SECONDS]]` (default scene `assets/scenes/default.ron`).
//!
//! Keys: Space pauses and resumes, S or the Right arrow takes one step of
//! `settings.time_step` (while paused), R reloads the scene from the start. A left click on a
//! dynamic body pushes it *away from the click*: its centre of mass gets a velocity change of
//! [`PUSH_SPEED`] along the direction from the click point to the centre (straight up for a
//! click on the centre). Static bodies (grey) are not pushed.
//!
//! Each body is drawn as its sampled spline curve, a translucent strip between the offset
//! curves `c(u) ± k λ(u) n(u)` (the tolerance band, `k` = `--band-scale`, default 4, since
//! millimetre bands are under a pixel at true scale) and, when the outline is star-shaped
//! about the centre of mass, a light fill, all in the body's colour of the plots and frames
//! (`rugosa::report::body_colour`). The HUD shows the simulated time, whether the run is
//! paused, the body count and the stage-time total (`Profile::total`) per step of the steps
//! taken in the last frame.
//!
//! `--screenshot PNG` runs unattended: once the simulated time reaches `--after` seconds
//! (default 1.5) it saves the window to `PNG` and exits (`scripts/viewer-screenshot.sh` uses it
//! under Xvfb).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use glam::DVec2;
use hecs::Entity;
use macroquad::Window;
use macroquad::color::{BLACK, Color, WHITE};
use macroquad::input::{KeyCode, MouseButton, is_key_pressed, is_mouse_button_pressed, mouse_position};
use macroquad::shapes::{draw_circle_lines, draw_line, draw_rectangle, draw_triangle};
use macroquad::text::draw_text;
use macroquad::texture::get_screen_data;
use macroquad::time::get_frame_time;
use macroquad::window::{Conf, clear_background, next_frame, screen_height, screen_width};
use rugosa::{BodyName, RigidState, Rugosity, Scene, Simulation, Spline, Static};

/// Velocity change (m/s) a click gives the body under the cursor.
const PUSH_SPEED: f64 = 1.5;
/// Longest frame time (s) fed to `Simulation::advance`: a slow frame slows the run down
/// instead of piling up steps.
const MAX_FRAME_DT: f64 = 0.05;
/// Curve samples per spline segment.
const SAMPLES_PER_SEGMENT: usize = 12;
/// Height of the HUD strip at the top of the window (px).
const HUD_HEIGHT: f32 = 58.0;
/// Run a RON scene in real time in a window, each body drawn with its rugosity band.
///
/// Keys: Space pauses and resumes, S or Right steps (while paused), R reloads the scene. A left
/// click pushes the dynamic body under the cursor away from the click.
#[derive(Parser, Debug)]
struct Options {
    /// The scene file (RON).
    #[arg(default_value = "assets/scenes/default.ron")]
    scene: PathBuf,
    /// Factor applied to λ when drawing the band (millimetre bands are under a pixel at true scale).
    #[arg(long, value_name = "K", default_value_t = 4.0)]
    #[arg(value_parser = finite_non_negative, allow_negative_numbers = true)]
    band_scale: f64,
    /// Save the window to this PNG file and exit once the simulated time reaches --after.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
    /// Simulated time (s) of the screenshot.
    #[arg(long, value_name = "SECONDS", default_value_t = 1.5)]
    #[arg(value_parser = finite_non_negative, allow_negative_numbers = true)]
    after: f64,
}

/// A finite, non-negative number.
fn finite_non_negative(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err("expected a finite number >= 0".to_owned()),
    }
}

/// What is drawn of one body, in its own frame (centre of mass at the origin).
struct BodyShape {
    entity: Entity,
    label: String,
    is_static: bool,
    colour: Color,
    /// The spline, for picking with the mouse.
    spline: Spline,
    curve: Vec<DVec2>,
    inner: Vec<DVec2>,
    outer: Vec<DVec2>,
    /// Whether a triangle fan from the origin fills the curve without overlaps.
    star_shaped: bool,
}

impl BodyShape {
    /// Samples the curve of `entity` and its band `c(u) ± band_scale λ(u) n(u)`.
    fn new(sim: &Simulation, entity: Entity, index: usize, band_scale: f64) -> Option<Self> {
        let world = sim.world();
        let spline = Spline::clone(&*world.get::<&Spline>(entity).ok()?);
        let rugosity = world.get::<&Rugosity>(entity).ok()?;
        let is_static = world.get::<&Static>(entity).is_ok();
        let label = world.get::<&BodyName>(entity).map_or_else(|_| index.to_string(), |n| n.0.clone());
        let (curve, inner, outer) = sample_band(&spline, &rugosity, band_scale);
        let star_shaped = curve.iter().zip(curve.iter().cycle().skip(1)).all(|(a, b)| a.perp_dot(*b) > 0.0);
        let colour = body_colour(index, is_static);
        Some(Self { entity, label, is_static, colour, spline, curve, inner, outer, star_shaped })
    }
}

/// The curve and the two edges of its band, sampled at the same parameters.
fn sample_band(spline: &Spline, rugosity: &Rugosity, band_scale: f64) -> (Vec<DVec2>, Vec<DVec2>, Vec<DVec2>) {
    let segments = spline.segment_count();
    let samples = segments * SAMPLES_PER_SEGMENT;
    let (mut curve, mut inner, mut outer) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..samples {
        let u = segments as f64 * k as f64 / samples as f64;
        let (point, normal) = (spline.position(u), spline.outward_normal(u));
        let offset = band_scale * rugosity.tolerance_at(u) * normal;
        curve.push(point);
        inner.push(point - offset);
        outer.push(point + offset);
    }
    (curve, inner, outer)
}

/// The body's colour in every picture of a run (`rugosa::report::body_colour`), as macroquad's.
fn body_colour(index: usize, is_static: bool) -> Color {
    let (r, g, b) = rugosa::report::body_colour(index, is_static);
    Color::from_rgba(r, g, b, 255)
}

fn with_alpha(colour: Color, alpha: f32) -> Color {
    Color { a: alpha, ..colour }
}

/// The world window: a fixed centre and extent, scaled to the window each frame.
#[derive(Clone, Copy)]
struct View {
    centre: DVec2,
    size: DVec2,
}

impl View {
    /// A window holding every body's band at its initial pose, with a 10 % margin.
    fn fit(sim: &Simulation, shapes: &[BodyShape]) -> Self {
        let (mut low, mut high) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for shape in shapes {
            let Some(state) = sim.state(shape.entity) else { continue };
            for &p in &shape.outer {
                let p = state.pose().transform_point(p);
                (low, high) = (low.min(p), high.max(p));
            }
        }
        if !(low.is_finite() && high.is_finite()) {
            return Self { centre: DVec2::ZERO, size: DVec2::splat(2.0) };
        }
        Self { centre: 0.5 * (low + high), size: 1.1 * (high - low).max(DVec2::splat(0.1)) }
    }

    /// Pixels per metre, and the screen position of the world centre.
    fn frame(self) -> (f64, DVec2) {
        let (width, height) = (f64::from(screen_width()), f64::from(screen_height() - HUD_HEIGHT));
        let scale = (width / self.size.x).min(height / self.size.y);
        (scale, DVec2::new(0.5 * width, f64::from(HUD_HEIGHT) + 0.5 * height))
    }

    fn to_screen(self, p: DVec2) -> (f32, f32) {
        let (scale, origin) = self.frame();
        let d = (p - self.centre) * scale;
        ((origin.x + d.x) as f32, (origin.y - d.y) as f32)
    }

    fn to_world(self, (x, y): (f32, f32)) -> DVec2 {
        let (scale, origin) = self.frame();
        self.centre + DVec2::new(f64::from(x) - origin.x, origin.y - f64::from(y)) / scale
    }
}

/// The running scene and the viewer's state.
struct Viewer {
    sim: Simulation,
    shapes: Vec<BodyShape>,
    view: View,
    paused: bool,
    /// Interpolation factor of the drawn poses.
    alpha: f64,
    /// Stage-time total per step, over the steps of the last frame that took any.
    step_time: Duration,
    events: usize,
    /// The last push: body label and world click point.
    last_push: Option<(String, DVec2)>,
}

impl Viewer {
    /// Builds the scene's simulation and samples every body.
    fn new(scene: &Scene, band_scale: f64) -> Result<Self, rugosa::SceneError> {
        let sim = scene.build()?;
        let shapes: Vec<BodyShape> =
            sim.bodies().enumerate().filter_map(|(i, e)| BodyShape::new(&sim, e, i, band_scale)).collect();
        let view = View::fit(&sim, &shapes);
        Ok(Self { sim, shapes, view, paused: false, alpha: 1.0, step_time: Duration::ZERO, events: 0, last_push: None })
    }

    /// Advances by the frame time, or one step on S / Right while paused.
    fn update(&mut self) {
        if !self.paused {
            self.alpha = self.sim.advance(f64::from(get_frame_time()).min(MAX_FRAME_DT));
        } else if is_key_pressed(KeyCode::S) || is_key_pressed(KeyCode::Right) {
            self.sim.step(self.sim.settings().time_step);
            self.alpha = 1.0;
        }
        self.events += self.sim.drain_events().count();
        let profile = self.sim.take_profile();
        if profile.steps > 0 {
            self.step_time = profile.total() / u32::try_from(profile.steps).unwrap_or(u32::MAX);
        }
    }

    /// The drawn (interpolated) state of a body.
    fn drawn_state(&self, shape: &BodyShape) -> RigidState {
        self.sim.interpolated_state(shape.entity, self.alpha).unwrap_or_default()
    }

    /// Pushes the dynamic body under `click` (world) away from it by [`PUSH_SPEED`].
    fn push(&mut self, click: DVec2) {
        let hit = self.shapes.iter().filter(|s| !s.is_static).find(|s| {
            let local = self.drawn_state(s).pose().inverse_transform_point(click);
            s.spline.winding_number(local) != 0
        });
        let Some(shape) = hit else { return };
        let Ok(mut state) = self.sim.world_mut().get::<&mut RigidState>(shape.entity) else { return };
        let away = (state.position - click).try_normalize().unwrap_or(DVec2::Y);
        state.linear_velocity += PUSH_SPEED * away;
        self.last_push = Some((shape.label.clone(), click));
    }

    fn draw(&self) {
        clear_background(WHITE);
        for shape in &self.shapes {
            draw_body(shape, &self.drawn_state(shape), &self.view);
        }
        if let Some((_, click)) = &self.last_push {
            let (x, y) = self.view.to_screen(*click);
            draw_circle_lines(x, y, 6.0, 1.5, BLACK);
        }
    }

    fn draw_hud(&self, options: &Options) {
        draw_rectangle(0.0, 0.0, screen_width(), HUD_HEIGHT, Color::new(0.93, 0.93, 0.93, 1.0));
        let status = if self.paused { "PAUSED" } else { "running" };
        let line = format!(
            "{}   t = {:.3} s   {status}   bodies {}   step {:.0} µs   events {}",
            options.scene.display(),
            self.sim.time(),
            self.sim.body_count(),
            self.step_time.as_secs_f64() * 1e6,
            self.events,
        );
        draw_text(&line, 10.0, 22.0, 22.0, BLACK);
        let push = self.last_push.as_ref().map_or_else(String::new, |(label, _)| format!("   last push: {label}"));
        let help = format!(
            "Space pause   S/Right step   R reset   click: push a body away from the cursor ({PUSH_SPEED} m/s)   band ×{}{push}",
            options.band_scale
        );
        draw_text(&help, 10.0, 46.0, 20.0, Color::new(0.25, 0.25, 0.25, 1.0));
    }
}

/// The band strip, the fill and the curve of one body at `state`.
fn draw_body(shape: &BodyShape, state: &RigidState, view: &View) {
    let pose = state.pose();
    let screen = |points: &[DVec2]| -> Vec<(f32, f32)> {
        points.iter().map(|&p| view.to_screen(pose.transform_point(p))).collect()
    };
    let (curve, inner, outer) = (screen(&shape.curve), screen(&shape.inner), screen(&shape.outer));
    if shape.star_shaped {
        let centre = view.to_screen(state.position);
        for (a, b) in closed_pairs(&curve) {
            draw_triangle(centre.into(), a.into(), b.into(), with_alpha(shape.colour, 0.12));
        }
    }
    let band = with_alpha(shape.colour, 0.35);
    for ((i0, i1), (o0, o1)) in closed_pairs(&inner).zip(closed_pairs(&outer)) {
        draw_triangle(i0.into(), o0.into(), o1.into(), band);
        draw_triangle(i0.into(), o1.into(), i1.into(), band);
    }
    for (a, b) in closed_pairs(&curve) {
        draw_line(a.0, a.1, b.0, b.1, 1.5, shape.colour);
    }
}

/// Consecutive pairs of a closed polyline, the last point paired with the first.
fn closed_pairs<T: Copy>(points: &[T]) -> impl Iterator<Item = (T, T)> + '_ {
    points.iter().copied().zip(points.iter().copied().cycle().skip(1))
}

/// Saves the window to `path` (opaque: the blended alpha channel is set to 255).
fn save_screenshot(path: &std::path::Path) {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        let _ = std::fs::create_dir_all(dir);
    }
    let mut image = get_screen_data();
    image.bytes.chunks_exact_mut(4).for_each(|pixel| pixel[3] = 255);
    image.export_png(&path.to_string_lossy());
    println!("saved {}", path.display());
}

/// The frame loop: input, step, draw; exits after the screenshot if one was asked for.
async fn run(scene: Scene, options: Options, mut viewer: Viewer) {
    loop {
        if is_key_pressed(KeyCode::Space) {
            viewer.paused = !viewer.paused;
        }
        if is_key_pressed(KeyCode::R) {
            match Viewer::new(&scene, options.band_scale) {
                Ok(fresh) => viewer = Viewer { paused: viewer.paused, ..fresh },
                Err(e) => eprintln!("error: {e}"),
            }
        }
        if is_mouse_button_pressed(MouseButton::Left) {
            viewer.push(viewer.view.to_world(mouse_position()));
        }
        viewer.update();
        viewer.draw();
        viewer.draw_hud(&options);
        if let Some(path) = options.screenshot.as_deref().filter(|_| viewer.sim.time() >= options.after) {
            save_screenshot(path);
            return;
        }
        next_frame().await;
    }
}

fn window_conf() -> Conf {
    Conf {
        window_title: "rugosa viewer".to_owned(),
        window_width: 1280,
        window_height: 720,
        sample_count: 4,
        window_resizable: true,
        ..Conf::default()
    }
}

fn main() -> ExitCode {
    let options = Options::parse();
    let scene = match Scene::load(&options.scene) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let viewer = match Viewer::new(&scene, options.band_scale) {
        Ok(viewer) => viewer,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    Window::from_config(window_conf(), run(scene, options, viewer));
    ExitCode::SUCCESS
}
