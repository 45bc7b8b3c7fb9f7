//! Every shape error variant is reached by bad input, with its message checked.

use glam::DVec2;
use rugosa::{
    BodyDesc, BodyLabel, Generator, Rugosity, ShapeError, Simulation, SimulationSettings, Spline, validate_boundary,
};

fn square() -> Vec<DVec2> {
    vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)]
}

#[test]
fn too_few_control_points() {
    let err = Spline::from_control_points(square()[..3].to_vec()).unwrap_err();
    assert_eq!(err, ShapeError::TooFewControlPoints { count: 3 });
    assert_eq!(err.to_string(), "a closed cubic B-spline needs at least 4 control points, got 3");
}

#[test]
fn non_finite_control_point() {
    let mut points = square();
    points[2].y = f64::NAN;
    let err = Spline::from_control_points(points).unwrap_err();
    assert!(matches!(err, ShapeError::NonFiniteControlPoint { index: 2, .. }));
    assert_eq!(err.to_string(), "control point 2 is not finite: (1, NaN)");
}

#[test]
fn degenerate_area() {
    let collinear = vec![DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(2.0, 0.0), DVec2::new(3.0, 0.0)];
    let err = Spline::from_control_points(collinear).unwrap_err();
    assert!(matches!(err, ShapeError::DegenerateArea { .. }));
    assert!(err.to_string().contains("near zero"), "{err}");
}

#[test]
fn negative_area_of_an_unchecked_clockwise_curve() {
    let mut points = square();
    points.reverse();
    let err = Spline::from_control_points_unchecked(points).validate().unwrap_err();
    assert!(matches!(err, ShapeError::NegativeArea { area } if area < 0.0));
    assert!(err.to_string().contains("control points run clockwise"), "{err}");
}

#[test]
fn invalid_rugosity() {
    let err = Rugosity::new(vec![0.1, -0.2, 0.0, 0.1]).unwrap_err();
    assert_eq!(err, ShapeError::InvalidRugosity { segment: 1, value: -0.2 });
    assert_eq!(err.to_string(), "rugosity of segment 1 is -0.2: it must be finite and >= 0");
    let err = Rugosity::new(vec![0.1, f64::INFINITY]).unwrap_err();
    assert!(matches!(err, ShapeError::InvalidRugosity { segment: 1, .. }));
}

#[test]
fn rugosity_length_mismatch() {
    let err = Rugosity::constant(5, 0.01).unwrap().validate(4).unwrap_err();
    assert_eq!(err, ShapeError::RugosityLength { expected: 4, got: 5 });
    assert_eq!(err.to_string(), "rugosity has 5 values but the curve has 4 segments");
}

#[test]
fn invalid_generator_parameter() {
    let err = Generator::Ellipse { a: 1.0, b: -2.0 }.build(16).unwrap_err();
    assert_eq!(err.to_string(), "ellipse.b: must be finite and > 0, got -2");
    let err = Generator::Gear { radius: 1.0, teeth: 0, depth: 0.1 }.build(16).unwrap_err();
    assert_eq!(err.to_string(), "gear.teeth: must be at least 1");
    let err = Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.4 }.build(16).unwrap_err();
    assert!(err.to_string().starts_with("rounded_rectangle.corner_radius: must lie in [0, half the smaller side"));
    let err = Generator::Circle { radius: 1.0 }.build(3).unwrap_err();
    assert_eq!(err, ShapeError::TooFewControlPoints { count: 3 });
}

#[test]
fn body_error_names_the_body() {
    let err = ShapeError::TooFewControlPoints { count: 2 }.for_body(BodyLabel::new(4, Some("wheel")));
    assert_eq!(err.to_string(), "body 4 ('wheel'): a closed cubic B-spline needs at least 4 control points, got 2");
    let err = ShapeError::TooFewControlPoints { count: 2 }.for_body(BodyLabel::new(0, None));
    assert!(err.to_string().starts_with("body 0: "));
}

