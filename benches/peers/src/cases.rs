//! Cases with an analytic answer, where curves matter: each engine against the same reference,
//! error against wall time over a sweep of the step.
//!
//! Every body is placed where its engine holds it at rest: rugosa's with its curve half the
//! combined band (1 mm) from the other's, so it starts in contact; the peers' exactly touching
//! (their contacts are speculative). rugosa's bodies carry a band of 1 mm (its default
//! `min_band`) with the friction law's λ_min = 0, so μ is μ_max whatever the band.

use std::f64::consts::PI;
use std::time::{Duration, Instant};

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity, SimulationSettings, Spline};

use crate::engine::{self, Peer, Reading, Setup, Variant};
use crate::scenes::SceneSpec;
use crate::shapes::{Natural, ShapeChoice};

/// Standard gravity (m/s²).
const G: f64 = 9.81;
/// rugosa's band on every body of these cases (m).
const BAND: f64 = 1e-3;
/// The steps swept (s).
pub const STEPS: [f64; 6] = [1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 480.0, 1.0 / 960.0];
/// Segments of rugosa's discs.
const DISC_SEGMENTS: usize = 32;

/// One case: a scene per engine, a reading per step, one error.
pub struct Case {
    /// Short name.
    pub name: &'static str,
    /// The set-up, for the report.
    pub setup: String,
    /// The reference and how it is computed.
    pub reference: String,
    /// What the error is.
    pub error_definition: &'static str,
    /// What bounds each engine's error here (mechanisms, for the report).
    pub notes: String,
    /// Simulated time (s).
    pub horizon: f64,
    /// Engines and shapes compared.
    pub variants: Vec<Variant>,
    /// The scene, with the observed body's curve this far from the surface it rests on (m).
    scene: fn(f64) -> SceneSpec,
    /// Index of the observed body.
    body: usize,
    /// The observation and its error.
    observer: fn() -> Box<dyn Observer>,
}

/// Follows the observed body and gives the case's error at the end.
trait Observer {
    /// State at time `t` (after a step).
    fn record(&mut self, t: f64, reading: Reading);
    /// The normalised error.
    fn error(&self) -> f64;
}

/// One point of error against cost.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Step (s).
    pub dt: f64,
    /// Normalised error.
    pub error: f64,
    /// Wall time of the whole horizon, stepping only (median of [`REPEATS`] runs).
    pub wall: Duration,
}

/// Runs per point; the wall time is their median (the runs agree exactly in the state).
const REPEATS: usize = 3;

impl Case {
    /// The error and wall time of `variant` at each step of [`STEPS`].
    #[must_use]
    pub fn sweep(&self, variant: Variant) -> Vec<Point> {
        STEPS.iter().map(|&dt| self.point(variant, dt)).collect()
    }

    fn point(&self, variant: Variant, dt: f64) -> Point {
        let gap = if variant.peer == Peer::Rugosa { BAND } else { 0.0 };
        let spec = (self.scene)(gap);
        let steps = (self.horizon / dt).round() as usize;
        let setup = Setup { dt, threads: 1, sleep: false };
        let mut walls = Vec::with_capacity(REPEATS);
        let mut error = f64::NAN;
        for _ in 0..REPEATS {
            let (mut world, _) = engine::build(variant, &spec, setup);
            let mut observer = (self.observer)();
            let mut wall = Duration::ZERO;
            for k in 1..=steps {
                let start = Instant::now();
                engine::advance(world.as_mut(), &spec);
                wall += start.elapsed();
                observer.record(k as f64 * dt, world.reading(self.body));
            }
            walls.push(wall);
            error = observer.error();
        }
        walls.sort();
        Point { dt, error, wall: walls[REPEATS / 2] }
    }
}

/// All cases.
#[must_use]
pub fn all() -> Vec<Case> {
    vec![incline(), bowl(), ellipse(), slide(), bounce()]
}

fn variants(circles: bool) -> Vec<Variant> {
    let mut out = vec![Variant::RUGOSA];
    for peer in [Peer::Box2d, Peer::RapierF32, Peer::RapierF64] {
        if circles {
            out.push(Variant { peer, shapes: ShapeChoice::natural(1e-4) });
        }
        for relative in [1e-3, 1e-4] {
            out.push(Variant { peer, shapes: ShapeChoice::polygon(relative) });
        }
    }
    out
}

