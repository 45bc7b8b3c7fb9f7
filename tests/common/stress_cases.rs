//! The stress cases, shared by `tests/stress.rs` (CI sizes) and `examples/stability_report.rs`
//! (full sizes, written to `docs/stability.md`). Each case builds a scene for a [`Size`] and
//! states its bounds; [`run`] steps it and measures, after every step: finite states, the
//! deepest penetration of any pair (exact, from the body query), the energy
//! `E = KE − Σ m g·x` against its start, tunnelling, and the creep of the watched body.
//!
//! Bounds shared by every case (each case adds its own where it has one):
//! - **Penetration** `δ = λ_A + λ_B − d` (d the curve distance, or `−depth` for crossing
//!   curves) of every pair at every step end is at most the combined band plus a margin of
//!   `1e-6 L` (L the case's body size). A step whose curves would cross is retried shorter
//!   (MODEL §4), so at a step end the curves may cross only by the leaf solver's accuracy
//!   (~1e-12 of a segment); `1e-6 L` is far above that and three orders below the bands here.
//! - **Energy** never exceeds its start by more than one band of fall per resting level:
//!   `Σ m_i |g| n_i b` (b the combined band, `n_i` the bands body i may sink through, 1 on the
//!   ground, k+1 for the k-th box of a stack). A micro-collision replaces `u_n ≈ 0` by
//!   `−√(2gδ)` (MODEL §7): it can return at most the `m g δ` the body lost sinking `δ` into the
//!   band, never more. Rounding adds `1e-9` of the energy's scale (Σ m |g| (|x| + L) + KE₀).
//! - **Tunnelling**: no dynamic body's centre of mass is ever inside another body, and each
//!   case names the side of the ground or wall each centre must stay on.
//! - **Drift** (resting cases): a body at rest below its friction angle stays put — mechanics
//!   allows no motion at all. The watched body's largest displacement from its start (in any
//!   direction: sliding, sinking or rising; sideways only for a body dropped onto the ground)
//!   over the whole run is at most the case's bound: 1e-3
//!   of its size for 10,000 steps of a body on a slope or in a stack, 1e-4 m on flat ground,
//!   5 mm for the top of a pyramid (the requirements; far above rounding, far below any
//!   creep a contact model could hide in them). Bodies start at the rest depth, so settling
//!   moves them by the solver's error only.
#![allow(dead_code)]

use std::time::{Duration, Instant};

use glam::DVec2;
use hecs::Entity;
use rugosa::{
    AobbTree, BodyDesc, BodyQuery, BodyShape, FrictionLaw, Generator, MassProperties, Material, PairState, Pose,
    QuerySettings, Rugosity, Simulation, SimulationSettings, SleepSettings, Spline, StepCounters, query_bodies,
};

use crate::common::{box_spline, disc, frictionless, polygon_control_points, scaled_ground};

/// Standard gravity (m/s²).
pub const G: f64 = 9.81;

/// How large a case is run: CI keeps `cargo test` fast, the report runs the full size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// Shorter runs and smaller piles, for `tests/stress.rs`.
    Ci,
    /// The sizes the issue asks for, for `docs/stability.md`.
    Full,
}

impl Size {
    fn pick<T>(self, ci: T, full: T) -> T {
        if self == Size::Ci { ci } else { full }
    }
}

/// A body whose centre must stay on the side `normal · x ≥ offset`.
#[derive(Clone, Copy, Debug)]
pub struct SideRule {
    /// The body.
    pub body: Entity,
    /// Unit normal pointing to the allowed side.
    pub normal: DVec2,
    /// Offset of the boundary line along `normal` (m).
    pub offset: f64,
}

/// The drift bound of a resting body.
#[derive(Clone, Copy, Debug)]
pub struct CreepRule {
    /// The watched body.
    pub body: Entity,
    /// Bound on its largest displacement from the start (m).
    pub bound: f64,
    /// Whether vertical motion counts: not for a body dropped onto the ground (it falls
    /// first), only its sideways drift.
    pub vertical: bool,
}

/// A case's scene, how long it runs, and its bounds.
pub struct Scenario {
    /// The scene.
    pub sim: Simulation,
    /// Steps of `time_step`.
    pub steps: usize,
    /// Body size L (m): scales the penetration margin and the rounding slack.
    pub size: f64,
    /// Combined band b of the resting contacts (m), for the energy slack.
    pub band: f64,
    /// Per dynamic body, how many bands it may sink through (see the module docs).
    pub levels: Vec<(Entity, f64)>,
    /// Sides the centres must stay on.
    pub sides: Vec<SideRule>,
    /// Drift bound, for resting cases.
    pub creep: Option<CreepRule>,
}

/// A named stress case.
pub struct Case {
    /// Snake-case name (the test's name).
    pub name: &'static str,
    /// One line on what it does, including the bounds it adds.
    pub description: &'static str,
    /// Builds the scene at a size.
    pub build: fn(Size) -> Scenario,
}