#[test]
fn self_intersecting_boundary() {
    // A lopsided figure-eight control polygon (net area non-zero): the lobes cross at the origin.
    // Listed so that the net area is positive (clockwise input is refused before this check).
    let eight: Vec<DVec2> = (0..16)
        .rev()
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 16.0;
            DVec2::new(a.sin(), a.sin() * a.cos() * (1.0 + 0.6 * a.sin()))
        })
        .collect();
    let spline = Spline::from_control_points(eight).unwrap();
    let err = validate_boundary(&spline).unwrap_err();
    let ShapeError::SelfIntersecting { first, second } = err else { panic!("expected SelfIntersecting, got {err}") };
    assert_eq!(err.to_string(), format!("the boundary intersects itself: segments {first} and {second} cross"));
    // Spawning it names the body.
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let desc = BodyDesc::new(spline, Rugosity::constant(16, 0.01).unwrap()).named("eight");
    let err = sim.add_body(desc).unwrap_err();
    assert!(err.to_string().starts_with("body 0 ('eight'): the boundary intersects itself: segments"), "{err}");
}

#[test]
fn invalid_material_names_the_field() {
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let spline = Generator::Circle { radius: 1.0 }.build(8).unwrap();
    let mut desc = BodyDesc::new(spline, Rugosity::constant(8, 0.01).unwrap());
    desc.material.restitution = 1.5;
    let err = sim.add_body(desc).unwrap_err();
    assert_eq!(err.to_string(), "body 0: material.restitution: must lie in [0, 1] (1.5)");
}

#[test]
fn invalid_settings_name_the_field() {
    let err = Simulation::new(SimulationSettings { time_step: -1.0, ..SimulationSettings::default() }).err().unwrap();
    assert_eq!(err.to_string(), "setting `time_step` = -1: must lie in [0.000000001, 10]");
    let err =
        Simulation::new(SimulationSettings { min_band: f64::NAN, ..SimulationSettings::default() }).err().unwrap();
    assert_eq!(err.to_string(), "setting `min_band` = NaN: must be finite");
    let err = Simulation::new(SimulationSettings { gravity: glam::DVec2::new(0.0, -1e308), ..Default::default() });
    assert!(err.err().unwrap().to_string().contains("`gravity`"));
    // Every curve-pair solver setting is checked (a NaN tolerance disabled every contact).
    let mut settings = SimulationSettings::default();
    settings.curve_pair.intersection_tolerance = f64::NAN;
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `curve_pair.intersection_tolerance` = NaN: must be finite");
    let mut settings = SimulationSettings::default();
    settings.curve_pair.max_cells = 0;
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `curve_pair.max_cells` = 0: must lie in [1, 1048576]");
    let mut settings = SimulationSettings::default();
    settings.curve_pair.seed_depth = 20;
    assert!(Simulation::new(settings).err().unwrap().to_string().contains("curve_pair.seed_depth"));
    let mut settings = SimulationSettings::default();
    settings.solver.subspace_iterations = 1001;
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `solver.subspace_iterations` = 1001: must be at most 1000");
    let mut settings = SimulationSettings::default();
    settings.solver.position_tolerance = f64::NAN;
    assert!(Simulation::new(settings).err().unwrap().to_string().contains("solver.position_tolerance"));
    let mut settings = SimulationSettings::default();
    settings.solver.position_shortfall = 1.5;
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `solver.position_shortfall` = 1.5: must lie in [0, 1]");
    let settings = SimulationSettings { worker_spin: -1e-3, ..SimulationSettings::default() };
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `worker_spin` = -0.001: must lie in [0, 1]");
    let settings = SimulationSettings { worker_spin: f64::INFINITY, ..SimulationSettings::default() };
    assert!(Simulation::new(settings).err().unwrap().to_string().contains("worker_spin"));
    let settings = SimulationSettings { approach_depth: 1.0, ..SimulationSettings::default() };
    let err = Simulation::new(settings).err().unwrap();
    assert_eq!(err.to_string(), "setting `approach_depth` = 1: must lie in [0.05, 0.9]");
    for refused in [0.0, f64::NAN] {
        let settings = SimulationSettings { approach_depth: refused, ..SimulationSettings::default() };
        assert!(Simulation::new(settings).err().unwrap().to_string().contains("approach_depth"), "{refused}");
    }
    for accepted in [0.05, 0.9] {
        Simulation::new(SimulationSettings { approach_depth: accepted, ..SimulationSettings::default() }).unwrap();
    }
}

#[test]
fn a_density_that_would_overflow_the_mass_is_refused() {
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let spline = Generator::Circle { radius: 1.0 }.build(8).unwrap();
    let mut desc = BodyDesc::new(spline, Rugosity::constant(8, 0.01).unwrap());
    desc.material.density = f64::MAX;
    let err = sim.add_body(desc).unwrap_err();
    assert!(err.to_string().starts_with("body 0: material.density: must lie in"), "{err}");
}
