//! Baseline benchmarks: curve evaluation, nearest point and mass properties.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use rugosa::{Generator, mass_properties};

fn curve_evaluation(c: &mut Criterion) {
    let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 1 }.build(64).unwrap();
    c.bench_function("spline_position_1000", |b| {
        b.iter(|| (0..1000).map(|k| spline.position(black_box(k as f64 * 0.064))).fold(DVec2::ZERO, |a, p| a + p))
    });
    c.bench_function("spline_nearest_point", |b| b.iter(|| spline.nearest_point(black_box(DVec2::new(1.7, 0.4)))));
}

fn mass(c: &mut Criterion) {
    for segments in [16usize, 64, 256] {
        let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 1 }.build(segments).unwrap();
        c.bench_function(&format!("mass_properties_{segments}"), |b| {
            b.iter(|| mass_properties(black_box(&spline), 1.0))
        });
    }
}

criterion_group!(benches, curve_evaluation, mass);
criterion_main!(benches);