impl Case {
    const fn new(name: &'static str, description: &'static str, build: fn(Size) -> Scenario) -> Self {
        Self { name, description, build }
    }
}

/// What a run measured.
#[derive(Clone, Debug)]
pub struct Measurement {
    /// Case name.
    pub name: &'static str,
    /// Steps taken (fewer than asked if a state became non-finite).
    pub steps: usize,
    /// First step whose state was not finite.
    pub non_finite_step: Option<usize>,
    /// Deepest penetration of any pair at any step end (m).
    pub max_penetration: f64,
    /// Combined band where that penetration was measured (m).
    pub band_at_max: f64,
    /// Bound on the penetration beyond the band (m).
    pub penetration_margin: f64,
    /// Largest `E(t) − E(0)` (J).
    pub max_energy_gain: f64,
    /// Allowed gain (J).
    pub energy_slack: f64,
    /// `E(end) − E(0)` relative to `E(0) − E_min` scale (J).
    pub final_energy_change: f64,
    /// Initial energy scale used for relative drift: `KE₀ + Σ m |g| L` (J).
    pub energy_scale: f64,
    /// Mean speed of the watched body along x over the second half (m/s).
    pub creep_speed: Option<f64>,
    /// Bound on the drift (m).
    pub creep_bound: Option<f64>,
    /// Largest displacement of the watched body from its start (m).
    pub drift: Option<f64>,
    /// The first tunnelling found, described.
    pub tunnelling: Option<String>,
    /// Retries, cap hits and the rest, summed over the run.
    pub counters: StepCounters,
    /// Wall time of the steps alone (measurements excluded).
    pub step_time: Duration,
    /// Wall time of the whole run, measurements included.
    pub run_time: Duration,
}

impl Measurement {
    /// Every bound the run broke, described with its numbers.
    #[must_use]
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(step) = self.non_finite_step {
            out.push(format!("non-finite state at step {step}"));
        }
        if let Some(what) = &self.tunnelling {
            out.push(format!("tunnelling: {what}"));
        }
        if self.max_penetration > self.band_at_max + self.penetration_margin {
            out.push(format!(
                "penetration {:.3e} m = {:.3} × band {:.3e} m (bound: band + {:.1e} m)",
                self.max_penetration,
                self.penetration_ratio(),
                self.band_at_max,
                self.penetration_margin
            ));
        }
        if self.max_energy_gain > self.energy_slack {
            out.push(format!("energy grew by {:.3e} J (slack {:.3e} J)", self.max_energy_gain, self.energy_slack));
        }
        if let (Some(drift), Some(bound)) = (self.drift, self.creep_bound)
            && drift > bound
        {
            out.push(format!("drifts {drift:.3e} m (bound {bound:.3e} m)"));
        }
        out
    }

    /// Deepest penetration over the band there.
    #[must_use]
    pub fn penetration_ratio(&self) -> f64 {
        if self.band_at_max > 0.0 { self.max_penetration / self.band_at_max } else { 0.0 }
    }
}

/// Runs a case at a size and measures it.
#[must_use]
pub fn run(case: &Case, size: Size) -> Measurement {
    let started = Instant::now();
    let mut scenario = (case.build)(size);
    let mut probe = Probe::new(&scenario);
    let dt = scenario.sim.settings().time_step;
    let mut step_time = Duration::ZERO;
    let mut steps = 0;
    scenario.sim.take_profile();
    for step in 1..=scenario.steps {
        let start = Instant::now();
        scenario.sim.step(dt);
        step_time += start.elapsed();
        steps = step;
        if !probe.observe(&scenario, step) {
            break;
        }
    }
    probe.finish(case.name, &mut scenario, steps, step_time, started.elapsed())
}

// ---------------------------------------------------------------- measuring

/// What is tracked while a case runs.
struct Probe {
    energy_start: f64,
    energy_scale: f64,
    energy_slack: f64,
    max_energy_gain: f64,
    last_energy: f64,
    max_penetration: f64,
    band_at_max: f64,
    /// `δ − band` of the deepest contact so far (−∞ before the first contact).
    deepest_excess: f64,
    non_finite_step: Option<usize>,
    tunnelling: Option<String>,
    watched_start: Option<DVec2>,
    watched_half: Option<f64>,
    watched_last: Option<f64>,
    drift: f64,
    query: BodyQuery,
}

