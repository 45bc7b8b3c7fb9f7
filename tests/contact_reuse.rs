//! Reused contacts (docs/model.md §3b): a pair in contact whose bodies have moved relative to
//! each other by at most `contact_reuse` of the band since its last query keeps that query's
//! contacts, evaluated again at the same curve parameters at the new poses, their normals
//! turned with B. Two rounded boxes, one resting on the other in its band, fly and turn as
//! one (no gravity): their relative motion is tiny, their motion in the world is not. The
//! contact hook records what the engine hands on. Reused contacts not moved with the bodies
//! would lie a step's travel (8 mm) off their curves, normals not turned with B a step's turn
//! (4e-6 rad) off; and a fresh query at the same poses finds no leaf pair in contact that the
//! engine missed.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::DVec2;
use rugosa::{
    AobbTree, BodyDesc, Generator, Material, PairAction, PairContacts, Pose, RigidState, Rugosity, Simulation,
    SimulationSettings, SleepSettings,
};
use rugosa::{BodyContact, BodyQuery, BodyShape, QuerySettings, query_bodies};

const BAND: f64 = 0.005;
/// Gap between the boxes' curves: inside the combined band (1 cm) and above its middle, so
/// the push-out leaves it alone.
const GAP: f64 = 0.006;
const SPIN: f64 = 5e-4;

/// What the hook saw at one detection.
struct Seen {
    poses: (Pose, Pose),
    contacts: Vec<BodyContact>,
}

fn rounded_box() -> BodyDesc {
    let spline = Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.05 }.build(24).unwrap();
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    BodyDesc::new(spline, rugosity)
}

/// What flying the two boxes as one for 120 steps showed.
struct Flight {
    settings: SimulationSettings,
    reused: u64,
    kept: usize,
    /// The largest distance of a contact's point from its curve at the poses handed on (m).
    worst_point: f64,
    worst_turn: f64,
    worst_outside: f64,
}

#[test]
fn reused_contacts_follow_the_bodies() {
    // Both move at the same velocity and turn at the same rate: B's place in A's frame turns
    // at −SPIN about A's centre, 0.5 m away: 2e-6 m a step, a fifth of the reuse limit.
    let flight = fly(DVec2::new(1.0, 0.3), SPIN, Material::default(), false);
    let Flight { settings, reused, kept, worst_point, worst_turn, worst_outside } = flight;
    assert!(reused > 60, "only {reused} of 120 detections reused the contacts");
    assert!(kept > 200, "only {kept} contacts were kept from one detection to the next");
    assert!(worst_point <= 1e-12, "a contact lies {worst_point:e} m off its curve at the poses it was handed on with");
    // Both boxes turn by 4e-6 rad a step; a normal left as it was would show that.
    assert!(worst_turn <= 1e-12, "a reused normal did not turn with B: {worst_turn:e}");
    assert!(worst_outside <= settings.contact_reuse, "a contact lies {worst_outside:e} of its band outside it");
}

/// Bodies that barely move keep their reused contacts as they were until they have moved by
/// a thousandth of what the solver resolves (its tolerance times the combined band, 1e-12 m
/// here): the boxes drift 2e-13 m a step, or turn as one about A's centre by as much at a
/// box's radius, so the contacts go stale by up to that limit and are evaluated again.
/// Compared with the last step instead of the last evaluation, the staleness would grow without
/// bound (2.4e-11 m over the flight); with the turn left out of the motion, the turning boxes'
/// contacts went stale by the whole limit plus rounding (1.0e-12 m) and this fails.
#[test]
fn barely_moving_bodies_keep_their_contacts_within_a_bound() {
    // A box's radius about its centre of mass, band included.
    let radius = DVec2::new(0.5, 0.25).length() + BAND;
    let per_step = 2e-13;
    // The turning boxes turn as one about A's centre (B orbits it), so nothing moves in the
    // pair while each box's angle changes.
    for (velocity, spin) in [(DVec2::new(60.0 * per_step, 0.0), 0.0), (DVec2::ZERO, 60.0 * per_step / radius)] {
        let flight = fly(velocity, spin, Material::default(), true);
        let Flight { settings, reused, kept, worst_point, worst_outside, .. } = flight;
        let limit = 1e-3 * settings.solver.tolerance * 2.0 * BAND;
        println!("velocity {velocity}, spin {spin:e}: stale by up to {worst_point:.2e} m, limit {limit:.2e} m");
        assert!(reused > 60 && kept > 200, "{reused} pairs reused, {kept} contacts kept");
        assert!(worst_point > 0.1 * limit, "the contacts were evaluated again at every step: {worst_point:e} m");
        assert!(worst_point <= limit + 1e-15, "a contact lies {worst_point:e} m off its curve, limit {limit:e} m");
        assert!(worst_outside <= settings.contact_reuse, "a contact lies {worst_outside:e} of its band outside it");
    }
}

