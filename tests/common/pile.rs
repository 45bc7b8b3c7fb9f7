//! The blob pile of `examples/performance_report.rs`, of the peer comparison
//! (`benches/peers`) and of `tests/allocation.rs`: one scene, built in one place (each
//! includes this file with `#[path]`).
#![allow(dead_code)] // each includer uses part of it

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity};

/// Distance between neighbouring blobs of the grid (m).
pub const BLOB_SPACING: f64 = 0.35;

/// A static box `columns` blobs wide (floor and two 40 m walls: rounded rectangles of 32
/// segments, band 2 mm) and `count` blobs (radius 0.1 m, 16 segments, band 2 mm, seeds
/// `0..count`, turned by 0.1 rad each) in a grid of `columns` columns `BLOB_SPACING` apart, every
/// other row shifted by 2 cm, the first row 0.3 m above the floor. Friction law λ_min = 1 mm,
/// μ_max = 0.6. The box comes first, then the blobs in seed order.
#[must_use]
pub fn blob_pile(count: usize, columns: usize) -> Vec<BodyDesc> {
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.6 }, ..Material::default() };
    let width = columns as f64 * BLOB_SPACING + 0.5;
    let wall = |size: DVec2, at: DVec2| {
        let spline =
            Generator::RoundedRectangle { width: size.x, height: size.y, corner_radius: 0.05 }.build(32).unwrap();
        BodyDesc::new(spline, Rugosity::constant(32, 0.002).unwrap()).with_material(material).at(at, 0.0).fixed()
    };
    let mut bodies = vec![
        wall(DVec2::new(width + 1.0, 0.4), DVec2::new(0.0, -0.2)),
        wall(DVec2::new(0.4, 40.0), DVec2::new(-0.5 * width - 0.2, 20.0)),
        wall(DVec2::new(0.4, 40.0), DVec2::new(0.5 * width + 0.2, 20.0)),
    ];
    bodies.extend((0..count).map(|k| {
        let (i, j) = (k % columns, k / columns);
        let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: k as u64 }.build(16).unwrap();
        let x = -0.5 * width + BLOB_SPACING + BLOB_SPACING * i as f64 + 0.02 * (j % 2) as f64;
        let at = DVec2::new(x, 0.3 + BLOB_SPACING * j as f64);
        BodyDesc::new(spline, Rugosity::constant(16, 0.002).unwrap()).with_material(material).at(at, 0.1 * k as f64)
    }));
    bodies
}

/// Columns of the square-ish grid of `count` blobs.
#[must_use]
pub fn square_columns(count: usize) -> usize {
    (count as f64).sqrt().ceil() as usize
}