fn material(mu: f64, restitution: f64) -> Material {
    Material {
        density: 1000.0,
        restitution,
        restitution_max: restitution.max(0.5),
        friction: FrictionLaw { lambda_min: 0.0, mu_max: mu },
    }
}

fn body(spline: Spline, material: Material) -> BodyDesc {
    let segments = spline.segment_count();
    BodyDesc::new(spline, Rugosity::constant(segments, BAND).expect("a band")).with_material(material)
}

/// Flat ground 40 m wide whose top is the line y = 0.
fn ground(material: Material) -> BodyDesc {
    let spline =
        Generator::RoundedRectangle { width: 40.0, height: 1.0, corner_radius: 0.1 }.build(32).expect("a ground");
    body(spline, material).at(DVec2::new(0.0, -0.5), 0.0).fixed()
}

fn disc(radius: f64, material: Material) -> BodyDesc {
    body(Generator::Circle { radius }.build(DISC_SEGMENTS).expect("a disc"), material)
}

fn settings(gravity: DVec2) -> SimulationSettings {
    SimulationSettings { gravity, record_events: false, ..SimulationSettings::default() }
}

/// Largest distance of rugosa's disc curve from the exact circle, for the report.
#[must_use]
pub fn disc_deviation(radius: f64) -> f64 {
    Generator::Circle { radius }.max_deviation(DISC_SEGMENTS).expect("a disc")
}

// ---------------------------------------------------------------- incline

const INCLINE_ANGLE: f64 = 0.3;
const INCLINE_RADIUS: f64 = 0.5;
const INCLINE_TIME: f64 = 1.0;

fn incline() -> Case {
    let reference = G * INCLINE_ANGLE.sin() * INCLINE_TIME * INCLINE_TIME / 3.0;
    Case {
        name: "incline",
        setup: format!(
            "disc r = {INCLINE_RADIUS} m (rugosa: {DISC_SEGMENTS} segments) released from rest on a slope of \
             {INCLINE_ANGLE} rad (gravity turned, ground flat), μ = 0.6 (rolls without slipping: tan θ = 0.31 ≤ 3μ), \
             e = 0, {INCLINE_TIME} s"
        ),
        reference: format!("analytic: distance (1/3) g sin θ t² = {reference:.4} m (acceleration (2/3) g sin θ)"),
        error_definition: "|distance along the slope − reference| / reference",
        notes: format!(
            "rugosa rests with its curve half the combined band (1 mm) from the ground and its contact point \
             halfway across, so its disc rolls on R = r + 0.5 mm: acceleration g sin θ / (1 + r²/(2R²)), {:.1e} \
             above the nominal, whatever the step — its floor here, proportional to the band. The peers' exact \
             circles converge at first order in the step. A polygon rolls over its vertices and loses energy at \
             each; Box2D's, a fan of small triangles (see the shapes above), does so most.",
            rolling_excess(INCLINE_RADIUS)
        ),
        horizon: INCLINE_TIME,
        variants: variants(true),
        scene: |gap| {
            let m = material(0.6, 0.0);
            let gravity = G * DVec2::new(INCLINE_ANGLE.sin(), -INCLINE_ANGLE.cos());
            let bodies = vec![ground(m), disc(INCLINE_RADIUS, m).at(DVec2::new(-5.0, INCLINE_RADIUS + gap), 0.0)];
            SceneSpec::new("incline", bodies, settings(gravity))
                .with_natural(1, Natural::Circle { radius: INCLINE_RADIUS })
        },
        body: 1,
        observer: || Box::new(Distance { start: -5.0, last: f64::NAN, reference: G * INCLINE_ANGLE.sin() / 3.0 }),
    }
}

/// Relative excess of the acceleration of a disc of radius `r` rolling on radius r + BAND/2
/// (rugosa's contact point, halfway across the combined band) over the nominal (2/3) g sin θ.
fn rolling_excess(r: f64) -> f64 {
    let rolling = r + 0.5 * BAND;
    1.5 / (1.0 + r * r / (2.0 * rolling * rolling)) - 1.0
}

