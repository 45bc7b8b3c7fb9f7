//! Collision filtering (rapier's interaction groups, Box2D's filter and pair exclusion): pairs
//! that do not interact are never tested and pass through each other; all others collide.

mod common;

use common::{box_spline, ground, material, simulation};
use glam::DVec2;
use hecs::Entity;
use rugosa::{BodyActionError, BodyDesc, CollisionGroups, FrictionLaw, Rugosity, Simulation};

const DT: f64 = 1.0 / 120.0;
const BAND: f64 = 0.002;
const FLOOR: u32 = 1;
const CRATES: u32 = 2;
const GHOSTS: u32 = 4;

fn rough() -> FrictionLaw {
    FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }
}

fn world() -> (Simulation, Entity) {
    let mut sim = simulation(DVec2::new(0.0, -9.81));
    let floor = ground(BAND, material(0.0, rough())).with_groups(CollisionGroups::new(FLOOR, u32::MAX));
    let floor = sim.add_body(floor).unwrap();
    (sim, floor)
}

fn crate_at(sim: &mut Simulation, y: f64, groups: CollisionGroups) -> Entity {
    let spline = box_spline(0.4, 0.2, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    let desc = BodyDesc::new(spline, rugosity).with_material(material(0.0, rough())).with_groups(groups);
    sim.add_body(desc.at(DVec2::new(0.0, y), 0.0)).unwrap()
}

fn run(sim: &mut Simulation, steps: usize) {
    for _ in 0..steps {
        sim.step(DT);
    }
}

fn y(sim: &Simulation, body: Entity) -> f64 {
    sim.state(body).unwrap().position.y
}

#[test]
fn groups_decide_which_pairs_collide() {
    let (mut sim, _) = world();
    // A crate on the floor, a crate dropped onto it, and a ghost (collides with the floor only)
    // dropped onto it too.
    let crates = CollisionGroups::new(CRATES, FLOOR | CRATES);
    let below = crate_at(&mut sim, 0.1 + BAND, crates);
    let above = crate_at(&mut sim, 0.5, crates);
    let ghost = crate_at(&mut sim, 0.9, CollisionGroups::new(GHOSTS, FLOOR));
    run(&mut sim, 120);
    // Mechanics: the crates stack; the ghost falls through both and rests on the floor.
    assert!((y(&sim, below) - (0.1 + BAND)).abs() < BAND, "crate below at {}", y(&sim, below));
    assert!((y(&sim, above) - (0.3 + 2.0 * BAND)).abs() < 2.0 * BAND, "crate above at {}", y(&sim, above));
    assert!((y(&sim, ghost) - (0.1 + BAND)).abs() < 2.0 * BAND, "ghost at {}", y(&sim, ghost));
    // And it overlaps the crate below without either being pushed.
    assert!(sim.state(ghost).unwrap().position.distance(sim.state(below).unwrap().position) < 0.01);
}

#[test]
fn a_body_filtering_out_the_floor_falls_through_it() {
    let (mut sim, _) = world();
    let body = crate_at(&mut sim, 0.5, CollisionGroups::new(CRATES, CRATES));
    run(&mut sim, 120);
    // Free fall for 1 s: y = 0.5 − g/2.
    assert!((y(&sim, body) - (0.5 - 0.5 * 9.81)).abs() < 1e-9, "at {}", y(&sim, body));
}

#[test]
fn an_excluded_pair_passes_through_and_an_included_one_collides_again() {
    let (mut sim, floor) = world();
    let body = crate_at(&mut sim, 0.5, CollisionGroups::ALL);
    sim.exclude_pair(body, floor).unwrap();
    sim.exclude_pair(floor, body).unwrap(); // the same pair, either order: no duplicate
    run(&mut sim, 60);
    assert!(y(&sim, body) < -0.5, "an excluded pair collided: at {}", y(&sim, body));
    let (mut sim, floor) = world();
    let body = crate_at(&mut sim, 0.5, CollisionGroups::ALL);
    sim.exclude_pair(body, floor).unwrap();
    sim.include_pair(body, floor).unwrap();
    run(&mut sim, 120);
    assert!(
        (y(&sim, body) - (0.1 + BAND)).abs() < 2.0 * BAND,
        "an included pair did not collide: at {}",
        y(&sim, body)
    );
}

#[test]
fn exclusions_refuse_what_is_not_a_pair_of_bodies() {
    let (mut sim, floor) = world();
    let body = crate_at(&mut sim, 0.5, CollisionGroups::ALL);
    let err = sim.exclude_pair(body, body).unwrap_err();
    assert!(matches!(err, BodyActionError::Argument { .. }), "{err}");
    let (mut other, _) = world();
    let foreign = crate_at(&mut other, 0.5, CollisionGroups::ALL);
    assert!(matches!(sim.exclude_pair(floor, foreign), Err(BodyActionError::NotABody { .. })));
    assert!(sim.remove_body(body));
    assert!(matches!(sim.include_pair(floor, body), Err(BodyActionError::NotABody { .. })));
}