impl Probe {
    fn new(scenario: &Scenario) -> Self {
        let sim = &scenario.sim;
        let weight = |e: Entity| mass(sim, e) * sim.settings().gravity.length();
        let scale = sim.kinetic_energy()
            + sim
                .bodies()
                .filter(|&e| !is_static(sim, e))
                .map(|e| weight(e) * (centre(sim, e).length() + scenario.size))
                .sum::<f64>();
        let band_slack: f64 = scenario.levels.iter().map(|&(e, n)| weight(e) * n * scenario.band).sum();
        let watched_start = scenario.creep.map(|c| centre(sim, c.body));
        let energy_start = total_energy(sim);
        Self {
            energy_start,
            energy_scale: scale,
            energy_slack: band_slack + 1e-9 * scale,
            max_energy_gain: 0.0,
            last_energy: energy_start,
            max_penetration: 0.0,
            band_at_max: 0.0,
            deepest_excess: f64::NEG_INFINITY,
            non_finite_step: None,
            tunnelling: None,
            watched_start,
            watched_half: None,
            watched_last: watched_start.map(|p| p.x),
            drift: 0.0,
            query: BodyQuery::default(),
        }
    }

    /// Measures the state after `step`; `false` stops the run (a non-finite state).
    fn observe(&mut self, scenario: &Scenario, step: usize) -> bool {
        let sim = &scenario.sim;
        if sim.bodies().any(|e| !sim.state(e).is_some_and(|s| s.is_finite())) {
            self.non_finite_step = Some(step);
            return false;
        }
        let energy = total_energy(sim);
        self.last_energy = energy;
        self.max_energy_gain = self.max_energy_gain.max(energy - self.energy_start);
        self.measure_pairs(sim, step);
        if self.tunnelling.is_none() {
            self.tunnelling = broken_side(sim, &scenario.sides, step);
        }
        if let (Some(rule), Some(start)) = (scenario.creep, self.watched_start) {
            let position = centre(sim, rule.body);
            let moved = position - start;
            self.drift = self.drift.max(if rule.vertical { moved.length() } else { moved.x.abs() });
            let x = position.x;
            self.watched_last = Some(x);
            if step == scenario.steps / 2 {
                self.watched_half = Some(x);
            }
        }
        true
    }

    /// Penetration and centre-inside checks for every pair whose banded bounds overlap.
    fn measure_pairs(&mut self, sim: &Simulation, step: usize) {
        let bodies: Vec<BodyView> = sim.bodies().map(|e| BodyView::new(sim, e)).collect();
        let settings = QuerySettings {
            min_band: sim.settings().min_band,
            curve_pair: sim.settings().curve_pair,
            ..QuerySettings::default()
        };
        for (i, a) in bodies.iter().enumerate() {
            for b in &bodies[i + 1..] {
                if (a.is_static && b.is_static) || !a.bounds_overlap(b) {
                    continue;
                }
                let (penetration, band) = pair_penetration(sim, a, b, &settings, &mut self.query);
                if penetration - band > self.deepest_excess {
                    self.deepest_excess = penetration - band;
                    (self.max_penetration, self.band_at_max) = (penetration, band);
                }
                if self.tunnelling.is_none() {
                    self.tunnelling = centre_inside(sim, a, b, step).or_else(|| centre_inside(sim, b, a, step));
                }
            }
        }
    }

    fn finish(
        self,
        name: &'static str,
        scenario: &mut Scenario,
        steps: usize,
        step_time: Duration,
        run_time: Duration,
    ) -> Measurement {
        let dt = scenario.sim.settings().time_step;
        let half_time = (steps - steps / 2) as f64 * dt;
        let creep_speed = match (self.watched_half, self.watched_last) {
            (Some(half), Some(last)) => Some((last - half).abs() / half_time),
            _ => None,
        };
        Measurement {
            name,
            steps,
            non_finite_step: self.non_finite_step,
            max_penetration: self.max_penetration,
            band_at_max: self.band_at_max,
            penetration_margin: 1e-6 * scenario.size,
            max_energy_gain: self.max_energy_gain,
            energy_slack: self.energy_slack,
            final_energy_change: self.last_energy - self.energy_start,
            energy_scale: self.energy_scale,
            creep_speed,
            creep_bound: scenario.creep.map(|c| c.bound),
            drift: scenario.creep.map(|_| self.drift),
            tunnelling: self.tunnelling,
            counters: scenario.sim.profile().counters,
            step_time,
            run_time,
        }
    }
}

/// A body's shape, pose and banded world bounds, read from the world.
struct BodyView {
    entity: Entity,
    spline: Spline,
    rugosity: Rugosity,
    tree: AobbTree,
    pose: Pose,
    is_static: bool,
    lower: DVec2,
    upper: DVec2,
}

impl BodyView {
    fn new(sim: &Simulation, entity: Entity) -> Self {
        let world = sim.world();
        let spline = Spline::clone(&world.get::<&Spline>(entity).unwrap());
        let rugosity = Rugosity::clone(&world.get::<&Rugosity>(entity).unwrap());
        let tree = AobbTree::clone(&world.get::<&AobbTree>(entity).unwrap());
        let pose = sim.state(entity).unwrap().pose();
        let band = rugosity.max_tolerance().max(sim.settings().min_band);
        let (lower, upper) = spline.mapped(|p| pose.transform_point(p)).bounds();
        let is_static = is_static(sim, entity);
        Self { entity, spline, rugosity, tree, pose, is_static, lower: lower - band, upper: upper + band }
    }

