//! Step control: no tunnelling at any speed, defined behaviour for overlapping input,
//! stages that have nothing to do are skipped, bodies added and removed between steps.

mod common;

use common::{box_spline, disc, frictionless, material, simulation};
use std::sync::{Arc, Mutex};

use glam::DVec2;
use rugosa::{BodyDesc, Rugosity, Simulation, SimulationSettings, SleepSettings};

fn wall(thickness: f64, height: f64, at: DVec2) -> BodyDesc {
    let spline = box_spline(thickness, height, thickness.min(0.05));
    let rugosity = Rugosity::constant(spline.segment_count(), 0.0).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material(0.5, frictionless())).at(at, 0.0).fixed().named("wall")
}

fn assert_finite(sim: &Simulation) {
    sim.validate().unwrap();
}

#[test]
fn fast_disc_never_passes_a_thin_wall() {
    // A 0.2 m disc at up to 10 km/s against a 2 cm wall 1 m away; gravity off. Each step moves
    // the disc up to 83 m, far more than the wall is thick: conservative advancement must stop
    // it in the band and the impulse must send it back (e = 0.5).
    for speed in [50.0, 500.0, 10_000.0] {
        let mut sim = simulation(DVec2::ZERO);
        sim.add_body(wall(0.02, 2.0, DVec2::new(1.0, 0.0))).unwrap();
        let ball = sim
            .add_body(disc(0.1, 32, 0.0, material(0.5, frictionless())).with_velocity(DVec2::new(speed, 0.0), 0.0))
            .unwrap();
        for _ in 0..60 {
            sim.step(sim.settings().time_step);
        }
        assert_finite(&sim);
        let s = sim.state(ball).unwrap();
        assert!(s.position.x < 1.0, "speed {speed}: the disc is at x = {} beyond the wall", s.position.x);
        assert!(s.linear_velocity.x < 0.0, "speed {speed}: not bounced back ({})", s.linear_velocity.x);
        let expected = 0.5 * speed;
        assert!(
            (s.linear_velocity.x + expected).abs() < 1e-9 * expected,
            "speed {speed}: rebound {}",
            s.linear_velocity.x
        );
    }
}

#[test]
fn sliding_past_a_wall_does_not_shorten_the_sub_steps() {
    // A disc (r = 0.1 m, band 1 mm) falls at 5 m/s along a wall, 3 mm from it (outside the
    // 1 mm + 1 mm combined band), gravity along the wall. Its leaf pairs with the wall are
    // 3 − 0.5 = 2.5 mm from three quarters into the band (`approach_depth`). Bounding the
    // closing speed by the whole relative speed would allow 2.5 mm / 5 m/s = 0.5 ms per sub-step,
    // 17 sub-steps per 1/120 s step; along
    // the wall's normal nothing closes, so the sub-steps are limited only by the bodies' own
    // travel: at most a few per step. Nothing may touch.
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    sim.add_body(wall(0.2, 40.0, DVec2::new(0.0, 0.0))).unwrap();
    let mat = material(0.5, frictionless());
    let start = DVec2::new(0.1 + 0.1 + 0.003, 15.0);
    let ball =
        sim.add_body(disc(0.1, 32, 0.001, mat).at(start, 0.0).with_velocity(DVec2::new(0.0, -5.0), 0.0)).unwrap();
    let steps = 120;
    for _ in 0..steps {
        sim.step(sim.settings().time_step);
    }
    assert_finite(&sim);
    let counters = sim.profile().counters;
    let s = sim.state(ball).unwrap();
    assert_eq!(counters.contacts, 0, "the disc touched the wall");
    assert_eq!(s.position.x, start.x, "the disc moved sideways");
    let per_step = counters.substeps as f64 / steps as f64;
    assert!(per_step <= 3.0, "{per_step} sub-steps per step");
}