/// Distance along x at the horizon against `reference × t²` (incline) or a fixed distance.
struct Distance {
    start: f64,
    last: f64,
    reference: f64,
}

impl Observer for Distance {
    fn record(&mut self, _t: f64, reading: Reading) {
        self.last = reading.position.x;
    }

    fn error(&self) -> f64 {
        let reference =
            if self.reference > 0.0 { self.reference * INCLINE_TIME * INCLINE_TIME } else { -self.reference };
        ((self.last - self.start - reference) / reference).abs()
    }
}

// ---------------------------------------------------------------- bowl

const BOWL_RADIUS: f64 = 1.0;
const BOWL_DISC: f64 = 0.25;
const BOWL_AMPLITUDE: f64 = 0.2;
/// Centre of the bowl's circle: its lowest point is the origin.
const BOWL_CENTRE: DVec2 = DVec2::new(0.0, BOWL_RADIUS);

/// Period of the disc rolling in the bowl: a pendulum of length L = 3 (R − r) / 2 (rolling
/// without slipping), 4 √(L/g) K(sin(φ0/2)) at amplitude φ0, K by the arithmetic-geometric mean.
fn bowl_period() -> f64 {
    let length = 1.5 * (BOWL_RADIUS - BOWL_DISC);
    let k = (0.5 * BOWL_AMPLITUDE).sin();
    let (mut a, mut b) = (1.0, (1.0 - k * k).sqrt());
    while (a - b).abs() > 1e-16 * a {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    4.0 * (length / G).sqrt() * PI / (2.0 * a)
}

/// A static cup: the annular sector between radii R and R + 0.3 m about the bowl's centre,
/// ±1 rad about the bottom, with round ends, as an interpolating spline through points about
/// 1 cm apart (its inner arc is within 1e-9 m of the circle where the disc rolls).
fn bowl_spline() -> Spline {
    let (inner, width, half) = (BOWL_RADIUS, 0.3, 1.0);
    let outer = inner + width;
    let spacing = 0.01;
    let u = |a: f64| DVec2::new(a.cos(), a.sin());
    let (a0, a1) = (-0.5 * PI - half, -0.5 * PI + half);
    let mut points = Vec::new();
    let arc = |radius: f64, from: f64, to: f64, points: &mut Vec<DVec2>| {
        let n = ((to - from).abs() * radius / spacing).ceil() as usize;
        points.extend((0..n).map(|k| BOWL_CENTRE + radius * u(from + (to - from) * k as f64 / n as f64)));
    };
    arc(outer, a0, a1, &mut points);
    // Right end: from the outer to the inner arc around the end.
    let cap = |angle: f64, sign: f64, points: &mut Vec<DVec2>| {
        let middle = BOWL_CENTRE + (inner + 0.5 * width) * u(angle);
        let tangent = u(angle).perp();
        let n = ((0.5 * width * PI) / spacing).ceil() as usize;
        points.extend((0..n).map(|k| {
            let psi = PI * k as f64 / n as f64;
            middle + 0.5 * width * (sign * psi.cos() * u(angle) + psi.sin() * sign * tangent)
        }));
    };
    cap(a1, 1.0, &mut points);
    arc(inner, a1, a0, &mut points);
    cap(a0, -1.0, &mut points);
    Spline::interpolating(&points).expect("a bowl")
}

fn bowl() -> Case {
    let period = bowl_period();
    Case {
        name: "bowl",
        setup: format!(
            "disc r = {BOWL_DISC} m released from rest at φ0 = {BOWL_AMPLITUDE} rad inside a fixed circular bowl R = \
             {BOWL_RADIUS} m (rugosa: an interpolating spline of the cup; peers: the cup's polygon at the stated \
             tolerance as a static loop), μ = 0.8, e = 0, 3 periods"
        ),
        reference: format!(
            "analytic: rolling without slipping is a pendulum of length 3 (R − r)/2; period 4 √(L/g) K(sin(φ0/2)) = \
             {period:.6} s (small-oscillation 2π √(3 (R − r)/(2g)) = {:.6} s)",
            2.0 * PI * (1.5 * (BOWL_RADIUS - BOWL_DISC) / G).sqrt()
        ),
        error_definition: "|period − reference| / reference, the period from the zero crossings of φ over the run",
        notes: format!(
            "rugosa's disc centre runs on a circle 1 mm inside R − r and rolls on r + 0.5 mm (its rest gap in the \
             band): the period of that geometry, 2π √((R − r − d)(1 + r²/(2ρ²))/g) at small amplitude, is {:.1e} \
             off the nominal — its floor. The peers roll their circles on the cup's polygon (1e-4 of the disc \
             size) and their errors wander with the step: a rolling contact over polygon vertices. Box2D's \
             polygon discs (fans of small triangles) mostly stop before three crossings (error 1).",
            {
                let (d, r, rho) = (BAND, BOWL_DISC, BOWL_DISC + 0.5 * BAND);
                let ratio = ((BOWL_RADIUS - r - d) * (1.0 + r * r / (2.0 * rho * rho))) / ((BOWL_RADIUS - r) * 1.5);
                (ratio.sqrt() - 1.0).abs()
            }
        ),
        horizon: 3.1 * period,
        variants: variants(true),
        scene: |gap| {
            let m = material(0.8, 0.0);
            let distance = BOWL_RADIUS - BOWL_DISC - gap;
            let at = BOWL_CENTRE + distance * DVec2::new(BOWL_AMPLITUDE.sin(), -BOWL_AMPLITUDE.cos());
            let bodies = vec![body(bowl_spline(), m).fixed(), disc(BOWL_DISC, m).at(at, 0.0)];
            SceneSpec::new("bowl", bodies, settings(DVec2::new(0.0, -G)))
                .with_natural(1, Natural::Circle { radius: BOWL_DISC })
        },
        body: 1,
        observer: || {
            Box::new(Period {
                signal: |r| (r.position.x - BOWL_CENTRE.x).atan2(BOWL_CENTRE.y - r.position.y),
                previous: None,
                crossings: Vec::new(),
                reference: bowl_period(),
            })
        },
    }
}

/// Period from the zero crossings of a signal (linear interpolation between steps).
struct Period {
    signal: fn(&Reading) -> f64,
    previous: Option<(f64, f64)>,
    crossings: Vec<f64>,
    reference: f64,
}

impl Observer for Period {
    fn record(&mut self, t: f64, reading: Reading) {
        let s = (self.signal)(&reading);
        if let Some((t0, s0)) = self.previous
            && s0 * s < 0.0
        {
            self.crossings.push(t0 + (t - t0) * s0 / (s0 - s));
        }
        if s != 0.0 {
            self.previous = Some((t, s));
        }
    }

    fn error(&self) -> f64 {
        let n = self.crossings.len();
        if n < 3 {
            // No oscillation left to measure: the whole period is lost.
            return 1.0;
        }
        let period = 2.0 * (self.crossings[n - 1] - self.crossings[0]) / (n - 1) as f64;
        ((period - self.reference) / self.reference).abs().min(1.0)
    }
}

// ---------------------------------------------------------------- ellipse

const ELLIPSE_A: f64 = 0.5;
const ELLIPSE_B: f64 = 0.25;
const ELLIPSE_TILT: f64 = 0.1;

/// Height of the ellipse's centre above flat ground at tilt θ (its support function).
fn ellipse_height(theta: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    (ELLIPSE_A * ELLIPSE_A * s * s + ELLIPSE_B * ELLIPSE_B * c * c).sqrt()
}

/// The rocking ellipse's angular acceleration (rolling without slipping on flat ground).
///
/// The contact point P is the instantaneous centre, so T = ½ J(θ) θ'², J = I_c + m |c − P|²,
/// and U = m g h(θ). With (per unit mass) I_c = (a² + b²)/4, h² = a² sin²θ + b² cos²θ and
/// |c − P|² = (a⁴ sin²θ + b⁴ cos²θ)/h², Lagrange gives J θ'' + ½ J'(θ) θ'² + g h'(θ) = 0.
fn ellipse_acceleration(theta: f64, omega: f64) -> f64 {
    let (a2, b2) = (ELLIPSE_A * ELLIPSE_A, ELLIPSE_B * ELLIPSE_B);
    let (s, c) = theta.sin_cos();
    let d = a2 * s * s + b2 * c * c;
    let n = a2 * a2 * s * s + b2 * b2 * c * c;
    let j = 0.25 * (a2 + b2) + n / d;
    let (dn, dd) = (2.0 * (a2 * a2 - b2 * b2) * s * c, 2.0 * (a2 - b2) * s * c);
    let dj = (dn * d - n * dd) / (d * d);
    let dh = (a2 - b2) * s * c / d.sqrt();
    -(0.5 * dj * omega * omega + G * dh) / j
}

/// Period of the rocking from the exact rolling equation, by classical Runge–Kutta at 1e-5 s
/// over three periods (zero crossings interpolated by a cubic Hermite step); and the
/// linearised period 2π √((I_c + m b²)/(m g (a²/b − b))) it must approach at small tilt.
#[must_use]
pub fn ellipse_period() -> (f64, f64) {
    ellipse_period_from(ELLIPSE_TILT)
}

fn ellipse_period_from(tilt: f64) -> (f64, f64) {
    let h = 1e-5;
    let (mut t, mut theta, mut omega) = (0.0, tilt, 0.0);
    let mut crossings = Vec::new();
    while crossings.len() < 7 {
        let f = |th: f64, om: f64| (om, ellipse_acceleration(th, om));
        let k1 = f(theta, omega);
        let k2 = f(theta + 0.5 * h * k1.0, omega + 0.5 * h * k1.1);
        let k3 = f(theta + 0.5 * h * k2.0, omega + 0.5 * h * k2.1);
        let k4 = f(theta + h * k3.0, omega + h * k3.1);
        let next = theta + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
        let next_omega = omega + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        if theta * next < 0.0 {
            // Newton on the cubic Hermite interpolant of θ over the step.
            let mut x = theta / (theta - next);
            for _ in 0..8 {
                let (x2, x3) = (x * x, x * x * x);
                let value = (2.0 * x3 - 3.0 * x2 + 1.0) * theta
                    + (x3 - 2.0 * x2 + x) * h * omega
                    + (-2.0 * x3 + 3.0 * x2) * next
                    + (x3 - x2) * h * next_omega;
                let slope = (6.0 * x2 - 6.0 * x) * theta
                    + (3.0 * x2 - 4.0 * x + 1.0) * h * omega
                    + (-6.0 * x2 + 6.0 * x) * next
                    + (3.0 * x2 - 2.0 * x) * h * next_omega;
                x -= value / slope;
            }
            crossings.push(t + x * h);
        }
        (theta, omega, t) = (next, next_omega, t + h);
    }
    let n = crossings.len();
    let period = 2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64;
    let (a2, b2) = (ELLIPSE_A * ELLIPSE_A, ELLIPSE_B * ELLIPSE_B);
    let linear = 2.0 * PI * ((0.25 * (a2 + b2) + b2) / (G * (a2 / ELLIPSE_B - ELLIPSE_B))).sqrt();
    (period, linear)
}

fn ellipse() -> Case {
    let (period, linear) = ellipse_period();
    Case {
        name: "ellipse",
        setup: format!(
            "ellipse a = {ELLIPSE_A} m, b = {ELLIPSE_B} m (rugosa: 32 segments) resting on its flattest point, released \
             from rest at a tilt of {ELLIPSE_TILT} rad on flat ground, μ = 1 (no slip), e = 0, 3 periods; the peers have \
             no ellipse, so polygons only"
        ),
        reference: format!(
            "the exact rolling equation J(θ) θ'' + ½ J'(θ) θ'² + g h'(θ) = 0 integrated by RK4 at 1e-5 s: period \
             {period:.6} s (the linearised period 2π √((I_c + m b²)/(m g (a²/b − b))) = {linear:.6} s; they differ \
             by {:.2e}, the amplitude's effect)",
            (period - linear).abs() / linear
        ),
        error_definition: "|period − reference| / reference, from the zero crossings of the angle; 1 when fewer \
                           than 3 crossings (the rocking died)",
        notes: "Curve on flat ground: the contact point travels along the curve, so the period depends on the \
                curvature near the flattest point (ρ = a²/b = 1 m). A polygon's curvature is zero on its edges and \
                infinite at its vertices: the polygon rocks on its vertices with an impact at each, which \
                dissipates (e = 0) — the rocking dies (error 1) or its period drifts. rugosa follows the curve; \
                its error falls with the step."
            .to_owned(),
        horizon: 3.1 * period,
        variants: variants(false),
        scene: |gap| {
            let m = material(1.0, 0.0);
            let spline = Generator::Ellipse { a: ELLIPSE_A, b: ELLIPSE_B }.build(32).expect("an ellipse");
            let at = DVec2::new(0.0, ellipse_height(ELLIPSE_TILT) + gap);
            let bodies = vec![ground(m), body(spline, m).at(at, ELLIPSE_TILT)];
            SceneSpec::new("ellipse", bodies, settings(DVec2::new(0.0, -G)))
        },
        body: 1,
        observer: || {
            Box::new(Period {
                signal: |r| r.angle,
                previous: None,
                crossings: Vec::new(),
                reference: ellipse_period().0,
            })
        },
    }
}

// ---------------------------------------------------------------- slide

const SLIDE_V0: f64 = 3.0;
const SLIDE_MU: f64 = 0.5;

fn slide() -> Case {
    let distance = SLIDE_V0 * SLIDE_V0 / (2.0 * SLIDE_MU * G);
    Case {
        name: "slide",
        setup: format!(
            "block 1 × 0.5 m (corners rounded at 2 cm; the peers' own rounded box) launched at v0 = {SLIDE_V0} m/s on \
             flat ground, μ = {SLIDE_MU}, e = 0; it stops at {:.3} s, read at 1 s",
            SLIDE_V0 / (SLIDE_MU * G)
        ),
        reference: format!("analytic: distance v0²/(2 μ g) = {distance:.4} m"),
        error_definition: "|distance − reference| / reference",
        notes: "A flat face on flat ground: no curve involved, every engine has the exact shape. The peers' \
                error is first order in the step (semi-implicit Euler: the block decelerates one step late); \
                rugosa moves a touching body at the mean of its velocities before and after the sub-step, exact for \
                a constant deceleration, so what remains is the stop falling inside a step."
            .to_owned(),
        horizon: 1.0,
        variants: vec![
            Variant::RUGOSA,
            Variant { peer: Peer::Box2d, shapes: ShapeChoice::natural(1e-4) },
            Variant { peer: Peer::RapierF32, shapes: ShapeChoice::natural(1e-4) },
            Variant { peer: Peer::RapierF64, shapes: ShapeChoice::natural(1e-4) },
        ],
        scene: |gap| {
            let m = material(SLIDE_MU, 0.0);
            let spline = Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.02 }
                .build(24)
                .expect("a block");
            let block =
                body(spline, m).at(DVec2::new(0.0, 0.25 + gap), 0.0).with_velocity(DVec2::new(SLIDE_V0, 0.0), 0.0);
            SceneSpec::new("slide", vec![ground(m), block], settings(DVec2::new(0.0, -G)))
                .with_natural(1, Natural::RoundedBox { half: DVec2::new(0.5, 0.25), radius: 0.02 })
        },
        body: 1,
        observer: || {
            Box::new(Distance { start: 0.0, last: f64::NAN, reference: -SLIDE_V0 * SLIDE_V0 / (2.0 * SLIDE_MU * G) })
        },
    }
}

