//! The cases of the work-precision report: the analytic cases of MODEL §9 (set up as in
//! `tests/validation.rs`) and a multi-contact pile, each reduced to an observable vector and a
//! normalized error against its reference. Shared by `examples/work_precision` and
//! `tests/work_precision.rs` (included with `#[path]`), so the test checks the very cases the
//! report measures.

use std::time::{Duration, Instant};

use glam::DVec2;
use rugosa::{
    BodyDesc, FrictionLaw, Generator, Material, Profile, Rugosity, Simulation, SimulationSettings, SleepSettings,
    Spline,
};

/// Gravity (m/s²).
pub const G: f64 = 9.81;

/// Coarsest step of every step sweep (s); the sweep halves it down to the case's finest step.
pub const COARSEST_STEP: f64 = 1.0 / 30.0;
/// Finest step of the analytic cases' sweeps (s).
pub const ANALYTIC_FINEST_STEP: f64 = 1.0 / 7680.0;
/// Finest step of the pile's sweep (s): 4× its reference step.
pub const PILE_FINEST_STEP: f64 = 1.0 / 3840.0;

/// What the error of a case is measured against.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// The exact observable from a formula.
    Analytic(Vec<f64>),
    /// The run of the same case at this fine step (s), default tolerances.
    FineStep(f64),
}

/// One case: how to run it, what it observes and how its error is normalized.
pub struct Case {
    /// Short name (CSV and plot legend).
    pub name: &'static str,
    /// What the case is.
    pub setup: &'static str,
    /// The normalized error, in words.
    pub error_definition: &'static str,
    /// The reference the error is measured against.
    pub reference: Reference,
    /// The reference in words (formula or run).
    pub reference_definition: &'static str,
    /// What limits the case's accuracy, from the sweeps.
    pub limit: &'static str,
    simulate: fn(&SimulationSettings, &mut Duration) -> (Vec<f64>, Profile),
    /// Finest step of the step sweep (s).
    pub finest_step: f64,
    error: fn(&[f64], &[f64]) -> f64,
}

/// The result of running a case once.
#[derive(Clone, Debug)]
pub struct Run {
    /// The observable (see each case).
    pub observable: Vec<f64>,
    /// Profile of the run (its counters do not depend on the machine).
    pub profile: Profile,
    /// Wall time of the stepping; building the bodies is not included.
    pub stepping: Duration,
}

impl Case {
    /// Runs the case once with `settings`, on one thread and without the event log.
    #[must_use]
    pub fn run(&self, settings: &SimulationSettings) -> Run {
        // Sleeping off: the cases measure the dynamics' numerical error.
        let settings =
            SimulationSettings { threads: 1, record_events: false, sleep: SleepSettings::off(), ..settings.clone() };
        let mut stepping = Duration::ZERO;
        let (observable, profile) = (self.simulate)(&settings, &mut stepping);
        Run { observable, profile, stepping }
    }

    /// The steps of the step sweep: `COARSEST_STEP` halved down to `finest_step`.
    #[must_use]
    pub fn step_sweep(&self) -> Vec<f64> {
        let mut steps = vec![COARSEST_STEP];
        while steps[steps.len() - 1] * 0.5 >= self.finest_step * (1.0 - 1e-9) {
            steps.push(steps[steps.len() - 1] * 0.5);
        }
        steps
    }

    /// Normalized error of `observable` against `reference` (both observables of this case).
    #[must_use]
    pub fn error(&self, observable: &[f64], reference: &[f64]) -> f64 {
        (self.error)(observable, reference)
    }
}

/// Every case of the report, in report order.
#[must_use]
pub fn all_cases() -> Vec<Case> {
    vec![bounce(), smooth_bounce(), sliding_stop(), rolling(), free_flight(), pile()]
}

/// Steps `sim` for `seconds` (rounded to whole steps of `settings.time_step`), adding the
/// wall time to `watch`.
fn run_for(sim: &mut Simulation, seconds: f64, watch: &mut Duration) {
    let start = Instant::now();
    let steps = (seconds / sim.settings().time_step).round() as usize;
    for _ in 0..steps {
        sim.step(sim.settings().time_step);
    }
    *watch += start.elapsed();
}

