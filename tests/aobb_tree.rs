//! AOBB tree: containment at every level, the separating-axis test against an exact reference, and
//! tree-against-tree traversal against brute force.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::f64::consts::TAU;

use glam::DVec2;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rugosa::Obb;
use rugosa::{AobbTree, TraversalWorkspace};
use rugosa::{Generator, Pose, Rugosity, Spline};

const FLOOR: f64 = 1e-3;

/// Pairs closer than this to touching may go either way (the SAT's rounding slack).
const AMBIGUOUS_GAP: f64 = 1e-9;

// ---------------------------------------------------------------------------------------------
// Allocation counting, per thread, so the zero-allocation test ignores other tests' threads.

struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|count| count.set(count.get() + 1));
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fn allocations_on_this_thread() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// ---------------------------------------------------------------------------------------------
// Shapes and rugosity profiles.

fn generators() -> Vec<Generator> {
    vec![
        Generator::Circle { radius: 1.0 },
        Generator::Ellipse { a: 1.5, b: 0.6 },
        Generator::RoundedRectangle { width: 2.0, height: 1.0, corner_radius: 0.2 },
        Generator::Superellipse { a: 1.0, b: 0.8, exponent: 4.0 },
        Generator::Gear { radius: 1.0, teeth: 7, depth: 0.15 },
        Generator::Blob { radius: 1.0, roughness: 0.5, seed: 7 },
    ]
}

/// Constant, sinusoidal (type 2) and seeded random (type 3) tolerances.
fn rugosity_profiles(segments: usize, seed: u64) -> Vec<Rugosity> {
    let mut rng = StdRng::seed_from_u64(seed);
    let sinusoidal = (0..segments).map(|i| 0.02 * (1.0 + 0.9 * (TAU * 3.0 * i as f64 / segments as f64).sin()));
    let random = (0..segments).map(|_| rng.random_range(0.0..0.05));
    vec![
        Rugosity::constant(segments, 0.02).unwrap(),
        Rugosity::new(sinusoidal.collect()).unwrap(),
        Rugosity::new(random.collect()).unwrap(),
    ]
}

struct Body {
    spline: Spline,
    rugosity: Rugosity,
    tree: AobbTree,
}

/// `segments` for most generators; 20 more for a rounded rectangle, which needs 6 control points
/// per corner (24), so 4 becomes 24 and odd counts stay odd.
fn resolution(generator: &Generator, segments: usize) -> usize {
    match generator {
        Generator::RoundedRectangle { .. } => segments + 20,
        _ => segments,
    }
}

fn body(generator: &Generator, segments: usize, profile: usize, seed: u64) -> Body {
    let segments = resolution(generator, segments);
    let spline = generator.build(segments).unwrap();
    let rugosity = rugosity_profiles(segments, seed).swap_remove(profile);
    let tree = AobbTree::build(&spline, &rugosity, FLOOR);
    Body { spline, rugosity, tree }
}

/// A pool of bodies of every shape, mixed segment counts (odd ones included) and profiles.
fn body_pool() -> Vec<Body> {
    let counts = [4, 5, 7, 16, 33, 64];
    generators()
        .iter()
        .enumerate()
        .flat_map(|(g, generator)| {
            counts
                .iter()
                .enumerate()
                .map(move |(c, &segments)| body(generator, segments, (g + c) % 3, (g * 7 + c) as u64))
        })
        .collect()
}

/// A random pose for the second body: near the first (centre distance 0.3..2.8 for unit-size shapes).
fn nearby_pose(rng: &mut StdRng) -> Pose {
    let direction = DVec2::from_angle(rng.random_range(0.0..TAU));
    Pose::new(direction * rng.random_range(0.3..2.8), rng.random_range(0.0..TAU))
}

/// A random pose and one near it ([`nearby_pose`] in the first one's frame).
fn nearby_poses(rng: &mut StdRng) -> (Pose, Pose) {
    let pose_a = random_pose(rng);
    let relative = nearby_pose(rng);
    (pose_a, Pose::new(pose_a.transform_point(relative.position), pose_a.angle() + relative.angle()))
}

fn random_pose(rng: &mut StdRng) -> Pose {
    let position = DVec2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
    Pose::new(position, rng.random_range(0.0..TAU))
}

// ---------------------------------------------------------------------------------------------
// 1. Containment at every level.