// ---------------------------------------------------------------- bounce

const BOUNCE_RADIUS: f64 = 0.25;
const BOUNCE_DROP: f64 = 1.0;
const BOUNCE_E: f64 = 0.8;
const BOUNCE_APEXES: usize = 3;

fn bounce() -> Case {
    Case {
        name: "bounce",
        setup: format!(
            "frictionless disc r = {BOUNCE_RADIUS} m dropped with its lowest point h0 = {BOUNCE_DROP} m above flat \
             ground, e = {BOUNCE_E} (rugosa: e_max = e too), 2.3 s"
        ),
        reference: "analytic: apex k = e^(2k) h0, k = 1, 2, 3".to_owned(),
        error_definition: "max over the first 3 apexes of |apex − e^(2k) h0| / h0, the apex of the lowest point \
                           (centre − r) read as y + v_y²/(2g) at the first state after the top",
        notes: format!(
            "rugosa bounces off the outer edge of the band, so every apex measured from the curves' contact is \
             low by about (1 − e^(2k)) × the impact gap: {:.1e} at k = 3 for the 1 mm band of each body (up to \
             twice that for the combined band) — its floor, proportional to the band and flat in the step. The \
             peers' soft contacts with speculative margins give up restitution at first order in the step.",
            (1.0 - BOUNCE_E.powi(6)) * BAND / BOUNCE_DROP
        ),
        horizon: 2.3,
        variants: variants(true),
        scene: |gap| {
            let m = material(0.0, BOUNCE_E);
            let at = DVec2::new(0.0, BOUNCE_RADIUS + BOUNCE_DROP + gap);
            let bodies = vec![ground(m), disc(BOUNCE_RADIUS, m).at(at, 0.0)];
            SceneSpec::new("bounce", bodies, settings(DVec2::new(0.0, -G)))
                .with_natural(1, Natural::Circle { radius: BOUNCE_RADIUS })
        },
        body: 1,
        observer: || Box::new(Apexes { previous_vy: 0.0, apexes: Vec::new() }),
    }
}