fn new_simulation(settings: &SimulationSettings) -> Simulation {
    Simulation::new(settings.clone()).expect("valid settings")
}

/// A material with restitution `e` (also its `e_max`) and a friction law.
fn material(restitution: f64, friction: FrictionLaw) -> Material {
    Material { density: 1000.0, restitution, restitution_max: restitution, friction }
}

/// Zero friction for any band below 1 m.
fn frictionless() -> FrictionLaw {
    FrictionLaw { lambda_min: 1.0, mu_max: 0.0 }
}

/// μ = 0.5 for a band of 0.004 m (λ_min = 0.002, μ_max = 1).
fn rough() -> FrictionLaw {
    FrictionLaw { lambda_min: 0.002, mu_max: 1.0 }
}

/// Control points along a `width × height` rectangle centred at the origin, at most `spacing`
/// apart, CCW; collinear points make the sides exactly straight (as `tests/common`).
fn box_spline(width: f64, height: f64, spacing: f64) -> Spline {
    let (hw, hh) = (0.5 * width, 0.5 * height);
    let corners = [DVec2::new(-hw, -hh), DVec2::new(hw, -hh), DVec2::new(hw, hh), DVec2::new(-hw, hh)];
    let mut points = Vec::new();
    for k in 0..4 {
        let (from, to) = (corners[k], corners[(k + 1) % 4]);
        let pieces = ((to - from).length() / spacing).ceil().max(3.0) as usize;
        points.extend((0..pieces).map(|i| from.lerp(to, i as f64 / pieces as f64)));
    }
    Spline::from_control_points(points).expect("a valid box")
}

/// A static box of constant rugosity centred at `centre`.
fn static_box(centre: DVec2, width: f64, height: f64, band: f64, material: Material) -> BodyDesc {
    let spline = box_spline(width, height, 0.5);
    let rugosity = Rugosity::constant(spline.segment_count(), band).expect("valid rugosity");
    BodyDesc::new(spline, rugosity).with_material(material).at(centre, 0.0).fixed()
}

/// Static flat ground 40 m wide whose top is the line `y = 0`.
fn ground(band: f64, material: Material) -> BodyDesc {
    static_box(DVec2::new(0.0, -1.0), 40.0, 2.0, band, material)
}

/// A spline disc of `radius` with 64 segments and constant rugosity.
fn disc(radius: f64, band: f64, material: Material) -> BodyDesc {
    let spline = Generator::Circle { radius }.build(64).expect("a valid circle");
    BodyDesc::new(spline, Rugosity::constant(64, band).expect("valid rugosity")).with_material(material)
}

// ---------------------------------------------------------------- bounce

/// Restitution of the bounce.
const BOUNCE_E: f64 = 0.8;
/// Disc radius (m).
const BOUNCE_RADIUS: f64 = 0.2;
/// Drop height h0 (m).
const BOUNCE_DROP: f64 = 1.0;
/// Apexes compared.
pub const BOUNCE_APEXES: usize = 3;
/// Simulated time: the third apex is at 1.98 s.
const BOUNCE_SECONDS: f64 = 2.3;

/// The exact apex heights `e^(2k) h0`, k = 1..=3.
fn bounce_exact() -> Vec<f64> {
    (1..=BOUNCE_APEXES).map(|k| BOUNCE_DROP * BOUNCE_E.powi(2 * k as i32)).collect()
}

