//! Scene helpers shared by the integration tests.
#![allow(dead_code)]

use glam::DVec2;
use rugosa::{
    BodyDesc, FrictionLaw, Generator, Material, Rugosity, Simulation, SimulationSettings, SleepSettings, Spline,
};

/// Control points along the boundary of a `width × height` rectangle centred at the origin,
/// spaced at most `spacing` apart, CCW. Four consecutive collinear points make an exactly
/// straight B-spline piece, so the long sides are exactly flat away from the corners.
pub fn box_control_points(width: f64, height: f64, spacing: f64) -> Vec<DVec2> {
    let (hw, hh) = (0.5 * width, 0.5 * height);
    polygon_control_points(
        &[DVec2::new(-hw, -hh), DVec2::new(hw, -hh), DVec2::new(hw, hh), DVec2::new(-hw, hh)],
        spacing,
    )
}

/// Control points along the edges of a closed polygon (`corners` in order), spaced at most
/// `spacing` apart with at least 3 pieces per edge.
pub fn polygon_control_points(corners: &[DVec2], spacing: f64) -> Vec<DVec2> {
    let mut points = Vec::new();
    for (k, &from) in corners.iter().enumerate() {
        let to = corners[(k + 1) % corners.len()];
        let pieces = ((to - from).length() / spacing).ceil().max(3.0) as usize;
        for i in 0..pieces {
            points.push(from.lerp(to, i as f64 / pieces as f64));
        }
    }
    points
}

/// A box-shaped spline (see [`box_control_points`]).
pub fn box_spline(width: f64, height: f64, spacing: f64) -> Spline {
    Spline::from_control_points(box_control_points(width, height, spacing)).unwrap()
}

/// A material with the given restitution and a friction law; `e_max = e`.
pub fn material(restitution: f64, friction: FrictionLaw) -> Material {
    Material { density: 1000.0, restitution, restitution_max: restitution, friction }
}

/// A friction law that is zero for any tolerance below 1 m: frictionless for our bands.
pub fn frictionless() -> FrictionLaw {
    FrictionLaw { lambda_min: 1.0, mu_max: 0.0 }
}

/// A static flat ground 40 m wide whose top surface is the line `y = 0` for `|x| < 19`.
pub fn ground(rugosity: f64, material: Material) -> BodyDesc {
    scaled_ground(1.0, rugosity, material)
}

/// [`ground`] scaled by `scale`: `40 scale` wide, top surface `y = 0` for `|x| < 19 scale`.
pub fn scaled_ground(scale: f64, rugosity: f64, material: Material) -> BodyDesc {
    let spline = box_spline(40.0 * scale, 2.0 * scale, 0.5 * scale);
    let rugosity = Rugosity::constant(spline.segment_count(), rugosity).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material).at(DVec2::new(0.0, -scale), 0.0).fixed().named("ground")
}

/// A spline disc of `radius` with `segments` segments and constant rugosity.
pub fn disc(radius: f64, segments: usize, rugosity: f64, material: Material) -> BodyDesc {
    let spline = Generator::Circle { radius }.build(segments).unwrap();
    let rugosity = Rugosity::constant(segments, rugosity).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material)
}

/// A simulation with the given gravity and single-threaded pool.
pub fn simulation(gravity: DVec2) -> Simulation {
    // Sleeping off: these tests judge the contact solver, which sleeping would stop testing
    // once a body has been still for half a second (tests/sleep.rs tests sleeping).
    let settings =
        SimulationSettings { gravity, threads: 1, sleep: SleepSettings::off(), ..SimulationSettings::default() };
    Simulation::new(settings).unwrap()
}