#[test]
fn every_shape_at_every_resolution_validates() {
    for generator in generators() {
        for segments in [4, 5, 7, 16, 64, 256, 1024].map(|n| resolution(&generator, n)) {
            let spline = generator.build(segments).unwrap();
            for (profile, rugosity) in rugosity_profiles(segments, segments as u64).iter().enumerate() {
                let tree = AobbTree::build(&spline, rugosity, FLOOR);
                let context = format!("{generator:?} with {segments} segments, rugosity profile {profile}");
                tree.validate(&spline, rugosity, FLOOR).unwrap_or_else(|e| panic!("{context}: {e}"));
                assert_eq!(tree.leaf_count(), segments, "{context}");
                assert_eq!(tree.nodes().len(), 2 * segments - 1, "{context}");
                assert_leaves_are_tight(&spline, rugosity, &tree, &context);
            }
        }
    }
}

/// Containment alone is met by huge boxes: a leaf's half-extents are at most the half-diagonal
/// of the segment's axis-aligned bounds (the segment's diameter bounds any projection) plus its band.
fn assert_leaves_are_tight(spline: &Spline, rugosity: &Rugosity, tree: &AobbTree, context: &str) {
    for (i, segment) in spline.segments().enumerate() {
        let (low, high) = segment.bounds();
        let bound = 0.5 * (high - low).length() + rugosity.max_on_segment(i).max(FLOOR) + 1e-12;
        let leaf = tree.leaf_box(i);
        assert!(leaf.half_extents.max_element() <= bound, "{context}: leaf {i} {leaf:?} looser than {bound}");
    }
}

#[test]
fn root_box_is_close_to_the_shape() {
    // A 1.5 × 0.6 ellipse with a 0.02 band: the root is aligned with the major axis. It holds the
    // band, and its children's corners rather than the curve, so it is looser than the curve's
    // bounds (1.73 × 0.95 measured: the quarter boxes are tilted), but not by more than 60%.
    let spline = Generator::Ellipse { a: 1.5, b: 0.6 }.build(64).unwrap();
    let rugosity = Rugosity::constant(64, 0.02).unwrap();
    let root = AobbTree::build(&spline, &rugosity, FLOOR).root().obb;
    assert!(root.axis.y.abs() < 1e-6, "root axis {}", root.axis);
    let band_bounds = DVec2::new(1.52, 0.62);
    assert!(root.half_extents.cmpge(band_bounds - 1e-9).all(), "{root:?}");
    assert!(root.half_extents.cmple(1.6 * band_bounds).all(), "{root:?}");
}

// ---------------------------------------------------------------------------------------------
// 2. The separating-axis test against an exact polygon reference.

fn random_obb(rng: &mut StdRng) -> Obb {
    let centre = DVec2::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
    let half_extents = DVec2::new(rng.random_range(0.0..1.5), rng.random_range(0.0..1.5));
    Obb::new(centre, DVec2::from_angle(rng.random_range(0.0..TAU)), half_extents)
}

