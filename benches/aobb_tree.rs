//! AOBB tree: build time, and traversal time, box tests and leaf pairs against segment count for a
//! near miss and for a touching pair of blobs.
//!
//! Both blobs have radius ≈ 1 and a constant 0.01 tolerance band. For each segment count the second
//! blob is slid along x until the gap between the two *bands* (sampled) is 0.02 (near miss) or
//! −0.005 (touching: the bands overlap by 0.005), so the geometry is the same at every resolution.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::DVec2;
use rugosa::{AobbTree, TraversalCounters, TraversalWorkspace};
use rugosa::{Generator, Pose, Rugosity, Spline};

const SEGMENT_COUNTS: [usize; 4] = [16, 64, 256, 1024];
const BAND: f64 = 0.01;
const FLOOR: f64 = 1e-3;
const NEAR_MISS_GAP: f64 = 0.02;
const TOUCHING_GAP: f64 = -0.005;
/// Samples per curve for the gap search (spacing ≈ 0.006, distance error ≈ 1e-5).
const GAP_SAMPLES: usize = 1024;

struct Scene {
    tree_a: AobbTree,
    tree_b: AobbTree,
    pose_b: Pose,
}

fn blob(seed: u64, segments: usize) -> (Spline, AobbTree) {
    let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed }.build(segments).unwrap();
    let tree = AobbTree::build(&spline, &Rugosity::constant(segments, BAND).unwrap(), FLOOR);
    (spline, tree)
}

fn samples(spline: &Spline, pose: &Pose) -> Vec<DVec2> {
    let n = spline.segment_count() as f64;
    (0..GAP_SAMPLES).map(|k| pose.transform_point(spline.position(n * k as f64 / GAP_SAMPLES as f64))).collect()
}

/// Sampled distance between the two curves.
fn curve_distance(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter().flat_map(|p| b.iter().map(move |q| p.distance_squared(*q))).fold(f64::INFINITY, f64::min).sqrt()
}

/// The pose of B, turned by 0.7 rad and slid along x at height 0.1, whose band gap to A is `gap`.
fn pose_at_band_gap(a: &Spline, b: &Spline, gap: f64) -> Pose {
    let points_a = samples(a, &Pose::IDENTITY);
    let pose = |x: f64| Pose::new(DVec2::new(x, 0.1), 0.7);
    let band_gap = |x: f64| curve_distance(&points_a, &samples(b, &pose(x))) - 2.0 * BAND;
    let (mut near, mut far) = (0.0, 4.0);
    for _ in 0..50 {
        let middle = 0.5 * (near + far);
        if band_gap(middle) < gap { near = middle } else { far = middle }
    }
    pose(far)
}

fn scene(segments: usize, gap: f64) -> Scene {
    let (spline_a, tree_a) = blob(1, segments);
    let (spline_b, tree_b) = blob(2, segments);
    Scene { tree_a, tree_b, pose_b: pose_at_band_gap(&spline_a, &spline_b, gap) }
}

fn traverse(scene: &Scene, workspace: &mut TraversalWorkspace, out: &mut Vec<(u32, u32)>) -> TraversalCounters {
    scene.tree_a.overlapping_leaves(&Pose::IDENTITY, &scene.tree_b, &scene.pose_b, workspace, out)
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("aobb_build");
    for segments in SEGMENT_COUNTS {
        let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 1 }.build(segments).unwrap();
        let rugosity = Rugosity::constant(segments, BAND).unwrap();
        group.bench_with_input(BenchmarkId::from_parameter(segments), &segments, |bench, _| {
            bench.iter(|| AobbTree::build(black_box(&spline), &rugosity, FLOOR))
        });
    }
    group.finish();
}

fn traversal(c: &mut Criterion) {
    for (name, gap) in [("near_miss", NEAR_MISS_GAP), ("touching", TOUCHING_GAP)] {
        let mut group = c.benchmark_group(format!("aobb_traverse_{name}"));
        for segments in SEGMENT_COUNTS {
            let scene = scene(segments, gap);
            let mut workspace = TraversalWorkspace::new();
            let mut out = Vec::new();
            let counters = traverse(&scene, &mut workspace, &mut out);
            println!(
                "{name:>9} segments {segments:>5}: box tests {:>6}, leaf pairs {:>4}, depth {}, B at {}",
                counters.box_tests,
                counters.leaf_pairs,
                scene.tree_a.depth(),
                scene.pose_b.position
            );
            group.bench_with_input(BenchmarkId::from_parameter(segments), &segments, |bench, _| {
                bench.iter(|| traverse(black_box(&scene), &mut workspace, &mut out))
            });
        }
        group.finish();
    }
}

fn short() -> Criterion {
    Criterion::default()
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20)
}

criterion_group! {
    name = benches;
    config = short();
    targets = build, traversal
}
criterion_main!(benches);