    fn bounds_overlap(&self, other: &BodyView) -> bool {
        self.lower.cmple(other.upper).all() && other.lower.cmple(self.upper).all()
    }

    fn shape(&self) -> BodyShape<'_> {
        BodyShape::new(&self.spline, &self.rugosity)
    }
}

/// The pair's deepest penetration `δ = λ_A + λ_B − d` and the combined band there. Crossing
/// curves give `band + depth`, the depth measured from 16 samples per segment of each curve.
fn pair_penetration(
    sim: &Simulation,
    a: &BodyView,
    b: &BodyView,
    settings: &QuerySettings,
    query: &mut BodyQuery,
) -> (f64, f64) {
    let manifold = query_bodies(&a.shape(), &a.tree, &a.pose, &b.shape(), &b.tree, &b.pose, settings, query);
    match manifold.state {
        PairState::Separate => (0.0, f64::INFINITY),
        PairState::Contact => manifold
            .contacts
            .iter()
            .map(|c| (c.contact.penetration, c.contact.lambda_a + c.contact.lambda_b))
            .fold((0.0, f64::INFINITY), |best, x| if x.0 - x.1 > best.0 - best.1 { x } else { best }),
        PairState::Intersecting => {
            let floor = sim.settings().min_band;
            let band = manifold
                .intersections
                .iter()
                .map(|x| {
                    a.rugosity.segment_tolerance(x.segment_a as usize, floor).max
                        + b.rugosity.segment_tolerance(x.segment_b as usize, floor).max
                })
                .fold(0.0, f64::max);
            (band + overlap_depth(a, b).max(overlap_depth(b, a)), band)
        }
    }
}

/// Deepest sample of `a`'s curve inside `b` (16 samples per segment).
fn overlap_depth(a: &BodyView, b: &BodyView) -> f64 {
    let samples = 16 * a.spline.segment_count();
    (0..samples)
        .map(|k| {
            let world = a.pose.transform_point(a.spline.position(k as f64 / 16.0));
            depth_inside(&b.spline, b.pose.inverse_transform_point(world))
        })
        .fold(0.0, f64::max)
}

/// How deep `point` (body frame) lies inside the curve, 0 outside: the distance to the nearest
/// boundary point when the point is behind that point's outward normal.
fn depth_inside(spline: &Spline, point: DVec2) -> f64 {
    let nearest = spline.nearest_point(point);
    let behind = (point - nearest.position).dot(spline.outward_normal(nearest.parameter)) < 0.0;
    if behind { nearest.distance } else { 0.0 }
}

/// A description if `a` is dynamic and its centre of mass lies inside `b`.
fn centre_inside(sim: &Simulation, a: &BodyView, b: &BodyView, step: usize) -> Option<String> {
    if a.is_static {
        return None;
    }
    let depth = depth_inside(&b.spline, b.pose.inverse_transform_point(centre(sim, a.entity)));
    (depth > 0.0).then(|| format!("step {step}: the centre of {:?} is {depth:.3e} m inside {:?}", a.entity, b.entity))
}

fn broken_side(sim: &Simulation, sides: &[SideRule], step: usize) -> Option<String> {
    sides.iter().find_map(|rule| {
        let along = rule.normal.dot(centre(sim, rule.body));
        (along < rule.offset).then(|| {
            format!("step {step}: {:?} at {along:.4} m, must stay ≥ {} m along {}", rule.body, rule.offset, rule.normal)
        })
    })
}

fn centre(sim: &Simulation, body: Entity) -> DVec2 {
    sim.state(body).unwrap().position
}

fn mass(sim: &Simulation, body: Entity) -> f64 {
    sim.world().get::<&MassProperties>(body).map(|m| m.mass).unwrap_or(0.0)
}

fn is_static(sim: &Simulation, body: Entity) -> bool {
    sim.world().get::<&rugosa::Static>(body).is_ok()
}

/// Kinetic plus potential energy `KE − Σ m g·x` (J).
fn total_energy(sim: &Simulation) -> f64 {
    let gravity = sim.settings().gravity;
    let potential: f64 =
        sim.bodies().filter(|&e| !is_static(sim, e)).map(|e| -mass(sim, e) * gravity.dot(centre(sim, e))).sum();
    sim.kinetic_energy() + potential
}

// ---------------------------------------------------------------- building scenes

/// A simulation with gravity `gravity`, the default settings otherwise, `min_band` as given.
fn simulation(gravity: DVec2, min_band: f64, size: Size) -> Simulation {
    // The report uses every core; results are identical for any thread count.
    let threads = size.pick(1, 0);
    // Sleeping off: a sleeping body does not move, so every drift bound would hold trivially.
    let sleep = SleepSettings::off();
    let settings = SimulationSettings { gravity, min_band, threads, record_events: false, sleep, ..Default::default() };
    Simulation::new(settings).unwrap()
}