fn segments_cross(p0: DVec2, p1: DVec2, q0: DVec2, q1: DVec2) -> bool {
    let side = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let (d1, d2) = (side(q0, q1, p0), side(q0, q1, p1));
    let (d3, d4) = (side(p0, p1, q0), side(p0, p1, q1));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

fn inside_convex(polygon: &[DVec2; 4], point: DVec2) -> bool {
    (0..4).all(|k| (polygon[(k + 1) % 4] - polygon[k]).perp_dot(point - polygon[k]) >= 0.0)
}

fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let t = ((p - a).dot(b - a) / (b - a).length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance(a + t * (b - a))
}

/// `None` when the boxes (as convex quadrilaterals) intersect, else their exact distance.
fn reference_distance(a: &Obb, b: &Obb) -> Option<f64> {
    let (pa, pb) = (a.corners(), b.corners());
    let edges = |p: [DVec2; 4]| (0..4).map(move |k| (p[k], p[(k + 1) % 4]));
    let crossing = edges(pa).any(|(a0, a1)| edges(pb).any(|(b0, b1)| segments_cross(a0, a1, b0, b1)));
    if crossing || inside_convex(&pb, pa[0]) || inside_convex(&pa, pb[0]) {
        return None;
    }
    let vertex_edge = |points: [DVec2; 4], polygon: [DVec2; 4]| {
        points.into_iter().flat_map(move |p| edges(polygon).map(move |(e0, e1)| point_segment_distance(p, e0, e1)))
    };
    Some(vertex_edge(pa, pb).chain(vertex_edge(pb, pa)).fold(f64::INFINITY, f64::min))
}

/// Moves `b` so that its separation from `a` becomes about `gap` (may be negative).
fn nudged_to_gap(a: &Obb, b: &Obb, gap: f64) -> Obb {
    let direction = (b.centre - a.centre).try_normalize().unwrap_or(DVec2::X);
    let mut moved = *b;
    for _ in 0..40 {
        let error = moved.separation(a) - gap;
        if error.abs() < 1e-15 {
            break;
        }
        moved.centre -= 0.5 * error * direction;
    }
    moved
}

#[test]
fn separating_axis_test_matches_the_exact_reference() {
    let mut rng = StdRng::seed_from_u64(0x0bb);
    let (mut disjoint, mut overlapping) = (0, 0);
    for case in 0..30_000 {
        let a = random_obb(&mut rng);
        let mut b = random_obb(&mut rng);
        if case % 3 == 0 {
            b = nudged_to_gap(&a, &b, rng.random_range(-1e-3..1e-3));
        }
        match reference_distance(&a, &b) {
            None => {
                assert!(a.overlaps(&b) && b.overlaps(&a), "case {case}: {a:?} {b:?} intersect");
                assert!(a.separation(&b) <= 1e-12, "case {case}: separation {}", a.separation(&b));
                overlapping += 1;
            }
            Some(distance) if distance > AMBIGUOUS_GAP => {
                assert!(!a.overlaps(&b) && !b.overlaps(&a), "case {case}: {a:?} {b:?} are {distance} apart");
                let separation = a.separation(&b);
                assert!(separation > 0.0 && separation <= distance + 1e-12, "case {case}: {separation} vs {distance}");
                disjoint += 1;
            }
            Some(_) => {}
        }
    }
    assert!(disjoint > 5_000 && overlapping > 5_000, "{disjoint} disjoint, {overlapping} overlapping cases");
}

#[test]
fn transformed_box_moves_its_corners() {
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..100 {
        let obb = random_obb(&mut rng);
        let pose = random_pose(&mut rng);
        let moved = obb.transformed(&pose);
        for (c, m) in obb.corners().into_iter().zip(moved.corners()) {
            assert!((pose.transform_point(c) - m).length() < 1e-12);
            assert!(moved.contains_point(m, 1e-12) && !moved.contains_point(m + 1e-6 * (m - moved.centre), 0.0));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Traversal against brute force.

/// Leaf pairs `(segment of a, segment of b)`.
type LeafPairs = Vec<(u32, u32)>;

/// All leaf pairs whose elementary boxes overlap in the world: `(sure, ambiguous)`, where ambiguous
/// pairs are within [`AMBIGUOUS_GAP`] of touching and may be reported or not.
fn brute_force_pairs(a: &Body, pose_a: &Pose, b: &Body, pose_b: &Pose) -> (LeafPairs, LeafPairs) {
    let world = |body: &Body, pose: &Pose| -> Vec<Obb> {
        (0..body.tree.leaf_count()).map(|i| body.tree.leaf_box(i).transformed(pose)).collect()
    };
    let (boxes_a, boxes_b) = (world(a, pose_a), world(b, pose_b));
    let (mut sure, mut ambiguous) = (Vec::new(), Vec::new());
    for (i, box_a) in boxes_a.iter().enumerate() {
        for (j, box_b) in boxes_b.iter().enumerate() {
            let separation = box_a.separation(box_b);
            if separation.abs() <= AMBIGUOUS_GAP {
                ambiguous.push((i as u32, j as u32));
            } else if separation < 0.0 {
                sure.push((i as u32, j as u32));
            }
        }
    }
    (sure, ambiguous)
}

#[test]
fn traversal_finds_exactly_the_overlapping_leaf_boxes() {
    let pool = body_pool();
    let mut rng = StdRng::seed_from_u64(2024);
    let mut workspace = TraversalWorkspace::new();
    let (mut out, mut swapped) = (Vec::new(), Vec::new());
    let mut cases_with_pairs = 0;
    for case in 0..3_000 {
        let (a, b) = (&pool[rng.random_range(0..pool.len())], &pool[rng.random_range(0..pool.len())]);
        let (pose_a, pose_b) = nearby_poses(&mut rng);
        let counters = a.tree.overlapping_leaves(&pose_a, &b.tree, &pose_b, &mut workspace, &mut out);
        let (sure, ambiguous) = brute_force_pairs(a, &pose_a, b, &pose_b);
        let found: Vec<_> = out.iter().filter(|p| !ambiguous.contains(p)).copied().collect();
        assert_eq!(found, sure, "case {case}: traversal differs from brute force");
        assert_eq!(counters.leaf_pairs, out.len());
        assert!(counters.box_tests <= a.tree.nodes().len() * b.tree.nodes().len());
        b.tree.overlapping_leaves(&pose_b, &a.tree, &pose_a, &mut workspace, &mut swapped);
        let mut transposed: Vec<_> = swapped.iter().map(|&(j, i)| (i, j)).filter(|p| !ambiguous.contains(p)).collect();
        transposed.sort_unstable();
        assert_eq!(transposed, found, "case {case}: querying from the other body differs");
        cases_with_pairs += usize::from(!sure.is_empty());
    }
    assert!(cases_with_pairs > 1_000, "only {cases_with_pairs} cases had overlapping leaves");
}

/// With a margin, the descent lists exactly the leaf pairs whose leaf test passes at that margin
/// (the leaf test over every pair, `leaf_pairs_within`): what a narrow phase's kept front,
/// filtered by the leaf test, relies on to list the same pairs as a new descent (docs/model.md
/// §3a). A branch's box fattened along its own axes need not hold its children's boxes fattened
/// along theirs, so the branches are tested with room for that.
#[test]
fn a_descent_within_a_margin_lists_exactly_the_pairs_the_leaf_test_passes() {
    let pool = body_pool();
    let mut rng = StdRng::seed_from_u64(77);
    let mut workspace = TraversalWorkspace::new();
    let (mut descended, mut every, mut tested) = (Vec::new(), Vec::new(), Vec::new());
    let mut listed = 0;
    for case in 0..3_000 {
        let (a, b) = (&pool[rng.random_range(0..pool.len())], &pool[rng.random_range(0..pool.len())]);
        let (pose_a, pose_b) = nearby_poses(&mut rng);
        let margin = [0.0, 1e-3, 0.02, 0.1, 0.4][case % 5];
        a.tree.overlapping_leaves_within(&pose_a, &b.tree, &pose_b, margin, &mut workspace, &mut descended);
        rugosa::all_segment_pairs(a.tree.leaf_count(), b.tree.leaf_count(), &mut every);
        a.tree.leaf_pairs_within(&pose_a, &b.tree, &pose_b, margin, &every, &mut tested);
        assert_eq!(descended, tested, "case {case}, margin {margin}: the descent's pairs are not the leaf test's");
        listed += descended.len();
    }
    assert!(listed > 10_000, "only {listed} leaf pairs listed");
}

/// Samples of a segment's band: positions and λ there.
fn band_samples(body: &Body, segment: usize, pose: &Pose) -> Vec<(DVec2, f64)> {
    const SAMPLES: usize = 12;
    let curve = body.spline.segment(segment);
    let band = body.rugosity.segment_tolerance(segment, FLOOR);
    (0..=SAMPLES)
        .map(|k| {
            let t = k as f64 / SAMPLES as f64;
            (pose.transform_point(curve.position(t)), band.at(t))
        })
        .collect()
}

/// A disc holding a segment's band samples (for pruning the brute-force contact search only).
fn enclosing_disc(samples: &[(DVec2, f64)]) -> (DVec2, f64) {
    let centre = samples.iter().map(|s| s.0).sum::<DVec2>() / samples.len() as f64;
    (centre, samples.iter().map(|&(p, lambda)| p.distance(centre) + lambda).fold(0.0, f64::max))
}

fn bands_touch(a: &[(DVec2, f64)], b: &[(DVec2, f64)]) -> bool {
    a.iter().any(|&(p, la)| b.iter().any(|&(q, lb)| p.distance(q) <= la + lb))
}

#[test]
fn traversal_never_misses_touching_bands() {
    let pool = body_pool();
    let mut rng = StdRng::seed_from_u64(77);
    let mut workspace = TraversalWorkspace::new();
    let mut out = Vec::new();
    let mut touching_pairs = 0;
    for case in 0..600 {
        let (a, b) = (&pool[rng.random_range(0..pool.len())], &pool[rng.random_range(0..pool.len())]);
        let (pose_a, pose_b) = nearby_poses(&mut rng);
        a.tree.overlapping_leaves(&pose_a, &b.tree, &pose_b, &mut workspace, &mut out);
        let samples_a: Vec<_> = (0..a.tree.leaf_count()).map(|i| band_samples(a, i, &pose_a)).collect();
        let samples_b: Vec<_> = (0..b.tree.leaf_count()).map(|j| band_samples(b, j, &pose_b)).collect();
        let discs_b: Vec<_> = samples_b.iter().map(|s| enclosing_disc(s)).collect();
        for (i, sa) in samples_a.iter().enumerate() {
            let (centre_a, radius_a) = enclosing_disc(sa);
            for (j, sb) in samples_b.iter().enumerate() {
                let (centre_b, radius_b) = discs_b[j];
                if centre_a.distance(centre_b) > radius_a + radius_b || !bands_touch(sa, sb) {
                    continue;
                }
                assert!(out.binary_search(&(i as u32, j as u32)).is_ok(), "case {case}: bands of ({i}, {j}) touch");
                touching_pairs += 1;
            }
        }
    }
    assert!(touching_pairs > 1_000, "only {touching_pairs} touching pairs were checked");
}

#[test]
fn output_is_sorted_and_deterministic() {
    let a = body(&Generator::Gear { radius: 1.0, teeth: 9, depth: 0.2 }, 256, 2, 1);
    let b = body(&Generator::Blob { radius: 1.0, roughness: 0.5, seed: 4 }, 129, 1, 2);
    let mut rng = StdRng::seed_from_u64(9);
    for _ in 0..50 {
        let (pose_a, pose_b) = nearby_poses(&mut rng);
        let mut fresh = Vec::new();
        let first = a.tree.overlapping_leaves(&pose_a, &b.tree, &pose_b, &mut TraversalWorkspace::new(), &mut fresh);
        // A used workspace and a dirty output vector give the same answer.
        let mut workspace = TraversalWorkspace::new();
        let mut reused = vec![(7, 7); 3];
        a.tree.overlapping_leaves(&pose_b, &b.tree, &pose_a, &mut workspace, &mut reused);
        let second = a.tree.overlapping_leaves(&pose_a, &b.tree, &pose_b, &mut workspace, &mut reused);
        assert_eq!(fresh, reused);
        assert_eq!(first, second);
        assert!(fresh.windows(2).all(|w| w[0] < w[1]), "pairs are strictly increasing");
    }
}

#[test]
fn far_apart_bodies_cost_one_box_test() {
    // The root of a unit circle is a square of half-side 1.36 (it encloses its tilted children), so
    // two roots 4 apart, one turned by 0.3 rad, are disjoint: 1.36 + 1.36 (cos 0.3 + sin 0.3) < 4.
    let a = body(&Generator::Circle { radius: 1.0 }, 64, 0, 0);
    let mut out = Vec::new();
    let counters = a.tree.overlapping_leaves(
        &Pose::IDENTITY,
        &a.tree,
        &Pose::new(DVec2::new(4.0, 0.0), 0.3),
        &mut TraversalWorkspace::new(),
        &mut out,
    );
    assert_eq!((counters.box_tests, counters.leaf_pairs), (1, 0));
    assert!(out.is_empty());
}

#[test]
fn steady_state_traversal_allocates_nothing() {
    let a = body(&Generator::Blob { radius: 1.0, roughness: 0.5, seed: 1 }, 256, 0, 0);
    let b = body(&Generator::Blob { radius: 1.0, roughness: 0.5, seed: 2 }, 256, 2, 0);
    let poses: Vec<Pose> = (0..20).map(|k| Pose::new(DVec2::new(1.6, 0.1 * k as f64), 0.2 * k as f64)).collect();
    let mut workspace = TraversalWorkspace::new();
    let mut out = Vec::new();
    let run = |workspace: &mut TraversalWorkspace, out: &mut Vec<(u32, u32)>| -> usize {
        poses.iter().map(|p| a.tree.overlapping_leaves(&Pose::IDENTITY, &b.tree, p, workspace, out).leaf_pairs).sum()
    };
    let warm_up: usize = run(&mut workspace, &mut out);
    let before = allocations_on_this_thread();
    let steady: usize = run(&mut workspace, &mut out);
    assert_eq!(allocations_on_this_thread(), before, "a warmed-up traversal allocated");
    assert_eq!(steady, warm_up);
    assert!(steady > 0, "the poses should produce contacts");
}