/// Drops a frictionless disc whose lowest point starts `BOUNCE_DROP` above `surface` (the
/// height of the centre at first touch) and returns the first apexes above `surface`.
///
/// The apex is read from the first state after the vertical velocity turns negative as
/// `y + v_y²/(2g)` (exact in free flight), so the step does not sample it. Missing apexes
/// count as 0.
fn bounce_apexes(settings: &SimulationSettings, band: f64, surface: f64, watch: &mut Duration) -> (Vec<f64>, Profile) {
    let mut sim = new_simulation(settings);
    let mat = material(BOUNCE_E, frictionless());
    sim.add_body(ground(band, mat)).expect("valid ground");
    let ball = disc(BOUNCE_RADIUS, band, mat).at(DVec2::new(0.0, surface + BOUNCE_DROP), 0.0);
    let ball = sim.add_body(ball).expect("valid disc");
    let mut apexes = Vec::new();
    let mut previous_vy = 0.0;
    let h = settings.time_step;
    let start = Instant::now();
    for _ in 0..(BOUNCE_SECONDS / h).round() as usize {
        sim.step(h);
        let s = sim.state(ball).expect("the disc exists");
        let vy = s.linear_velocity.y;
        if previous_vy > 0.0 && vy <= 0.0 && apexes.len() < BOUNCE_APEXES {
            apexes.push(s.position.y + vy * vy / (2.0 * G) - surface);
        }
        previous_vy = vy;
    }
    *watch += start.elapsed();
    apexes.resize(BOUNCE_APEXES, 0.0);
    (apexes, sim.take_profile())
}

/// Largest apex error over the compared bounces, divided by h0.
fn bounce_error(observable: &[f64], reference: &[f64]) -> f64 {
    observable.iter().zip(reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / BOUNCE_DROP
}

/// Rugosity of the banded bounce (m), as in `tests/validation.rs`.
const BOUNCE_BAND: f64 = 0.002;

/// Frictionless disc (r = 0.2 m, rugosity 0.002 m on disc and ground) dropped from 1 m, e = 0.8.
#[must_use]
pub fn bounce() -> Case {
    Case {
        name: "bounce",
        setup: "frictionless spline disc (r = 0.2 m, 64 segments, rugosity 0.002 m on disc and ground) dropped \
                from h0 = 1 m onto flat ground, e = 0.8, 2.3 s",
        error_definition: "max over the first 3 apexes of |apex − e^(2k) h0| / h0; apexes above the outer edge of the \
                           combined band (centre at r + 2·0.002 m), read as y + v_y²/(2g) after the top",
        reference: Reference::Analytic(bounce_exact()),
        reference_definition: "analytic: apex k = e^(2k) h0",
        limit: "where in the band the impact happens. An impact at depth d into the combined band (0.004 m) shifts \
                apex k by up to (1 − e^(2k)) d. At coarse steps conservative advancement puts every impact at about \
                the same depth whatever the step, so the error is flat; once one step's travel at the impact speed \
                (4.4 m/s) is shorter than the band, h < 1/1100 s, the depth is at most that travel and the error \
                falls about linearly with the step. tests/work_precision.rs checks this bound.",
        simulate: |settings, watch| bounce_apexes(settings, BOUNCE_BAND, BOUNCE_RADIUS + 2.0 * BOUNCE_BAND, watch),
        finest_step: ANALYTIC_FINEST_STEP,
        error: bounce_error,
    }
}

/// The same drop with rugosity 0 on both bodies, so the band is `settings.min_band`.
#[must_use]
pub fn smooth_bounce() -> Case {
    Case {
        name: "bounce-smooth",
        setup: "the bounce with rugosity 0 on disc and ground, so every band is settings.min_band; the disc starts \
                with its curve 1 m above the ground's curve",
        error_definition: "as bounce, but apexes measured above the curves' contact (centre at r): the band is not \
                           surface detail here, so bouncing off its edge is an error",
        reference: Reference::Analytic(bounce_exact()),
        reference_definition: "analytic: apex k = e^(2k) h0 above the curves' contact",
        limit: "the minimum band itself: with rugosity 0 the disc bounces off a band of half-width min_band, so \
                every apex is off by about (1 − e^(2k)) × the impact gap; the error is proportional to min_band (see \
                its sweep) and does not fall with the step (at the finest steps the impact lands at another depth \
                in the band and the error moves within the same size).",
        simulate: |settings, watch| bounce_apexes(settings, 0.0, BOUNCE_RADIUS, watch),
        finest_step: ANALYTIC_FINEST_STEP,
        error: bounce_error,
    }
}

// ---------------------------------------------------------------- sliding stop

/// Launch speed of the sliding block (m/s).
const SLIDE_V0: f64 = 2.0;
/// Friction coefficient from the rugosity: λ = 0.004 on both, λ_min = 0.002, μ_max = 1.
const SLIDE_MU: f64 = 0.5;
/// Band of the sliding and rolling cases (m).
const CONTACT_BAND: f64 = 0.004;
/// The block stops at v0/(μg) = 0.41 s; its position is read at 0.6 s.
const SLIDE_SECONDS: f64 = 0.6;

fn sliding_distance(settings: &SimulationSettings, watch: &mut Duration) -> (Vec<f64>, Profile) {
    let mut sim = new_simulation(settings);
    sim.add_body(ground(CONTACT_BAND, material(0.0, rough()))).expect("valid ground");
    let spline = box_spline(0.4, 0.2, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), CONTACT_BAND).expect("valid rugosity");
    let block = BodyDesc::new(spline, rugosity)
        .with_material(Material { restitution_max: 0.5, ..material(0.0, rough()) })
        .at(DVec2::new(0.0, 0.1 + 1.5 * CONTACT_BAND), 0.0)
        .with_velocity(DVec2::new(SLIDE_V0, 0.0), 0.0);
    let block = sim.add_body(block).expect("valid block");
    let x0 = sim.state(block).expect("the block exists").position.x;
    run_for(&mut sim, SLIDE_SECONDS, watch);
    let distance = sim.state(block).expect("the block exists").position.x - x0;
    (vec![distance], sim.take_profile())
}