fn down() -> DVec2 {
    DVec2::new(0.0, -G)
}

/// Gravity tilted so that flat ground is a slope of `tan θ = tan`, downhill along +x.
fn tilted(tan: f64) -> DVec2 {
    let theta = tan.atan();
    G * DVec2::new(theta.sin(), -theta.cos())
}

/// Friction law giving `μ = 0.5` at `λ = 2 λ_min`.
fn friction(lambda_min: f64) -> FrictionLaw {
    FrictionLaw { lambda_min, mu_max: 1.0 }
}

fn material(density: f64, restitution: f64, restitution_max: f64, friction: FrictionLaw) -> Material {
    Material { density, restitution, restitution_max, friction }
}

/// A `width × height` box spline with spacing `height / 2`, constant band `band`.
fn boxed(width: f64, height: f64, band: f64, material: Material) -> BodyDesc {
    let spline = box_spline(width, height, 0.5 * height);
    let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material)
}

fn shaped(control_points: Vec<DVec2>, band: f64, material: Material) -> BodyDesc {
    let spline = Spline::from_control_points(control_points).unwrap();
    let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material)
}

/// One dynamic body on the ground, resting on one band of `band`, no creep bound.
fn one_body(sim: Simulation, body: Entity, steps: usize, size: f64, band: f64) -> Scenario {
    Scenario { sim, steps, size, band, levels: vec![(body, 1.0)], sides: above_ground(&[body]), creep: None }
}

/// The centre of every body must stay above the ground line `y = 0`.
fn above_ground(bodies: &[Entity]) -> Vec<SideRule> {
    bodies.iter().map(|&body| SideRule { body, normal: DVec2::Y, offset: 0.0 }).collect()
}

/// Drift bound on flat ground (m): the 0.1 mm over 10,000 steps.
const FLAT_DRIFT: f64 = 1e-4;

/// Drift bound of a body of size `size` resting where it should stick (m): 1 mm for 1 m.
fn sticking_drift(size: f64) -> f64 {
    1e-3 * size
}

/// Two 0.3 × 0.1 m boxes stacked on the ground; the top one `ratio` times as dense.
fn two_boxes(size: Size, ratio: f64) -> Scenario {
    let (band, e_max) = (0.002, 0.5);
    let mut sim = simulation(down(), 1e-3, size);
    let law = friction(0.001);
    sim.add_body(scaled_ground(1.0, band, material(1000.0, 0.0, e_max, law))).unwrap();
    let bottom_density = 1000.0 / ratio.sqrt();
    let bottom = boxed(0.3, 0.1, band, material(bottom_density, 0.0, e_max, law));
    let top = boxed(0.3, 0.1, band, material(bottom_density * ratio, 0.0, e_max, law));
    // Each box rests at the solver's rest depth: the middle of the combined band (2λ) below it.
    let bottom = sim.add_body(bottom.at(DVec2::new(0.0, 0.05 + band), 0.0)).unwrap();
    let top = sim.add_body(top.at(DVec2::new(0.0, 0.15 + 2.0 * band), 0.0)).unwrap();
    Scenario {
        sim,
        steps: size.pick(240, 1200),
        size: 0.3,
        band: 2.0 * band,
        levels: vec![(bottom, 1.0), (top, 2.0)],
        sides: above_ground(&[bottom, top]),
        creep: Some(CreepRule { body: top, bound: sticking_drift(1.0), vertical: true }),
    }
}

fn heavy_on_light(size: Size) -> Scenario {
    two_boxes(size, 1e4)
}

fn light_on_heavy(size: Size) -> Scenario {
    two_boxes(size, 1e-4)
}

/// A 0.2 m disc at 500 body lengths per second (100 m/s) into a 2 mm wall (1 % of its size).
fn thin_wall(size: Size) -> Scenario {
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.5, 0.5, frictionless());
    let wall = box_spline(0.002, 1.0, 0.05);
    let rugosity = Rugosity::constant(wall.segment_count(), 0.0).unwrap();
    sim.add_body(BodyDesc::new(wall, rugosity).with_material(mat).at(DVec2::new(1.0, 0.0), 0.0).fixed()).unwrap();
    let ball = sim.add_body(disc(0.1, 32, 0.0, mat).with_velocity(DVec2::new(100.0, 0.0), 0.0)).unwrap();
    Scenario {
        sim,
        steps: size.pick(30, 120),
        size: 0.2,
        band: 2e-3,
        levels: vec![(ball, 0.0)],
        // The centre must stay left of the wall's near face (x = 0.999).
        sides: vec![SideRule { body: ball, normal: DVec2::NEG_X, offset: -0.999 }],
        creep: None,
    }
}