#[test]
fn a_body_at_rest_without_gravity_does_not_shorten_the_sub_steps() {
    // Without gravity a body at rest has no motion margin; nothing of it moves, so it bounds
    // nothing. Before this was fixed its zero margin forced every sub-step to the 1e-9 floor and
    // a step never ended. Both models: one sub-step per step until the discs are near (0.2 s of
    // the 0.25 s the 0.5 m gap takes at 2 m/s), and the step always ends (at most
    // `max_substeps` sub-steps plus the retries of the last one).
    for model in [rugosa::ContactModel::Solver, rugosa::ContactModel::SeedMicroCollisions] {
        let mut sim = Simulation::new(SimulationSettings {
            gravity: DVec2::ZERO,
            threads: 1,
            contact_model: model,
            ..SimulationSettings::default()
        })
        .unwrap();
        let mat = material(1.0, frictionless());
        sim.add_body(disc(0.25, 64, 0.001, mat).with_velocity(DVec2::new(2.0, 0.0), 0.0)).unwrap();
        sim.add_body(disc(0.25, 64, 0.001, mat).at(DVec2::new(1.0, 0.0), 0.0)).unwrap();
        let steps = (0.2 / sim.settings().time_step) as u64;
        for _ in 0..steps {
            sim.step(sim.settings().time_step);
        }
        assert_eq!(sim.profile().counters.substeps, steps, "{model:?}");
        for _ in 0..steps {
            sim.step(sim.settings().time_step);
        }
        let per_step = sim.profile().counters.substeps as f64 / (2 * steps) as f64;
        assert!(per_step < 2.0, "{model:?}: {per_step} sub-steps per step through the impact");
    }
}

#[test]
fn bodies_at_rest_near_each_other_without_gravity_take_one_sub_step_per_step() {
    // Two boxes at rest beside a fixed one, gravity off: 3 cm apart (a separate pair) and 6 mm
    // apart (within the 10 mm combined band, less than halfway in: nothing pushes). Nothing
    // moves, so nothing may bound the sub-step. A pair carried from its last query with no
    // margin (neither body moves) once bounded it by that zero margin: every step took the
    // sub-step cap of 256 and one more.
    for gap in [0.03, 0.006] {
        let mut sim = simulation(DVec2::ZERO);
        let boxed = |x: f64| {
            let spline = box_spline(1.0, 1.0, 0.1);
            let rugosity = Rugosity::constant(spline.segment_count(), 0.005).unwrap();
            BodyDesc::new(spline, rugosity).with_material(material(0.5, frictionless())).at(DVec2::new(x, 0.0), 0.0)
        };
        sim.add_body(boxed(0.0).fixed()).unwrap();
        let free = sim.add_body(boxed(1.0 + gap)).unwrap();
        let start = sim.state(free).unwrap();
        let steps = 10;
        for _ in 0..steps {
            sim.step(sim.settings().time_step);
        }
        assert_finite(&sim);
        let counters = sim.profile().counters;
        assert_eq!(counters.substeps, steps, "gap {gap}: {} sub-steps in {steps} steps", counters.substeps);
        assert_eq!(counters.substep_cap_hits, 0, "gap {gap}");
        let end = sim.state(free).unwrap();
        assert_eq!((end.position, end.angle), (start.position, start.angle), "gap {gap}: the box moved");
    }
}

#[test]
fn thin_fast_body_never_passes_a_disc() {
    // A 1 cm × 40 cm plank spinning and flying at 300 m/s into a heavy static disc.
    let mut sim = simulation(DVec2::ZERO);
    let target = disc(0.3, 32, 0.0, material(0.5, frictionless())).at(DVec2::new(2.0, 0.0), 0.0).fixed();
    sim.add_body(target).unwrap();
    let spline = box_spline(0.4, 0.01, 0.01);
    let rugosity = Rugosity::constant(spline.segment_count(), 0.0).unwrap();
    let plank = BodyDesc::new(spline, rugosity)
        .with_material(material(0.5, frictionless()))
        .at(DVec2::new(0.0, 0.05), 0.3)
        .with_velocity(DVec2::new(300.0, 0.0), 40.0);
    let plank = sim.add_body(plank).unwrap();
    for _ in 0..30 {
        sim.step(sim.settings().time_step);
    }
    assert_finite(&sim);
    let s = sim.state(plank).unwrap();
    assert!(s.position.x < 2.0 && s.linear_velocity.x < 0.0, "plank passed or did not bounce: {s:?}");
}

#[test]
fn overlapping_input_is_counted_and_never_retried() {
    // Two discs spawned overlapping: no retry can separate them. They must not stall the step
    // (no retries, no floor hits) and must not produce NaN; the recovery contact pushes them
    // apart without kinetic energy (split impulses).
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    let mat = material(0.5, frictionless());
    sim.add_body(disc(0.2, 32, 0.002, mat)).unwrap();
    sim.add_body(disc(0.2, 32, 0.002, mat).at(DVec2::new(0.3, 0.0), 0.0)).unwrap();
    for _ in 0..60 {
        sim.step(sim.settings().time_step);
    }
    assert_finite(&sim);
    let counters = sim.profile().counters;
    assert!(counters.persistent_overlaps > 0, "{counters:?}");
    assert_eq!(counters.retries, 0, "{counters:?}");
    assert_eq!(counters.retry_limit_hits, 0, "{counters:?}");
    assert!(counters.recovery_contacts > 0, "{counters:?}");
}