/// Apex heights of the lowest point, read after each top.
struct Apexes {
    previous_vy: f64,
    apexes: Vec<f64>,
}

impl Observer for Apexes {
    fn record(&mut self, _t: f64, reading: Reading) {
        let vy = reading.velocity.y;
        if self.previous_vy > 0.0 && vy <= 0.0 && self.apexes.len() < BOUNCE_APEXES {
            self.apexes.push(reading.position.y + vy * vy / (2.0 * G) - BOUNCE_RADIUS);
        }
        self.previous_vy = vy;
    }

    fn error(&self) -> f64 {
        (1..=BOUNCE_APEXES)
            .map(|k| {
                let apex = self.apexes.get(k - 1).copied().unwrap_or(0.0);
                (apex - BOUNCE_DROP * BOUNCE_E.powi(2 * k as i32)).abs() / BOUNCE_DROP
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rolling_ellipse_reference_approaches_its_linearisation() {
        // The amplitude lengthens the period at second order (J grows and the restoring torque
        // softens away from the flattest point): the excess over the linearised period must
        // shrink 100-fold from a tilt of 0.1 rad to 0.01 rad, and vanish with it.
        let excess = |tilt: f64| {
            let (period, linear) = ellipse_period_from(tilt);
            (period - linear) / linear
        };
        let (large, small) = (excess(0.1), excess(0.01));
        assert!(small > 0.0 && small < 5e-4, "excess at 0.01 rad: {small}");
        assert!((large / small - 100.0).abs() < 5.0, "excess ratio {}", large / small);
    }

    #[test]
    fn the_bowl_period_is_the_pendulum_period() {
        // Small amplitude: K(k) = π/2 (1 + k²/4 + …), so T ≈ T0 (1 + φ0²/16).
        let t0 = 2.0 * PI * (1.5 * (BOWL_RADIUS - BOWL_DISC) / G).sqrt();
        let expected = t0 * (1.0 + BOWL_AMPLITUDE * BOWL_AMPLITUDE / 16.0);
        assert!((bowl_period() - expected).abs() / expected < 1e-5);
    }

    #[test]
    fn the_bowl_spline_is_the_circle_where_the_disc_rolls() {
        let spline = bowl_spline();
        let worst = (0..20_000)
            .map(|k| spline.position(k as f64 * spline.segment_count() as f64 / 20_000.0))
            .filter(|p| (p.x - BOWL_CENTRE.x).abs() < 0.5 && p.distance(BOWL_CENTRE) < BOWL_RADIUS + 0.15)
            .map(|p| (p.distance(BOWL_CENTRE) - BOWL_RADIUS).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "inner arc off the circle by {worst}");
    }
}