/// A `scale × scale/2` box with its bottom `scale/100` above ground scaled alike (it lands after
/// `√(2 · 0.01 L / g)`: 170 steps for L = 1 km). Bands are
/// proportionate: λ = 0.002 L on both, minimum band 0.001 L (the defaults' ratios for L = 1 m).
fn scaled_box(size: Size, scale: f64) -> Scenario {
    let band = 0.002 * scale;
    let e_max = 0.5;
    let mut sim = simulation(down(), 1e-3 * scale, size);
    let law = friction(0.001 * scale);
    sim.add_body(scaled_ground(scale, band, material(1000.0, 0.0, e_max, law))).unwrap();
    let body = boxed(scale, 0.5 * scale, band, material(1000.0, 0.0, e_max, law));
    let body = sim.add_body(body.at(DVec2::new(0.0, 0.26 * scale), 0.0)).unwrap();
    Scenario {
        creep: Some(CreepRule { body, bound: sticking_drift(scale), vertical: false }),
        ..one_body(sim, body, size.pick(240, 1200), scale, 2.0 * band)
    }
}

fn scale_millimetre(size: Size) -> Scenario {
    scaled_box(size, 1e-3)
}

fn scale_kilometre(size: Size) -> Scenario {
    scaled_box(size, 1e3)
}

/// A polygon body dropped from 0.2 m at an angle onto the ground, λ = 2 mm.
fn dropped_polygon(size: Size, control_points: Vec<DVec2>) -> Scenario {
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.2, 0.5, friction(0.001));
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let body = sim.add_body(shaped(control_points, band, mat).at(DVec2::new(0.0, 0.4), 0.3)).unwrap();
    // The cusped square retries at the depth limit on most sub-steps (~0.05 s a step).
    one_body(sim, body, size.pick(240, 480), 0.3, 2.0 * band)
}

/// A 0.3 m square whose corners are each repeated three times: the curve passes through them
/// with a cusp (zero tangent).
fn repeated_points(size: Size) -> Scenario {
    let h = 0.15;
    let corners = [DVec2::new(-h, -h), DVec2::new(h, -h), DVec2::new(h, h), DVec2::new(-h, h)];
    dropped_polygon(size, corners.iter().flat_map(|&c| [c, c, c]).collect())
}

/// A 0.3 m triangle with 8 collinear control points per edge (exactly straight pieces).
fn collinear_points(size: Size) -> Scenario {
    let corners = [DVec2::new(-0.15, -0.1), DVec2::new(0.15, -0.1), DVec2::new(0.0, 0.16)];
    dropped_polygon(size, polygon_control_points(&corners, 0.3 / 8.0))
}

/// A static U-shaped cup 0.8 m wide, 0.5 m tall, walls and floor 8 cm, catching a 0.2 m disc
/// dropped 0.3 m above its rim at 0.5 m/s sideways (it enters the cup 2.5 cm right of centre and
/// rolls into the right wall).
fn c_shape(size: Size) -> Scenario {
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.3, 0.5, friction(0.001));
    let corners =
        [(-0.4, 0.0), (0.4, 0.0), (0.4, 0.5), (0.32, 0.5), (0.32, 0.08), (-0.32, 0.08), (-0.32, 0.5), (-0.4, 0.5)];
    let corners: Vec<DVec2> = corners.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
    sim.add_body(shaped(polygon_control_points(&corners, 0.02), band, mat).fixed().named("cup")).unwrap();
    let ball = disc(0.1, 32, band, mat).at(DVec2::new(-0.1, 0.9), 0.0).with_velocity(DVec2::new(0.5, 0.0), 0.0);
    let ball = sim.add_body(ball).unwrap();
    Scenario {
        sim,
        steps: size.pick(240, 600),
        size: 0.2,
        band: 2.0 * band,
        levels: vec![(ball, 1.0)],
        // The centre never goes below the cup's inner floor (y = 0.08).
        sides: vec![SideRule { body: ball, normal: DVec2::Y, offset: 0.08 }],
        creep: None,
    }
}

/// A blob of radius 0.3 m with 1024 segments dropped from 5 cm onto the ground.
fn segments_1024(size: Size) -> Scenario {
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.2, 0.5, friction(0.001));
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let spline = Generator::Blob { radius: 0.3, roughness: 0.3, seed: 7 }.build(1024).unwrap();
    let lowest = spline.bounds().0.y;
    let rugosity = Rugosity::constant(1024, band).unwrap();
    let blob = BodyDesc::new(spline, rugosity).with_material(mat).at(DVec2::new(0.0, 0.05 - lowest), 0.0);
    let blob = sim.add_body(blob).unwrap();
    one_body(sim, blob, size.pick(120, 480), 0.6, 2.0 * band)
}

