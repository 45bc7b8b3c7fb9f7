//! A body spawned wholly inside another (no curves meeting) is an overlap, not a separate
//! pair: it is pushed out, as Box2D and rapier push out overlapping shapes.

use rugosa::glam::DVec2;
use rugosa::{BodyDesc, Generator, QueryFilter, Rugosity, Simulation, SimulationSettings};

fn disc(radius: f64) -> BodyDesc {
    BodyDesc::new(Generator::Circle { radius }.build(16).unwrap(), Rugosity::constant(16, 0.0).unwrap())
}

fn slab() -> BodyDesc {
    let spline = Generator::RoundedRectangle { width: 2.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
    BodyDesc::new(spline, Rugosity::constant(24, 0.0).unwrap()).fixed()
}

#[test]
fn a_disc_spawned_inside_a_slab_is_pushed_out_through_the_nearest_side() {
    // The slab spans x ∈ [−1, 1], y ∈ [−0.5, 0.5]; the disc (r = 0.1) sits at (0.3, 0.1), 0.4
    // below the top and 0.7 from the right side: it must leave through the top and come to rest
    // on it, its centre about r above it. Both spawn orders (which body is A in the pair).
    for disc_first in [true, false] {
        let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
        let inner = disc(0.1).at(DVec2::new(0.3, 0.1), 0.0);
        let (ball, slab) = if disc_first {
            let ball = sim.add_body(inner).unwrap();
            (ball, sim.add_body(slab()).unwrap())
        } else {
            let slab = sim.add_body(slab()).unwrap();
            (sim.add_body(inner).unwrap(), slab)
        };
        for _ in 0..240 {
            sim.step(1.0 / 120.0);
        }
        let state = sim.state(ball).unwrap();
        assert!(state.is_finite());
        assert!(
            !sim.bodies_containing(state.position, &QueryFilter::default()).contains(&slab),
            "still inside: {state:?}"
        );
        // Resting on the top (the band of 1 mm each and the rest depth put it within 3 mm of r).
        assert!((state.position.y - 0.6).abs() < 3e-3, "disc first {disc_first}: {state:?}");
        assert!(state.linear_velocity.length() < 1e-2, "disc first {disc_first}: {state:?}");
    }
}