/// A disc flying at 30 m/s, and a static disc teleported into its path behind the engine's
/// back (no `mark_moved`), so the conservative-advancement data are stale and the next step
/// ends in an intersection.
fn ambush(max_retry_depth: u32, contact_model: rugosa::ContactModel) -> (Simulation, hecs::Entity) {
    let settings =
        SimulationSettings { gravity: DVec2::ZERO, max_retry_depth, contact_model, threads: 1, ..Default::default() };
    let mut sim = Simulation::new(settings).unwrap();
    let mat = material(1.0, frictionless());
    let runner = sim.add_body(disc(0.2, 16, 0.001, mat).with_velocity(DVec2::new(30.0, 0.0), 0.0)).unwrap();
    let blocker = sim.add_body(disc(0.2, 16, 0.001, mat).at(DVec2::new(100.0, 0.0), 0.0).fixed()).unwrap();
    sim.step(sim.settings().time_step);
    let ahead = sim.state(runner).unwrap().position + DVec2::new(0.55, 0.02);
    sim.world_mut().get::<&mut rugosa::RigidState>(blocker).unwrap().position = ahead;
    (sim, runner)
}

#[test]
fn an_intersection_is_retried_shorter_and_the_depth_limit_holds_bodies() {
    use rugosa::ContactModel::{SeedMicroCollisions, Solver};
    // Depth 8: the step is halved until the runner stops short of the blocker, then it bounces.
    for model in [Solver, SeedMicroCollisions] {
        let (mut sim, runner) = ambush(8, model);
        let energy = sim.kinetic_energy();
        for _ in 0..30 {
            sim.step(sim.settings().time_step);
        }
        let counters = sim.profile().counters;
        assert!(counters.retries >= 1, "{model:?}: {counters:?}");
        assert_eq!(counters.retry_limit_hits, 0, "{model:?}: {counters:?}");
        assert!(sim.state(runner).unwrap().linear_velocity.x < 0.0, "{model:?}: did not bounce");
        assert!(sim.kinetic_energy() <= energy * (1.0 + 1e-12), "{model:?}");
        assert_finite(&sim);
    }
    // Depth 0, solver: the intersecting sub-step is accepted (counted) — nothing is held with a
    // velocity its position ignores — and the overlap-recovery contact pushes the runner out
    // while the collision law sends it back; its energy never grows.
    let (mut sim, runner) = ambush(0, Solver);
    let energy = sim.kinetic_energy();
    for _ in 0..30 {
        sim.step(sim.settings().time_step);
        assert!(sim.kinetic_energy() <= energy * (1.0 + 1e-12), "energy grew to {}", sim.kinetic_energy());
    }
    let counters = sim.profile().counters;
    assert!(counters.retry_limit_hits >= 1, "{counters:?}");
    assert!(sim.state(runner).unwrap().linear_velocity.x < 0.0, "did not bounce");
    assert_finite(&sim);
    // Depth 0, seed model: the runner is held where it was for the rest of the sub-step.
    let (mut sim, runner) = ambush(0, SeedMicroCollisions);
    let energy = sim.kinetic_energy();
    let start = sim.state(runner).unwrap();
    sim.step(sim.settings().time_step);
    let counters = sim.profile().counters;
    assert!(counters.retry_limit_hits >= 1, "{counters:?}");
    assert_eq!(sim.state(runner).unwrap(), start, "a held body keeps its state");
    for _ in 0..30 {
        sim.step(sim.settings().time_step);
        assert!(sim.kinetic_energy() <= energy * (1.0 + 1e-12), "energy grew to {}", sim.kinetic_energy());
    }
    assert_finite(&sim);
}

#[test]
fn a_lone_body_skips_the_contact_stages() {
    // No pairs: the narrow phase, impulse and micro-collision stages each count one skip per
    // sub-step and do no work.
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    sim.add_body(disc(0.2, 32, 0.0, material(0.5, frictionless()))).unwrap();
    for _ in 0..10 {
        sim.step(sim.settings().time_step);
    }
    let counters = sim.profile().counters;
    assert_eq!(counters.candidate_pairs, 0);
    assert_eq!(counters.leaf_pairs, 0);
    assert_eq!(counters.substeps, 10);
    // Per sub-step the narrow phase, collide, contact solver and position correction skip, and
    // per step the sleep stage (sleeping is off here); the first step also runs detection at
    // the spawn poses (one more narrow-phase skip).
    assert_eq!(counters.skipped_stages, 4 * 10 + 10 + 1, "{counters:?}");
}

