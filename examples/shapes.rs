//! Builds the generator shapes and prints their exact mass properties and rugosity statistics.
//!
//! Run: `cargo run --release --example shapes`

use rugosa::{Generator, Rugosity, ShapeError, mass_properties};

/// Density of every shape in this listing (kg/m²).
const DENSITY: f64 = 1000.0;

fn main() -> Result<(), ShapeError> {
    let shapes = [
        ("circle", Generator::Circle { radius: 0.5 }),
        ("ellipse", Generator::Ellipse { a: 0.8, b: 0.4 }),
        ("rounded rectangle", Generator::RoundedRectangle { width: 1.2, height: 0.6, corner_radius: 0.1 }),
        ("superellipse", Generator::Superellipse { a: 0.5, b: 0.5, exponent: 4.0 }),
        ("gear", Generator::Gear { radius: 0.5, teeth: 10, depth: 0.12 }),
        ("blob", Generator::Blob { radius: 0.5, roughness: 0.6, seed: 42 }),
    ];
    println!(
        "{:<18} {:>4} {:>11} {:>11} {:>11} {:>12} {:>12}  rugosity (min / mean / max)",
        "shape", "segs", "area m²", "perimeter m", "mass kg", "inertia kgm²", "centroid"
    );
    for (name, generator) in shapes {
        let spline = generator.build(64)?;
        let props = mass_properties(&spline, DENSITY);
        let rugosity = Rugosity::constant(spline.segment_count(), 0.005)?;
        let tolerances = rugosity.tolerances();
        let mean = tolerances.iter().sum::<f64>() / tolerances.len() as f64;
        let min = tolerances.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "{:<18} {:>4} {:>11.6} {:>11.6} {:>11.4} {:>12.6} {:>12.2e}  {:.4} / {:.4} / {:.4}",
            name,
            spline.segment_count(),
            props.mass / DENSITY,
            spline.arc_length(),
            props.mass,
            props.inertia,
            props.centre_of_mass.length(),
            min,
            mean,
            rugosity.max_tolerance()
        );
    }
    Ok(())
}
