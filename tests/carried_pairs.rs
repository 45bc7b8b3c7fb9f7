//! Pairs carried from an earlier query (docs/model.md §3b) never hide a contact: a landing pile
//! is stepped, and after every step every pair of bodies is queried afresh, searching every
//! leaf pair at the final poses. Each pair the fresh query finds crossing, or in contact clearly
//! inside the band, must be among the pairs the engine reports touching at the end of the step.
//!
//! "Clearly": a leaf pair answered from its memory (§3a) may place a contact up to `2δ` above
//! the true minimum, `δ ≤ coherence × band`, so a contact within that of the band's edge may
//! be missed by the memory, not by the carry. The carry itself has no slack: a carried pair is
//! proven apart by more than half its clearance. Conversely, every pair the engine reports
//! touching is in contact by the fresh query: a recalled contact is never nearer than the true
//! minimum.

#[path = "common/pile.rs"]
mod pile;

use hecs::Entity;
use rugosa::{AobbTree, RigidState, Rugosity, Simulation, SimulationSettings, SleepSettings, Spline, Static};
use rugosa::{BodyQuery, BodyShape, PairState, QuerySettings, query_bodies};

/// Every pair the fresh query finds crossing or in contact clearly inside the band (`slack > 0`),
/// or in contact anywhere in the band (`slack = 0`).
fn pairs_in_contact(sim: &Simulation, bodies: &[Entity], slack: f64) -> Vec<(Entity, Entity)> {
    let world = sim.world();
    let settings = QuerySettings::default();
    let mut query = BodyQuery::default();
    let mut found = Vec::new();
    for (k, &a) in bodies.iter().enumerate() {
        for &b in &bodies[k + 1..] {
            if world.satisfies::<&Static>(a) && world.satisfies::<&Static>(b) {
                continue; // the box's walls touch, and static bodies never collide
            }
            let (sa, ra, ta, pa) = (
                world.get::<&Spline>(a).unwrap(),
                world.get::<&Rugosity>(a).unwrap(),
                world.get::<&AobbTree>(a).unwrap(),
                world.get::<&RigidState>(a).unwrap().pose(),
            );
            let (sb, rb, tb, pb) = (
                world.get::<&Spline>(b).unwrap(),
                world.get::<&Rugosity>(b).unwrap(),
                world.get::<&AobbTree>(b).unwrap(),
                world.get::<&RigidState>(b).unwrap().pose(),
            );
            let (shape_a, shape_b) = (BodyShape::new(&sa, &ra), BodyShape::new(&sb, &rb));
            let manifold = query_bodies(&shape_a, &ta, &pa, &shape_b, &tb, &pb, &settings, &mut query);
            let clearly_inside = manifold.contacts.iter().any(|contact| {
                let c = &contact.contact;
                let band = c.lambda_a + c.lambda_b;
                c.distance <= band * (1.0 - slack)
            });
            if manifold.state == PairState::Intersecting || clearly_inside {
                found.push((a.min(b), a.max(b)));
            }
        }
    }
    found
}

#[test]
fn carried_pairs_never_hide_a_contact() {
    let settings = SimulationSettings { threads: 1, sleep: SleepSettings::off(), ..SimulationSettings::default() };
    let slack = 2.0 * settings.coherence;
    let mut sim = Simulation::new(settings).unwrap();
    for body in pile::blob_pile(30, 6) {
        sim.add_body(body).unwrap();
    }
    let bodies: Vec<Entity> = sim.bodies().collect();
    let dt = sim.settings().time_step;
    let (mut checked, mut carried) = (0, 0);
    for step in 0..150 {
        sim.step(dt);
        carried += sim.take_profile().counters.carried_pairs;
        if step % 3 != 0 {
            continue;
        }
        for pair in pairs_in_contact(&sim, &bodies, slack) {
            checked += 1;
            assert!(
                sim.touching_pairs().contains(&pair),
                "step {step}: the pair {pair:?} is in contact at the final poses, and the engine did not report it"
            );
        }
        // And the converse: a contact the engine reports is never nearer than the true minimum.
        let in_band = pairs_in_contact(&sim, &bodies, 0.0);
        for pair in sim.touching_pairs() {
            assert!(
                in_band.contains(pair),
                "step {step}: the engine reports {pair:?} touching, a fresh query does not"
            );
        }
    }
    assert!(checked > 500, "only {checked} contacts were checked: the pile did not land");
    assert!(carried > 1000, "only {carried} pairs were carried: the carry was not exercised");
}
