//! Builds the generator shapes and prints their exact mass properties, then the rugosity
//! statistics of the pattern library (types 1–4) and of rugosity recovered from a noisy
//! detailed outline.
//!
//! Run: `cargo run --release --example shapes`

use glam::DVec2;
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use rugosa::{
    FrictionLaw, Generator, NoiseEstimator, Rugosity, RugosityPattern, ShapeError, ToleranceRule, mass_properties,
    rugosity_from_outline,
};

/// Density of every shape in this listing (kg/m²).
const DENSITY: f64 = 1000.0;
/// Segments of every generated curve.
const SEGMENTS: usize = 64;

fn main() -> Result<(), ShapeError> {
    print_mass_properties()?;
    print_patterns()?;
    print_outline_recovery()
}

fn print_mass_properties() -> Result<(), ShapeError> {
    let shapes = [
        ("circle", Generator::Circle { radius: 0.5 }),
        ("ellipse", Generator::Ellipse { a: 0.8, b: 0.4 }),
        ("rounded rectangle", Generator::RoundedRectangle { width: 1.2, height: 0.6, corner_radius: 0.1 }),
        ("superellipse", Generator::Superellipse { a: 0.5, b: 0.5, exponent: 4.0 }),
        ("gear", Generator::Gear { radius: 0.5, teeth: 10, depth: 0.12 }),
        ("blob", Generator::Blob { radius: 0.5, roughness: 0.6, seed: 42 }),
    ];
    println!("Mass properties at density {DENSITY} kg/m², {SEGMENTS} segments each (exact, Green's theorem):\n");
    println!(
        "{:<18} {:>11} {:>11} {:>11} {:>13} {:>10}",
        "shape", "area m²", "perimeter m", "mass kg", "inertia kg·m²", "|centroid|"
    );
    for (name, generator) in shapes {
        let spline = generator.build(SEGMENTS)?;
        let props = mass_properties(&spline, DENSITY);
        println!(
            "{:<18} {:>11.6} {:>11.6} {:>11.4} {:>13.6} {:>10.2e}",
            name,
            props.mass / DENSITY,
            spline.arc_length(),
            props.mass,
            props.inertia,
            props.centre_of_mass.length()
        );
    }
    Ok(())
}

fn print_patterns() -> Result<(), ShapeError> {
    let friction = FrictionLaw { lambda_min: 0.002, mu_max: 1.0 };
    let patterns = [
        RugosityPattern::Constant { value: 0.005 },
        RugosityPattern::Smooth { mean: 0.005, amplitude: 0.004, periods: 3, phase: 0.0 },
        RugosityPattern::Random { mean: 0.005, std_dev: 0.003, seed: 7 },
        RugosityPattern::Patches { rough: 0.009, smooth: 0.001, patches: 4, seed: 7 },
    ];
    println!("\nRugosity patterns on {SEGMENTS} segments; μ from λ with λ_min = 0.002 m, μ_max = 1:\n");
    println!(
        "{:<6} {:>9} {:>9} {:>9} {:>10} {:>7} {:>7}",
        "type", "min R", "mean R", "max R", "max λ(u)", "min μ", "max μ"
    );
    for pattern in &patterns {
        let rugosity = pattern.rugosity(SEGMENTS)?;
        let r = rugosity.tolerances();
        let (min, max) = r.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        let mu: Vec<f64> =
            (0..SEGMENTS * 8).map(|k| friction.coefficient(rugosity.tolerance_at(k as f64 / 8.0))).collect();
        let (mu_min, mu_max) = mu.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        println!(
            "{:<6} {:>9.5} {:>9.5} {:>9.5} {:>10.5} {:>7.3} {:>7.3}",
            pattern.type_number(),
            min,
            mean,
            max,
            rugosity.max_tolerance(),
            mu_min,
            mu_max
        );
    }
    Ok(())
}

fn print_outline_recovery() -> Result<(), ShapeError> {
    let sigma = 1e-3;
    let points = 1024;
    // The model's rugosity: the fine control points are displaced by N(0, σ²) noise. The dense
    // outline is that noisy fine curve sampled at its joints.
    let circle = Generator::Circle { radius: 1.0 }.build(points)?;
    let mut rng = StdRng::seed_from_u64(3);
    let noise = Normal::new(0.0, sigma).expect("σ > 0");
    let noisy: Vec<DVec2> = circle
        .control_points()
        .iter()
        .map(|&c| c + DVec2::new(noise.sample(&mut rng), noise.sample(&mut rng)))
        .collect();
    let fine = rugosa::Spline::from_control_points(noisy)?;
    let outline: Vec<DVec2> = (0..points).map(|k| fine.position(k as f64)).collect();
    println!(
        "\nRugosity from a detailed outline: unit circle, {points} control points with N(0, {sigma}²) noise, 4 levels:\n"
    );
    for (name, rule, expected) in [
        ("R = 3σ", ToleranceRule::ToleranceInterval { k: 3.0 }, 3.0 * sigma),
        ("universal", ToleranceRule::UniversalThreshold, sigma * (2.0 * (points as f64 / 2.0).ln()).sqrt()),
    ] {
        let (spline, rugosity): (_, Rugosity) =
            rugosity_from_outline(&outline, 4, rule, NoiseEstimator::MedianAbsolute)?;
        let r = rugosity.tolerances();
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        println!(
            "{name:<10} coarse segments {:>3}, mean R {mean:.5} m (from the true σ: {expected:.5} m)",
            spline.segment_count()
        );
    }
    Ok(())
}