/// Flies the boxes of `material`, one resting on the other, at `velocity` and `spin` for 120
/// steps, B also orbiting A's centre with `orbit`.
fn fly(velocity: DVec2, spin: f64, material: Material, orbit: bool) -> Flight {
    let settings = SimulationSettings {
        gravity: DVec2::ZERO,
        threads: 1,
        sleep: SleepSettings::off(),
        contact_reuse: 1e-3,
        ..SimulationSettings::default()
    };
    let mut sim = Simulation::new(settings.clone()).unwrap();
    let a =
        sim.add_body(rounded_box().with_material(material).at(DVec2::ZERO, 0.0).with_velocity(velocity, spin)).unwrap();
    // With `orbit`, B moves as the point of A's frame at its centre would: the two turn as one.
    let above = DVec2::new(0.0, 0.5 + GAP);
    let velocity_b = if orbit { velocity + spin * above.perp() } else { velocity };
    let b = sim.add_body(rounded_box().with_material(material).at(above, 0.0).with_velocity(velocity_b, spin)).unwrap();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let record = Arc::clone(&seen);
    sim.set_contact_hook(Some(Arc::new(move |pair: &PairContacts<'_>| {
        let poses = (pair.state_a.pose(), pair.state_b.pose());
        record.lock().unwrap().push(Seen { poses, contacts: pair.contacts.to_vec() });
        PairAction::Keep
    })));
    let world = sim.world();
    let geometry = |e| {
        (
            (*world.get::<&rugosa::Spline>(e).unwrap()).clone(),
            (*world.get::<&Rugosity>(e).unwrap()).clone(),
            (*world.get::<&AobbTree>(e).unwrap()).clone(),
        )
    };
    let ((spline_a, rugosity_a, tree_a), (spline_b, rugosity_b, tree_b)) = (geometry(a), geometry(b));
    let (shape_a, shape_b) = (BodyShape::new(&spline_a, &rugosity_a), BodyShape::new(&spline_b, &rugosity_b));
    let query_settings = QuerySettings { min_band: settings.min_band, ..QuerySettings::default() };
    let mut query = BodyQuery::default();
    let dt = settings.time_step;
    let (mut reused, mut compared, mut kept) = (0, 0, 0);
    let (mut worst_point, mut worst_turn, mut worst_outside): (f64, f64, f64) = (0.0, 0.0, 0.0);
    // Per contact (leaf pair and ordinal): its parameters and its normal's component along B's
    // tangent there, at the last detection.
    let mut last: HashMap<(u32, u32, usize), (f64, f64, f64)> = HashMap::new();
    for step in 0..120 {
        sim.step(dt);
        reused += sim.take_profile().counters.reused_pairs;
        for seen in seen.lock().unwrap().drain(..) {
            let (pose_a, pose_b) = seen.poses;
            let mut ordinal = HashMap::new();
            for engine in &seen.contacts {
                let c = &engine.contact;
                let piece_a = spline_a.segment(engine.segment_a as usize).transformed(&pose_a);
                let piece_b = spline_b.segment(engine.segment_b as usize).transformed(&pose_b);
                // Moved with the bodies: the points of both curves at the contact's parameters.
                worst_point = worst_point
                    .max(c.point_a.distance(piece_a.position(c.t)))
                    .max(c.point_b.distance(piece_b.position(c.s)));
                // Within the band, or outside it by at most the reuse limit (an overlap's end).
                let band = c.lambda_a + c.lambda_b;
                worst_outside = worst_outside.max((c.distance - band) / band);
                // Turned with B: where the parameters are those of the last detection (a reuse),
                // the normal makes the same angle with B's tangent there.
                let along = c.normal.dot(piece_b.derivative(c.s).normalize());
                let k = ordinal.entry((engine.segment_a, engine.segment_b)).or_insert(0);
                let key = (engine.segment_a, engine.segment_b, *k);
                *k += 1;
                if let Some(&(t, s, before)) = last.get(&key)
                    && (t, s) == (c.t, c.s)
                {
                    worst_turn = worst_turn.max((along - before).abs());
                    kept += 1;
                }
                last.insert(key, (c.t, c.s, along));
                compared += 1;
            }
            // No leaf pair in contact is missed: each one a fresh query finds clearly inside the
            // band (by more than twice the reuse limit) is among the engine's, or the engine has
            // a contact at the same place (within 1e-3 of the band) from a neighbouring leaf
            // pair. Where a corner's rounding meets a side the distance is flat to 1e-15 over a
            // few µm (it grows like the cube of the offset), so the search's nearest points of the
            // three leaf pairs around the joint land up to 2e-6 m apart while the engine's recalled
            // ones land on the joint itself, one contact the three share.
            let fresh =
                query_bodies(&shape_a, &tree_a, &pose_a, &shape_b, &tree_b, &pose_b, &query_settings, &mut query);
            for f in &fresh.contacts {
                let band = f.contact.lambda_a + f.contact.lambda_b;
                let leaf = (f.segment_a, f.segment_b);
                let listed = seen.contacts.iter().any(|e| {
                    (e.segment_a, e.segment_b) == leaf || e.contact.point_a.distance(f.contact.point_a) <= 1e-3 * band
                });
                let marginal = f.contact.distance > band * (1.0 - 2.0 * settings.contact_reuse);
                assert!(listed || marginal, "step {step}: leaf pair {leaf:?} is in contact and the engine missed it");
            }
        }
    }
    println!(
        "{reused} pairs reused, {compared} contacts checked, {kept} kept from the detection before; largest: point \
         off its curve {worst_point:.2e} m, change of the normal against B's tangent {worst_turn:.2e}, outside the \
         band {worst_outside:.2e} of it"
    );
    let (state_a, state_b) = (sim.state(a).unwrap(), sim.state(b).unwrap());
    let still =
        |s: RigidState| (s.linear_velocity - velocity).length() < 1e-3 && (s.angular_velocity - spin).abs() < 1e-3;
    assert!(still(state_a) && still(state_b), "the boxes did not fly as one: {state_a:?} {state_b:?}");
    Flight { settings, reused, kept, worst_point, worst_turn, worst_outside }
}