/// Relative error of a scalar observable.
fn relative_error(observable: &[f64], reference: &[f64]) -> f64 {
    ((observable[0] - reference[0]) / reference[0]).abs()
}

/// A 0.4 × 0.2 m box launched at 2 m/s on flat ground, μ = 0.5 from rugosity 0.004 m.
#[must_use]
pub fn sliding_stop() -> Case {
    Case {
        name: "sliding-stop",
        setup: "0.4 × 0.2 m box (rugosity 0.004 m on box and ground, μ = 0.5 from it, e = 0, e_max = 0.5) \
                launched at v0 = 2 m/s on flat ground; it stops at v0/(μg) = 0.41 s; position read at 0.6 s",
        error_definition: "|distance − v0²/(2μg)| / (v0²/(2μg))",
        reference: Reference::Analytic(vec![SLIDE_V0 * SLIDE_V0 / (2.0 * SLIDE_MU * G)]),
        reference_definition: "analytic: stop distance v0²/(2μg) = 0.4077 m",
        limit: "the step: with the iterated solver the block slides on its flat face with a steady normal \
                force, and the integrator moves a touched body at the mean of its velocities before and after \
                the sub-step (trapezoidal), which is exact for constant deceleration; what remains is the stop \
                inside the last step (the solver clamps friction once the block would reverse), which falls at \
                an observed order of about 2. The symplectic x += v h the solver used before fell v0 h / 2 short \
                (2.0e-2 at 1/120 s, order 1).",
        simulate: sliding_distance,
        finest_step: ANALYTIC_FINEST_STEP,
        error: relative_error,
    }
}

// ---------------------------------------------------------------- rolling

/// tan θ of the incline: 0.5 ≤ 3μ, so the disc rolls without slip.
const ROLL_TAN: f64 = 0.5;
/// Rolling time (s).
const ROLL_SECONDS: f64 = 1.0;

/// Radius of the rolling disc (m).
const ROLL_RADIUS: f64 = 0.2;

/// The disc starts with its curve this fraction of the combined band `2λ` from the ground's
/// curve: a quarter of the way into the band, shallower than the rest depth (half), so the
/// contact holds it there and it rolls at that distance.
const ROLL_GAP_FRACTION: f64 = 0.75;

/// Rolling radius the contact model implies (docs/model.md): the contact point lies halfway
/// between the curves, which are `d` apart, so the no-slip constraint acts at `r + d/2`.
#[must_use]
pub fn rolling_radius(radius: f64, gap: f64) -> f64 {
    radius + 0.5 * gap
}