#[test]
fn bodies_can_be_added_and_removed_between_steps() {
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    let mat = material(0.3, frictionless());
    let first = sim.add_body(disc(0.2, 16, 0.002, mat)).unwrap();
    sim.step(sim.settings().time_step);
    let second = sim.add_body(disc(0.2, 16, 0.002, mat).at(DVec2::new(0.0, 1.0), 0.0)).unwrap();
    sim.step(sim.settings().time_step);
    assert_eq!(sim.body_count(), 2);
    assert!(sim.remove_body(first));
    assert!(!sim.remove_body(first), "removed twice");
    sim.step(sim.settings().time_step);
    assert_eq!(sim.bodies().collect::<Vec<_>>(), vec![second]);
    assert_finite(&sim);
}

#[test]
fn advance_runs_fixed_steps_and_returns_the_blend_factor() {
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    let body = sim.add_body(disc(0.2, 16, 0.0, material(0.3, frictionless()))).unwrap();
    let dt = sim.settings().time_step;
    let alpha = sim.advance(2.5 * dt);
    assert!((sim.time() - 2.0 * dt).abs() < 1e-15);
    assert!((alpha - 0.5).abs() < 1e-9, "alpha {alpha}");
    let blended = sim.interpolated_state(body, alpha).unwrap();
    let now = sim.state(body).unwrap();
    assert!(blended.position.y > now.position.y, "the blend lies between the last two states");
    assert_eq!(sim.advance(f64::NAN), alpha, "a NaN frame time is ignored");
    assert_eq!(sim.interpolated_state(body, f64::NAN), Some(now), "a NaN blend factor gives the step's end");
    assert_eq!(sim.interpolated_state(body, 7.0), Some(now), "the blend factor is clamped to [0, 1]");
}

#[test]
fn an_undrained_event_log_keeps_at_most_its_capacity_and_counts_the_rest() {
    // A disc resting on a wall-box records a resting event per contact and sub-step; never
    // drained, the log stops at `event_capacity` and every later event is counted as dropped.
    let capacity = 50;
    let mut sim = Simulation::new(SimulationSettings {
        gravity: DVec2::new(0.0, -9.81),
        threads: 1,
        event_capacity: capacity,
        // Awake: a sleeping disc records no resting events.
        sleep: SleepSettings::off(),
        ..SimulationSettings::default()
    })
    .unwrap();
    sim.add_body(wall(2.0, 0.2, DVec2::new(0.0, -0.1))).unwrap();
    sim.add_body(disc(0.1, 32, 0.0, material(0.0, frictionless())).at(DVec2::new(0.0, 0.101), 0.0)).unwrap();
    for _ in 0..240 {
        sim.step(sim.settings().time_step);
    }
    let dropped = sim.profile().counters.dropped_events;
    let kept = sim.drain_events().count();
    assert_eq!(kept, capacity);
    assert!(dropped > 0, "240 steps of resting contact should overflow a log of {capacity}");
    sim.step(sim.settings().time_step);
    assert!(sim.drain_events().count() > 0, "a drained log records again");
}

#[test]
fn a_step_outside_its_range_is_refused_and_a_stalled_frame_is_clamped() {
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    let body = sim.add_body(disc(0.2, 16, 0.0, material(0.3, frictionless()))).unwrap();
    let before = sim.state(body).unwrap();
    for dt in [1e154, f64::INFINITY, f64::NAN, -1.0, 0.0, 1e-12] {
        let err = sim.try_step(dt).unwrap_err();
        assert_eq!(err.field, "dt", "{err}");
        sim.step(dt);
    }
    assert_eq!(sim.state(body).unwrap(), before, "a refused step changed the state");
    assert_eq!(sim.time(), 0.0);
    assert_eq!(sim.profile().counters.refused_steps, 6);
    // A frame of 10⁹ s (a stalled game) takes max_steps_per_advance steps and drops the rest.
    let alpha = sim.advance(1e9);
    assert!((0.0..1.0).contains(&alpha), "α = {alpha}");
    let steps = f64::from(sim.settings().max_steps_per_advance);
    assert!((sim.time() - steps * sim.settings().time_step).abs() < 1e-12);
    assert!(sim.profile().counters.dropped_steps > 1_000_000_000);
    assert!(sim.state(body).unwrap().is_finite());
    let alpha = sim.advance(f64::MAX);
    assert!(alpha.is_finite() && (0.0..1.0).contains(&alpha), "α = {alpha}");
}