/// Ten 0.3 × 0.1 m boxes stacked at rest, each in the middle of the band below it (the
/// solver's rest depth).
fn stack_of_10(size: Size) -> Scenario {
    let (band, e_max) = (0.002, 0.5);
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.0, e_max, friction(0.001));
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let boxes: Vec<Entity> = (0..10)
        .map(|k| {
            let y = 0.05 + 0.1 * k as f64 + band * (k + 1) as f64;
            sim.add_body(boxed(0.3, 0.1, band, mat).at(DVec2::new(0.0, y), 0.0)).unwrap()
        })
        .collect();
    let top = boxes[9];
    Scenario {
        sim,
        steps: size.pick(240, 1200),
        size: 0.3,
        band: 2.0 * band,
        levels: boxes.iter().enumerate().map(|(k, &b)| (b, (k + 1) as f64)).collect(),
        sides: above_ground(&boxes),
        creep: Some(CreepRule { body: top, bound: sticking_drift(1.0), vertical: true }),
    }
}

/// A pyramid of rounded boxes (0.3 × 0.15 m, corner radius 0.02 m, 28 segments, λ = 2 mm,
/// μ = 0.6) standing on the ground: base 5 (15 boxes) for CI, base 20 (210 boxes) for the
/// report, 1 cm apart in a row, each row on the middle of the two below, every interface at
/// the rest depth. Mechanics: nothing moves; the top box may drift at most 5 mm (the issue's
/// bound for 30 s: a tall structure of 20 levels, each level's rest position set by its band).
fn pyramid(size: Size) -> Scenario {
    let base: usize = size.pick(5, 20);
    let (width, height, gap, band) = (0.3, 0.15, 0.01, 0.002);
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.0, 0.5, FrictionLaw { lambda_min: 0.0, mu_max: 0.6 });
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let spline = Generator::RoundedRectangle { width, height, corner_radius: 0.02 }.build(28).unwrap();
    let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
    let mut boxes = Vec::new();
    let mut levels = Vec::new();
    for row in 0..base {
        let count = base - row;
        // Each interface: curves λ apart, the middle of the combined band (the rest depth).
        let y = (row as f64 + 0.5) * height + (row + 1) as f64 * band;
        for i in 0..count {
            let x = (i as f64 - 0.5 * (count - 1) as f64) * (width + gap);
            let body = BodyDesc::new(spline.clone(), rugosity.clone()).with_material(mat).at(DVec2::new(x, y), 0.0);
            let body = sim.add_body(body).unwrap();
            boxes.push(body);
            levels.push((body, (row + 1) as f64));
        }
    }
    let top = *boxes.last().unwrap();
    Scenario {
        sim,
        steps: size.pick(240, 3600),
        size: width,
        band: 2.0 * band,
        levels,
        sides: above_ground(&boxes),
        creep: Some(CreepRule { body: top, bound: 5e-3, vertical: true }),
    }
}

/// Blobs (16 segments, radius 0.1 m, λ = 2 mm) dropped in a grid into a static box: 24 for CI,
/// 200 for the report.
fn pile(size: Size) -> Scenario {
    let count: usize = size.pick(24, 200);
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.3, 0.5, FrictionLaw { lambda_min: 0.001, mu_max: 0.6 });
    let columns = (count as f64).sqrt().ceil() as usize;
    let rows = count.div_ceil(columns);
    let width = columns as f64 * 0.35 + 0.5;
    let wall = |w: f64, h: f64, at: DVec2| boxed(w, h, band, mat).at(at, 0.0).fixed();
    sim.add_body(wall(width + 1.0, 0.4, DVec2::new(0.0, -0.2))).unwrap();
    sim.add_body(wall(0.4, 12.0, DVec2::new(-0.5 * width - 0.2, 6.0))).unwrap();
    sim.add_body(wall(0.4, 12.0, DVec2::new(0.5 * width + 0.2, 6.0))).unwrap();
    let blobs: Vec<Entity> = (0..count)
        .map(|k| {
            let (i, j) = (k % columns, k / columns);
            let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: k as u64 }.build(16).unwrap();
            let rugosity = Rugosity::constant(16, band).unwrap();
            let at = DVec2::new(-0.5 * width + 0.35 + 0.35 * i as f64 + 0.02 * (j % 2) as f64, 0.3 + 0.35 * j as f64);
            sim.add_body(BodyDesc::new(spline, rugosity).with_material(mat).at(at, 0.1 * k as f64)).unwrap()
        })
        .collect();
    let mut sides = above_ground(&blobs);
    for &body in &blobs {
        sides.push(SideRule { body, normal: DVec2::X, offset: -0.5 * width });
        sides.push(SideRule { body, normal: DVec2::NEG_X, offset: -0.5 * width });
    }
    Scenario {
        sim,
        // 3 s: the top row (5 m up for 200 blobs) lands after ~1 s.
        steps: size.pick(240, 360),
        size: 0.2,
        band: 2.0 * band,
        // A blob may rest on as many others as there are rows below it, plus the floor.
        levels: blobs.iter().map(|&b| (b, rows as f64)).collect(),
        sides,
        creep: None,
    }
}