/// Speed at `t` of a uniform disc (`I = m r²/2`) rolling without slip at radius `R` down an
/// incline of angle θ: `a = g sin θ / (1 + r²/(2R²))`, which is `(2/3) g sin θ` for `R = r`.
#[must_use]
pub fn rolling_speed(radius: f64, rolling_radius: f64, t: f64) -> f64 {
    let ratio = radius / rolling_radius;
    G * ROLL_TAN.atan().sin() / (1.0 + 0.5 * ratio * ratio) * t
}

/// The disc's speed along the incline after [`ROLL_SECONDS`], for a disc and ground of rugosity
/// `band`, and the run's profile.
fn rolling_run(settings: &SimulationSettings, band: f64, watch: &mut Duration) -> (f64, Profile) {
    let theta = ROLL_TAN.atan();
    let settings = SimulationSettings { gravity: G * DVec2::new(theta.sin(), -theta.cos()), ..settings.clone() };
    let mut sim = new_simulation(&settings);
    // μ = 0.5 at every band (λ_min = λ/2, μ_max = 1; `rough()` for the case's band).
    let friction = FrictionLaw { lambda_min: 0.5 * band, mu_max: 1.0 };
    sim.add_body(ground(band, material(0.0, friction))).expect("valid ground");
    let mat = Material { restitution_max: 0.5, ..material(0.0, friction) };
    let height = ROLL_RADIUS + ROLL_GAP_FRACTION * 2.0 * band;
    let wheel = sim.add_body(disc(ROLL_RADIUS, band, mat).at(DVec2::new(0.0, height), 0.0)).expect("valid disc");
    run_for(&mut sim, ROLL_SECONDS, watch);
    (sim.state(wheel).expect("the disc exists").linear_velocity.x, sim.take_profile())
}

fn rolling_velocity(settings: &SimulationSettings, watch: &mut Duration) -> (Vec<f64>, Profile) {
    let (velocity, profile) = rolling_run(settings, CONTACT_BAND, watch);
    (vec![velocity], profile)
}

/// Rugosities of the rolling-radius table (m): from twice the case's down to the default
/// `min_band`, below which every band is `min_band`.
pub const ROLL_BANDS: [f64; 4] = [0.008, 0.004, 0.002, 0.001];

/// One row of the rolling-radius table.
pub struct RollingOffset {
    /// Rugosity of disc and ground (m).
    pub band: f64,
    /// Measured speed at 1 s relative to the nominal `(2/3) g sin θ t`, minus 1.
    pub measured: f64,
    /// The same offset derived from the rolling radius `r + d/2`.
    pub derived: f64,
}

/// The rolling case at `settings` for each of [`ROLL_BANDS`]: how far the speed is from the
/// nominal answer, measured and derived from the rolling radius.
#[must_use]
pub fn rolling_offsets(settings: &SimulationSettings) -> Vec<RollingOffset> {
    let nominal = rolling_speed(ROLL_RADIUS, ROLL_RADIUS, ROLL_SECONDS);
    ROLL_BANDS
        .iter()
        .map(|&band| {
            let mut watch = Duration::ZERO;
            let (speed, _) = rolling_run(settings, band, &mut watch);
            let radius = rolling_radius(ROLL_RADIUS, ROLL_GAP_FRACTION * 2.0 * band);
            RollingOffset {
                band,
                measured: speed / nominal - 1.0,
                derived: rolling_speed(ROLL_RADIUS, radius, ROLL_SECONDS) / nominal - 1.0,
            }
        })
        .collect()
}