#[test]
fn a_body_broken_through_world_mut_is_counted_not_passed_on() {
    // A disc resting on a wall-floor. Its state made NaN between steps: the step counts it and
    // keeps its last good state (no NaN reaches the solver, nothing panics). Its tree removed:
    // counted at every step while it lasts (it can collide with nothing, so it falls — but
    // not quietly).
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    sim.add_body(wall(2.0, 0.2, DVec2::new(0.0, -0.1))).unwrap();
    let ball = sim.add_body(disc(0.1, 32, 0.0, material(0.0, frictionless())).at(DVec2::new(0.0, 0.101), 0.0)).unwrap();
    for _ in 0..30 {
        sim.step(sim.settings().time_step);
    }
    let good = sim.state(ball).unwrap();
    sim.take_profile();
    sim.world_mut().get::<&mut rugosa::RigidState>(ball).unwrap().position.x = f64::NAN;
    sim.step(sim.settings().time_step);
    assert_eq!(sim.take_profile().counters.broken_bodies, 1);
    let now = sim.state(ball).unwrap();
    assert!(now.is_finite(), "{now:?}");
    assert!((now.position - good.position).length() < 1e-3, "kept near its last good state: {now:?} against {good:?}");
    sim.world_mut().remove_one::<rugosa::AobbTree>(ball).unwrap();
    for _ in 0..5 {
        sim.step(sim.settings().time_step);
    }
    assert_eq!(sim.take_profile().counters.broken_bodies, 5);
    assert!(sim.state(ball).unwrap().is_finite());
    let found = sim.validate().unwrap_err();
    assert!(found.contains("missing") && found.contains("AobbTree"), "{found}");
}

#[test]
fn an_impact_lands_in_the_band_no_deeper_than_the_approach_depth() {
    // A disc (r = 0.1 m, band 5 mm) flies at 3 m/s, gravity off, at a fixed disc of the same
    // size. Conservative advancement ends each sub-step before the pair comes `approach_depth`
    // into its 10 mm combined band, so the first narrow phase that finds the pair in contact (the
    // contact hook sees every one) finds its nearest contact within the band and no nearer than
    // `(1 − approach_depth)` of it, and the deeper the approach, the deeper it lands (the
    // sub-step that reaches the band is cut 5 % short of its bound, about the same share of a gap
    // that shrinks with the depth); the collision then sends the disc back.
    let (radius, band, speed) = (0.1, 0.005, 3.0);
    let mut shallower = f64::INFINITY;
    for depth in [0.3, 0.5, 0.75, 0.9] {
        let settings = SimulationSettings {
            gravity: DVec2::ZERO,
            threads: 1,
            approach_depth: depth,
            sleep: SleepSettings::off(),
            ..SimulationSettings::default()
        };
        let mut sim = Simulation::new(settings).unwrap();
        let landed: Arc<Mutex<Option<f64>>> = Arc::default();
        let seen = Arc::clone(&landed);
        sim.set_contact_hook(Some(Arc::new(move |pair: &rugosa::PairContacts<'_>| {
            let nearest = pair.contacts.iter().map(|c| c.contact.distance).fold(f64::INFINITY, f64::min);
            seen.lock().unwrap().get_or_insert(if pair.crossing { f64::NEG_INFINITY } else { nearest });
            rugosa::PairAction::Keep
        })));
        let mat = material(0.5, frictionless());
        sim.add_body(disc(radius, 64, band, mat).at(DVec2::new(0.5, 0.0), 0.0).fixed()).unwrap();
        let ball = sim.add_body(disc(radius, 64, band, mat).with_velocity(DVec2::new(speed, 0.0), 0.0)).unwrap();
        for _ in 0..60 {
            sim.step(sim.settings().time_step);
        }
        let distance = landed.lock().unwrap().unwrap_or_else(|| panic!("depth {depth}: no contact"));
        let combined = 2.0 * band;
        eprintln!("approach depth {depth}: the impact landed {distance:.4e} m apart in a {combined} m band");
        assert!(
            distance <= combined && distance >= (1.0 - depth) * combined,
            "depth {depth}: the impact landed at a distance of {distance} m (band {combined} m)"
        );
        assert!(distance < shallower, "depth {depth}: landed at {distance} m, not deeper than {shallower} m");
        shallower = distance;
        assert!(sim.state(ball).unwrap().linear_velocity.x < 0.0, "depth {depth}: the disc did not bounce back");
    }
}