/// The 0.4 × 0.2 m box of `tests/validation.rs` resting on ground of slope `tan`, λ = 4 mm,
/// μ = 0.5: 1,000 steps for CI, 10,000 for the report.
fn resting(size: Size, tan: f64) -> Scenario {
    let (band, e_max) = (0.004, 0.5);
    let mut sim = simulation(tilted(tan), 1e-3, size);
    let mat = material(1000.0, 0.0, e_max, friction(0.002));
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let body = sim.add_body(boxed(0.4, 0.2, band, mat).at(DVec2::new(0.0, 0.1 + band), 0.0)).unwrap();
    Scenario {
        creep: Some(CreepRule {
            body,
            bound: if tan == 0.0 { FLAT_DRIFT } else { sticking_drift(1.0) },
            vertical: true,
        }),
        ..one_body(sim, body, size.pick(1000, 10_000), 0.4, 2.0 * band)
    }
}

fn resting_flat(size: Size) -> Scenario {
    resting(size, 0.0)
}

fn resting_slope(size: Size) -> Scenario {
    resting(size, 0.4)
}

/// A frictionless 0.2 m disc dropped from 1 m with `e = e_max = restitution`.
fn bouncing(size: Size, restitution: f64) -> Scenario {
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, restitution, restitution, frictionless());
    sim.add_body(scaled_ground(1.0, band, mat)).unwrap();
    let ball = sim.add_body(disc(0.2, 64, band, mat).at(DVec2::new(0.0, 1.2 + 2.0 * band), 0.0)).unwrap();
    one_body(sim, ball, size.pick(240, 1200), 0.4, 2.0 * band)
}

fn restitution_0(size: Size) -> Scenario {
    bouncing(size, 0.0)
}

fn restitution_1(size: Size) -> Scenario {
    bouncing(size, 1.0)
}

/// A 0.2 m disc spinning at 100 rev/s dropped from 0.1 m onto ground with μ = 0.5. Friction
/// turns the spin into rolling at about `r ω / 3 = 42 m/s`, so the ground is 400 m wide (its top
/// is still exactly flat at `y = 0`).
fn spinning(size: Size) -> Scenario {
    let band = 0.002;
    let mut sim = simulation(down(), 1e-3, size);
    let mat = material(1000.0, 0.3, 0.5, friction(0.001));
    sim.add_body(scaled_ground(10.0, band, mat)).unwrap();
    let spin = 2.0 * std::f64::consts::PI * 100.0;
    let ball = disc(0.2, 64, band, mat).at(DVec2::new(0.0, 0.3), 0.0).with_velocity(DVec2::ZERO, spin);
    let ball = sim.add_body(ball).unwrap();
    // Spinning on the ground, the surface moves at 126 m/s: conservative advancement cuts
    // each step into up to `max_substeps` sub-steps (~0.07 s a step in the test profile).
    one_body(sim, ball, size.pick(60, 600), 0.4, 2.0 * band)
}

/// Every case, in report order.
pub const CASES: [Case; 17] = [
    Case::new("heavy_on_light", "a box 10⁴ times denser on a light box on the ground", heavy_on_light),
    Case::new("light_on_heavy", "a box 10⁴ times lighter on a heavy box on the ground", light_on_heavy),
    Case::new("thin_wall", "a 0.2 m disc at 100 m/s (500 lengths/s) into a 2 mm wall", thin_wall),
    Case::new("scale_millimetre", "a 1 mm box dropped on the ground, λ = 2 µm", scale_millimetre),
    Case::new("scale_kilometre", "a 1 km box dropped on the ground, λ = 2 m", scale_kilometre),
    Case::new("repeated_points", "a square with tripled corners (cusps) dropped on the ground", repeated_points),
    Case::new("collinear_points", "a triangle of collinear control points dropped on the ground", collinear_points),
    Case::new("c_shape", "a U-shaped cup catching a 0.2 m disc", c_shape),
    Case::new("segments_1024", "a 1024-segment blob landing and resting", segments_1024),
    Case::new("stack_of_10", "ten boxes stacked at rest", stack_of_10),
    Case::new("pyramid", "a pyramid of rounded boxes standing 30 s (base 5 in CI, base 20: 210 boxes)", pyramid),
    Case::new("pile", "blobs dropped into a box (24 in CI, 200 in the report)", pile),
    Case::new("resting_flat", "a box resting on flat ground (1,000 / 10,000 steps)", resting_flat),
    Case::new("resting_slope", "a box resting on a slope tan θ = 0.4 < μ = 0.5 (1,000 / 10,000 steps)", resting_slope),
    Case::new("restitution_0", "a disc dropped from 1 m with e = 0", restitution_0),
    Case::new("restitution_1", "a disc dropped from 1 m with e = e_max = 1", restitution_1),
    Case::new("spinning", "a disc spinning at 100 rev/s landing on the ground", spinning),
];

/// The case named `name`.
///
/// # Panics
/// If there is no such case.
#[must_use]
pub fn case(name: &str) -> &'static Case {
    CASES.iter().find(|c| c.name == name).unwrap_or_else(|| panic!("no stress case {name}"))
}