/// A disc rolling down an incline tan θ = 0.5 (gravity tilted, the ground stays flat).
#[must_use]
pub fn rolling() -> Case {
    let radius = rolling_radius(ROLL_RADIUS, ROLL_GAP_FRACTION * 2.0 * CONTACT_BAND);
    Case {
        name: "rolling",
        setup: "spline disc (r = 0.2 m, rugosity 0.004 m, μ = 0.5, e = 0, e_max = 0.5) released on an incline \
                tan θ = 0.5 (≤ 3μ: no slip) with its curve d = 0.006 m (¾ of the combined band) from the ground's, 1 s",
        error_definition: "|v(1 s) − v_R| / v_R, v the centre's velocity along the incline",
        reference: Reference::Analytic(vec![rolling_speed(ROLL_RADIUS, radius, ROLL_SECONDS)]),
        reference_definition: "analytic for the rolling radius the contact model implies, R = r + d/2 = 0.203 m \
                               (the contact point lies halfway between the curves): v_R = g sin θ t / (1 + r²/(2R²)) \
                               = 2.954 m/s at t = 1 s; the nominal (2/3) g sin θ t = 2.925 m/s is R = r (see the \
                               rolling-radius table)",
        limit: "the rolling radius. Against v_R the error is at the level of the spline circle's radius and inertia \
                errors at every step, since a constant acceleration is integrated exactly; against the nominal answer \
                the offset is the band's, derived and measured in the rolling-radius table.",
        simulate: rolling_velocity,
        finest_step: ANALYTIC_FINEST_STEP,
        error: relative_error,
    }
}

// ---------------------------------------------------------------- free flight

/// Radius of the flying blob (m): the length scale of its error.
const FLIGHT_RADIUS: f64 = 0.3;
/// Flight time (s).
const FLIGHT_SECONDS: f64 = 2.0;
const FLIGHT_VELOCITY: DVec2 = DVec2::new(3.0, 4.0);
const FLIGHT_SPIN: f64 = 5.0;

fn flight_pose(settings: &SimulationSettings, watch: &mut Duration) -> (Vec<f64>, Profile) {
    let mut sim = new_simulation(settings);
    let blob = Generator::Blob { radius: FLIGHT_RADIUS, roughness: 0.5, seed: 9 }.build(24).expect("a valid blob");
    let body = BodyDesc::new(blob, Rugosity::constant(24, 0.002).expect("valid rugosity"))
        .with_velocity(FLIGHT_VELOCITY, FLIGHT_SPIN);
    let body = sim.add_body(body).expect("valid blob");
    let start = sim.state(body).expect("the blob exists");
    run_for(&mut sim, FLIGHT_SECONDS, watch);
    let end = sim.state(body).expect("the blob exists");
    let moved = end.position - start.position;
    (vec![moved.x, moved.y, end.angle - start.angle], sim.take_profile())
}

/// `(|Δ displacement| + R |Δ angle|) / R`: how far a boundary point is off, in body radii.
fn pose_error(observable: &[f64], reference: &[f64]) -> f64 {
    let position = DVec2::new(observable[0] - reference[0], observable[1] - reference[1]).length();
    (position + FLIGHT_RADIUS * (observable[2] - reference[2]).abs()) / FLIGHT_RADIUS
}

/// A spinning blob in flight under gravity.
#[must_use]
pub fn free_flight() -> Case {
    let t = FLIGHT_SECONDS;
    let exact = FLIGHT_VELOCITY * t + 0.5 * DVec2::new(0.0, -G) * t * t;
    Case {
        name: "free-flight",
        setup: "blob (radius R = 0.3 m, 24 segments) launched at (3, 4) m/s spinning at 5 rad/s, no contact, 2 s",
        error_definition: "(|Δ displacement| + R |Δ angle|) / R at t = 2 s",
        reference: Reference::Analytic(vec![exact.x, exact.y, FLIGHT_SPIN * t]),
        reference_definition: "analytic: parabola v0 t + g t²/2, angle ω0 t",
        limit: "rounding only: the integrator is exact for constant gravity and constant spin, so the error is \
                the floating-point floor (1e-14 … 1e-11) and grows with the number of steps; no order is fitted.",
        simulate: flight_pose,
        finest_step: ANALYTIC_FINEST_STEP,
        error: pose_error,
    }
}

// ---------------------------------------------------------------- pile

/// Blob radius of the pile (m); the body size in its error is the diameter.
const PILE_RADIUS: f64 = 0.12;
/// Time at which the pile's positions are compared (s).
pub const PILE_SECONDS: f64 = 0.3;
/// Step of the pile's reference run (s).
pub const PILE_REFERENCE_STEP: f64 = 1.0 / 61440.0;

/// Five blobs, positions and velocities.
const PILE_BLOBS: [(f64, f64, f64, f64, f64); 5] = [
    // (x, y, vx, vy, ω)
    (-0.35, 0.25, 0.6, 0.0, 1.0),
    (0.0, 0.2, 0.0, 0.0, -2.0),
    (0.35, 0.3, -0.6, 0.0, 0.0),
    (-0.15, 0.6, 0.0, -1.0, 3.0),
    (0.2, 0.7, 0.0, 0.0, -1.0),
];

fn pile_positions(settings: &SimulationSettings, watch: &mut Duration) -> (Vec<f64>, Profile) {
    let mut sim = new_simulation(settings);
    let wall = material(0.2, FrictionLaw { lambda_min: 0.002, mu_max: 0.8 });
    let mat = Material { restitution_max: 0.4, ..wall };
    sim.add_body(static_box(DVec2::new(0.0, -0.1), 1.4, 0.2, 0.004, wall)).expect("valid floor");
    for side in [-1.0, 1.0] {
        sim.add_body(static_box(DVec2::new(0.6 * side, 0.5), 0.2, 1.0, 0.004, wall)).expect("valid wall");
    }
    let blobs: Vec<_> = PILE_BLOBS
        .iter()
        .enumerate()
        .map(|(k, &(x, y, vx, vy, w))| {
            let spline = Generator::Blob { radius: PILE_RADIUS, roughness: 0.5, seed: 20 + k as u64 }
                .build(24)
                .expect("a valid blob");
            let body = BodyDesc::new(spline, Rugosity::constant(24, 0.003).expect("valid rugosity"))
                .with_material(mat)
                .at(DVec2::new(x, y), 0.0)
                .with_velocity(DVec2::new(vx, vy), w);
            sim.add_body(body).expect("valid blob")
        })
        .collect();
    run_for(&mut sim, PILE_SECONDS, watch);
    let positions = blobs
        .iter()
        .flat_map(|&b| {
            let p = sim.state(b).expect("the blob exists").position;
            [p.x, p.y]
        })
        .collect();
    (positions, sim.take_profile())
}

/// RMS over the blobs of the distance between their centres, divided by the blob diameter.
fn rms_position_error(observable: &[f64], reference: &[f64]) -> f64 {
    let squares: f64 = observable.iter().zip(reference).map(|(a, b)| (a - b) * (a - b)).sum();
    (squares / (observable.len() / 2) as f64).sqrt() / (2.0 * PILE_RADIUS)
}

/// Five blobs thrown into a box, compared with a fine-step run of the same scene.
#[must_use]
pub fn pile() -> Case {
    Case {
        name: "pile",
        setup: "five blobs (radius 0.12 m, rugosity 0.003 m, e = 0.2, e_max = 0.4, μ from λ_min = 0.002, μ_max = 0.8) \
                thrown into a 1 m wide box (rugosity 0.004 m); positions compared at t = 0.3 s, when every blob has landed or hit another",
        error_definition: "RMS over the 5 blobs of |centre − reference centre|, divided by the blob diameter 0.24 m",
        reference: Reference::FineStep(PILE_REFERENCE_STEP),
        reference_definition: "the same scene run at time_step = 1/61440 s with default tolerances",
        limit: "the order of the collisions and where in the bands they happen: the blobs meet at other times \
                and depths and end about 1.5e-2 diameters away at 1/120 s and 7e-3 from 1/1920 s; at 1/30 and \
                1/60 s about 6e-2, the resting and sliding contacts between collisions then integrated over the \
                few sub-steps such a step takes. The reference itself moves by about 4e-5 diameters when its step \
                is halved (checked above), well below every error.",
        simulate: pile_positions,
        finest_step: PILE_FINEST_STEP,
        error: rms_position_error,
    }
}
