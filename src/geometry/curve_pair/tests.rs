//! Unit tests of the leaf solver: the apart-pair shortcut, the separating axes, and crossings,
//! nearest points and conformal ends of straight lines.

use super::*;

fn line(from: DVec2, to: DVec2) -> CubicSegment {
    CubicSegment { bezier: [from, from.lerp(to, 1.0 / 3.0), from.lerp(to, 2.0 / 3.0), to] }
}

/// Curved pieces just beyond the combined band (the pairs a landing pile searches most): a
/// search whose cells prove them apart returns its best point unpolished. Each answer is
/// separate, its lower bound beyond the band and below the exact distance, and its point a
/// real point of the pieces, no nearer than the exact minimum; and the shortcut is taken.
#[test]
fn pairs_proven_apart_keep_a_true_lower_bound_without_polishing() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(23);
    let settings = CurvePairSettings::default();
    let (lambda, mut apart, mut unpolished) = (0.002, 0, 0);
    let tolerance = SegmentTolerance::constant(lambda, 0.0);
    for case in 0..2000 {
        // A curved piece: Bézier points on a circle, `step` rad apart from `from`.
        let arc = |centre: DVec2, radius: f64, from: f64, step: f64| CubicSegment {
            bezier: [0.0, 1.0, 2.0, 3.0].map(|k| centre + radius * DVec2::from_angle(from + k * step)),
        };
        // Two curved pieces of blobs facing each other across 0.6 to 1.6 combined bands.
        let gap = rng.random_range(0.6..1.6) * 2.0 * lambda;
        let a = arc(DVec2::ZERO, 0.1, rng.random_range(-0.6..0.0), rng.random_range(0.1..0.15));
        let centre_b = DVec2::new(0.22 + gap, rng.random_range(-0.03..0.03));
        let b = arc(centre_b, 0.12, rng.random_range(2.6..3.1), rng.random_range(0.1..0.15));
        let exact = closest_points_segment_segment(&a, &b, &settings).distance;
        let cutoff = 2.0 * lambda;
        let scale = pair_scale(&a, &b);
        let query = query_segment_segment(
            &TolerancedSegment { segment: a, tolerance },
            &TolerancedSegment { segment: b, tolerance },
            Orientation::CounterClockwise,
            &settings,
        );
        if exact <= cutoff + 1e-9 * scale {
            continue;
        }
        apart += 1;
        assert_eq!(query.state, SegmentPairState::Separate, "case {case}: {exact} apart");
        let bound = query.distance_lower_bound;
        assert!(bound >= cutoff && bound <= exact + 1e-12 * scale, "case {case}: bound {bound}, exact {exact}");
        if let Some(c) = query.closest {
            assert!(c.distance >= exact - 1e-12 * scale, "case {case}: {c:?} nearer than {exact}");
            assert!(c.point_a == a.position(c.t) && c.point_b == b.position(c.s), "case {case}: {c:?}");
            unpolished += usize::from(c.distance > exact + 1e-9 * scale);
        }
    }
    assert!(apart > 1000 && unpolished > 100, "{apart} pairs apart, {unpolished} answered unpolished");
}

/// Bumps of two rough blobs facing each other a few millimetres apart, sliding past each other
/// along the tangent at their nearest points: the direction between the nearest points (four
/// Newton steps) separates them by about their distance, and a slide does not close that gap,
/// so with it some axis keeps them apart for at least a second at 1 m/s. In some of the cases
/// every one of the hull's five axes is closed by the slide within 1/60 s: without the sixth
/// axis those pairs bounded a sub-step by their sliding speed (a third of a landing pile's
/// cuts, docs/performance.md).
#[test]
fn the_nearest_direction_separates_facing_bulges_by_their_distance() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(31);
    let settings = CurvePairSettings::default();
    let arc = |centre: DVec2, radius: f64, from: f64, step: f64| CubicSegment {
        bezier: [0.0, 1.0, 2.0, 3.0].map(|k| centre + radius * DVec2::from_angle(from + k * step)),
    };
    let mut hull_short = 0;
    let mut cases = 0;
    for case in 0..2000 {
        // Bumps of rough blobs, radii 2 to 10 cm, each piece turning by 0.3 to 1.5 rad, facing
        // each other 3 to 6 mm apart along a random direction (which the coordinate axes miss).
        let (ra, rb) = (rng.random_range(0.02..0.1), rng.random_range(0.02..0.1));
        let (sa, sb) = (rng.random_range(0.1..0.5), rng.random_range(0.1..0.5));
        let turn = rng.random_range(0.0..std::f64::consts::TAU);
        let gap = rng.random_range(0.003..0.006);
        let a = arc(DVec2::ZERO, ra, turn + rng.random_range(-3.0 * sa..0.0), sa);
        let facing = turn + std::f64::consts::PI;
        let b = arc((ra + rb + gap) * DVec2::from_angle(turn), rb, facing + rng.random_range(-3.0 * sb..0.0), sb);
        let found = closest_points_segment_segment(&a, &b, &settings);
        // Only pieces whose nearest points lie inside both (the pieces face each other there).
        if found.t <= 0.0 || found.t >= 1.0 || found.s <= 0.0 || found.s >= 1.0 {
            continue;
        }
        cases += 1;
        let exact = found.distance;
        // A sliding past B along the tangent at their nearest points, at 1 m/s either way: how
        // long the axes' gaps keep them apart (an axis lasts its gap over the speed closing it,
        // ∞ where it does not close).
        let tangent = (found.point_b - found.point_a).perp() / exact;
        let axes = separating_axes(&a, &b);
        let lasts = |axes: &[(DVec2, f64)]| {
            [tangent, -tangent]
                .map(|sliding| {
                    let time = |&(axis, gap): &(DVec2, f64)| {
                        if gap <= 0.0 { 0.0 } else { gap / sliding.dot(axis).max(0.0) }
                    };
                    axes.iter().map(time).fold(0.0, f64::max)
                })
                .into_iter()
                .fold(f64::INFINITY, f64::min)
        };
        let along = axes[SEPARATING_AXES - 1].1;
        assert!(
            along >= 0.95 * exact && along <= exact + 1e-12,
            "case {case}: {along} along the nearest direction, {exact} apart"
        );
        // With the nearest direction, the slide closes no gap for at least a second.
        assert!(lasts(&axes) >= 1.0, "case {case}: a slide at 1 m/s closes every gap within {} s", lasts(&axes));
        // The hull's axes alone: every gap closed within one step of 1/60 s.
        hull_short += usize::from(lasts(&axes[..SEPARATING_AXES - 1]) < 1.0 / 60.0);
    }
    assert!(
        cases > 500 && hull_short > 10,
        "a slide at 1 m/s closed every hull gap within 1/60 s in {hull_short} of {cases} cases only"
    );
}

/// Each separating axis points from A's side to B's: B's projection lies beyond A's by the
/// gap, so `(v_A − v_B)·axis` is the speed that closes it (conservative advancement reads
/// only that). Checked on points of random pieces, every axis that separates.
#[test]
fn separating_axes_point_from_a_to_b() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(29);
    let mut separating = 0;
    for case in 0..2000 {
        let direction = rng.random_range(0.0..std::f64::consts::TAU);
        let mut piece = |offset: DVec2| CubicSegment {
            bezier: [0; 4].map(|_| offset + DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))),
        };
        let a = piece(DVec2::ZERO);
        let b = piece(DVec2::from_angle(direction) * 2.5);
        for (axis, gap) in separating_axes(&a, &b) {
            if gap <= 0.0 {
                continue;
            }
            separating += 1;
            // Points of the curves (the gap is between their exact projections, which hold
            // every sampled point).
            let project = |piece: &CubicSegment, k: u32| piece.position(f64::from(k) / 64.0).dot(axis);
            let a_high = (0..=64).map(|k| project(&a, k)).fold(f64::NEG_INFINITY, f64::max);
            let b_low = (0..=64).map(|k| project(&b, k)).fold(f64::INFINITY, f64::min);
            assert!(
                b_low - a_high >= gap - 1e-12,
                "case {case}: B beyond A by {} along {axis}, gap {gap}",
                b_low - a_high
            );
        }
    }
    assert!(separating > 2000, "{separating} separating axes");
}

#[test]
fn crossing_lines_intersect_at_the_crossing() {
    let a = line(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0));
    let b = line(DVec2::new(0.0, 1.0), DVec2::new(1.0, 0.0));
    let (t, s) = intersect_segment_segment(&a, &b, &CurvePairSettings::default()).unwrap();
    assert!((t - 0.5).abs() < 1e-12 && (s - 0.5).abs() < 1e-12);
}

#[test]
fn skew_lines_have_their_nearest_points_at_an_end() {
    let a = line(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0));
    let b = line(DVec2::new(2.0, 1.0), DVec2::new(3.0, 5.0));
    let c = closest_points_segment_segment(&a, &b, &CurvePairSettings::default());
    assert!((c.t - 1.0).abs() < 1e-15 && c.s.abs() < 1e-15);
    assert!((c.distance - 2f64.sqrt()).abs() < 1e-14);
}

#[test]
fn parallel_lines_in_the_band_give_two_points() {
    let a = TolerancedSegment {
        segment: line(DVec2::new(0.0, 0.0), DVec2::new(2.0, 0.0)),
        tolerance: SegmentTolerance::constant(0.05, 0.0),
    };
    let b = TolerancedSegment {
        segment: line(DVec2::new(1.5, 0.08), DVec2::new(0.5, 0.08)),
        tolerance: SegmentTolerance::constant(0.05, 0.0),
    };
    let q = query_segment_segment(&a, &b, Orientation::Clockwise, &CurvePairSettings::default());
    assert_eq!(q.state, SegmentPairState::Contact, "{q:?}");
    let ends = q.contacts.as_slice();
    assert_eq!(ends.len(), 2);
    let mut xs = [ends[0].point_a.x, ends[1].point_a.x];
    xs.sort_by(f64::total_cmp);
    assert!((xs[0] - 0.5).abs() < 1e-9 && (xs[1] - 1.5).abs() < 1e-9, "{xs:?}");
    for e in ends {
        assert!((e.distance - 0.08).abs() < 1e-12 && (e.penetration - 0.02).abs() < 1e-12);
        assert!((e.normal - DVec2::new(0.0, -1.0)).length() < 1e-12, "{:?}", e.normal);
    }
}

/// A search started from a remembered point (a contact that moved past its trust radius)
/// finds the same minimum as a cold search, also where Newton from that point alone stops in
/// another basin: the seed only gives the branch and bound an incumbent. Random wiggly pieces
/// (Bézier points anywhere in a unit box, so several local minima are common), random seeds.
#[test]
fn a_seeded_search_finds_the_cold_minimum() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(29);
    let settings = CurvePairSettings::default();
    let mut trapped = 0;
    for case in 0..3000 {
        let mut point = || DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        let a = CubicSegment { bezier: [(); 4].map(|()| point()) };
        let offset = DVec2::new(0.3, -0.5) + point() * DVec2::new(0.9, 1.0);
        let b = CubicSegment { bezier: [(); 4].map(|()| offset + point()) };
        let seed = DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        let scale = pair_scale(&a, &b);
        let touch = settings.intersection_tolerance * scale;
        let cold = search(&a, &b, &settings, f64::INFINITY).closest.expect("no cutoff: a point").distance;
        let seeded =
            search_from(&a, &b, &settings, f64::INFINITY, (Some(seed), None)).closest.expect("a point").distance;
        if cold <= touch {
            assert!(seeded <= touch, "case {case}: cold search crosses, seeded {seeded}");
            continue;
        }
        assert!((seeded - cold).abs() <= 1e-12 * scale, "case {case}: seeded {seeded}, cold {cold}");
        let local = minimize_distance(&a, &b, seed, ParamBox::UNIT, &settings, RoundingFloor::Crawl).distance;
        trapped += usize::from(local > cold + 1e-6 * scale);
    }
    assert!(trapped > 200, "Newton from the seed alone missed the minimum in only {trapped} cases");
}

/// The least distance between 201 evenly spaced points of each piece (at least the pieces' least
/// distance).
fn sampled_least_distance(a: &CubicSegment, b: &CubicSegment) -> f64 {
    let samples = 200;
    let points =
        |piece: &CubicSegment| (0..=samples).map(|k| piece.position(k as f64 / samples as f64)).collect::<Vec<_>>();
    let (pa, pb) = (points(a), points(b));
    pa.iter().flat_map(|p| pb.iter().map(move |q| p.distance(*q))).fold(f64::INFINITY, f64::min)
}

/// A contact searched from its last answer (a moved contact) is certified by the slab between
/// its nearest points where each piece lies on its own side, with no cell searched. Two kinds
/// of pairs: arcs of blobs facing each other within the band, searched from their cold
/// minimum moved by up to 0.05 in each parameter (a moved contact, the certificate's use); and
/// an arc facing a random piece (each Bézier point up to 6 mm off the chord, often a bump and
/// an end or two bumps), searched from anywhere in the square, where Newton from the seed often
/// stops at a local minimum that is not the least. In both, the seeded search's answer is the
/// cold search's minimum (to the search's slack); no local minimum above the least is
/// certified; and wherever the slab certifies a point, no sampled point pair is nearer than its
/// distance less the slack. (1,493 of the 2,000 facing pairs are certified; 48 random ones
/// trap Newton. Checking A's side alone certifies such a trap.)
#[test]
fn the_slab_between_nearest_points_certifies_moved_contacts_soundly() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(29);
    let settings = CurvePairSettings::default();
    let lambda = 0.002;
    let arc = |centre: DVec2, radius: f64, from: f64, step: f64| CubicSegment {
        bezier: [0.0, 1.0, 2.0, 3.0].map(|k| centre + radius * DVec2::from_angle(from + k * step)),
    };
    let (mut certified_facing, mut trapped) = (0, 0);
    for case in 0..4000 {
        let random = case % 2 == 1;
        let gap = rng.random_range(0.1..1.5) * 2.0 * lambda;
        let a = arc(DVec2::ZERO, 0.1, rng.random_range(-0.6..0.0), rng.random_range(0.1..0.15));
        let centre_b = DVec2::new(0.22 + gap, rng.random_range(-0.03..0.03));
        let mut b = arc(centre_b, 0.12, rng.random_range(2.6..3.1), rng.random_range(0.1..0.15));
        if random {
            let (from, to) = (b.bezier[0], b.bezier[3]);
            let across = (to - from).perp().normalize();
            let mut off = || rng.random_range(-0.006..0.006) * across;
            b.bezier = [from + off(), from.lerp(to, 1.0 / 3.0) + off(), from.lerp(to, 2.0 / 3.0) + off(), to + off()];
        }
        let scale = pair_scale(&a, &b);
        let slack = settings.distance_tolerance * scale;
        let cold = closest_points_segment_segment(&a, &b, &settings);
        if cold.distance <= settings.intersection_tolerance * scale {
            continue; // crossing pieces: no slab
        }
        let seed = if random {
            DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0))
        } else {
            let moved = DVec2::new(rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05));
            (DVec2::new(cold.t, cold.s) + moved).clamp(DVec2::ZERO, DVec2::ONE)
        };
        // Where Newton from the seed stops, and whether the slab certifies it.
        let local = minimize_distance(&a, &b, seed, ParamBox::UNIT, &settings, RoundingFloor::Crawl);
        let certifies = slab_separates(&a, &b, local.x, slack, true);
        if local.distance > cold.distance + 2.0 * slack {
            trapped += 1;
            assert!(
                !certifies,
                "case {case}: a local minimum {} above the least {} certified",
                local.distance, cold.distance
            );
        }
        if certifies {
            certified_facing += usize::from(!random);
            let nearest = sampled_least_distance(&a, &b);
            assert!(
                nearest >= local.distance - slack,
                "case {case}: a sampled pair {nearest} nearer than {}",
                local.distance
            );
        }
        let seeded = search_from(&a, &b, &settings, f64::INFINITY, (Some(seed), None));
        let got = seeded.closest.expect("a point");
        assert!(
            (got.distance - cold.distance).abs() <= 2.0 * slack,
            "case {case}: seeded {} against cold {}",
            got.distance,
            cold.distance
        );
        assert!(
            seeded.lower_bound <= cold.distance + slack,
            "case {case}: bound {} above {}",
            seeded.lower_bound,
            cold.distance
        );
    }
    assert!(certified_facing > 1300 && trapped > 30, "{certified_facing} facing pairs certified, {trapped} trapped");
}

/// A blob resting in another's hollow: a convex arc (radius 5–9 cm) inside a concave one
/// (radius 12–20 cm) within the band, searched from their cold minimum moved by up to 0.05 in
/// each parameter. The slab between the nearest points certifies none of them (the hollow's
/// piece turns towards the blob on both sides); the ring (`search::Ring`) certifies most, and
/// wherever it does no sampled point pair is nearer than its distance less the slack; the
/// seeded search's answer is the cold search's.
#[test]
fn the_ring_between_nearest_points_certifies_a_blob_in_a_hollow_soundly() {
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let mut rng = StdRng::seed_from_u64(31);
    let settings = CurvePairSettings::default();
    let lambda = 0.002;
    let arc = |centre: DVec2, radius: f64, from: f64, step: f64| CubicSegment {
        bezier: [0.0, 1.0, 2.0, 3.0].map(|k| centre + radius * DVec2::from_angle(from + k * step)),
    };
    let down = -std::f64::consts::FRAC_PI_2;
    let (mut by_ring, mut by_slab, cases) = (0, 0, 1000);
    for case in 0..cases {
        let (hollow, blob) = (rng.random_range(0.12..0.2), rng.random_range(0.05..0.09));
        let gap = rng.random_range(0.1..1.5) * 2.0 * lambda;
        let step_a = rng.random_range(0.1..0.15);
        let a = arc(DVec2::ZERO, hollow, down - 1.5 * step_a + rng.random_range(-0.05..0.05), step_a);
        let centre_b = DVec2::new(rng.random_range(-0.005..0.005), -hollow + blob + gap);
        let step_b = rng.random_range(0.2..0.3);
        let b = arc(centre_b, blob, down + 1.5 * step_b + rng.random_range(-0.05..0.05), -step_b);
        let scale = pair_scale(&a, &b);
        let slack = settings.distance_tolerance * scale;
        let cold = closest_points_segment_segment(&a, &b, &settings);
        let moved = DVec2::new(rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05));
        let seed = (DVec2::new(cold.t, cold.s) + moved).clamp(DVec2::ZERO, DVec2::ONE);
        let local = minimize_distance(&a, &b, seed, ParamBox::UNIT, &settings, RoundingFloor::Crawl);
        by_slab += usize::from(slab_separates(&a, &b, local.x, slack, false));
        if slab_separates(&a, &b, local.x, slack, true) {
            by_ring += 1;
            let nearest = sampled_least_distance(&a, &b);
            assert!(
                nearest >= local.distance - slack,
                "case {case}: a sampled pair {nearest} nearer than {}",
                local.distance
            );
        }
        let seeded = search_from(&a, &b, &settings, f64::INFINITY, (Some(seed), None)).closest.expect("a point");
        assert!(
            (seeded.distance - cold.distance).abs() <= 2.0 * slack,
            "case {case}: seeded {} against cold {}",
            seeded.distance,
            cold.distance
        );
        // The bound itself, ring included, over random cells against their exact minimum.
        let slab = Slab::at(&a, &b, local.x).expect("apart");
        for _ in 0..4 {
            let mut interval = || {
                let (u, v) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
                if u < v { (u, v) } else { (v, u) }
            };
            let ((t0, t1), (s0, s1)) = (interval(), interval());
            let (piece_a, piece_b) = (a.subsegment(t0, t1), b.subsegment(s0, s1));
            let cell = Cell { a: piece_a, b: piece_b, t0, t1, s0, s1, depth: 1, lower_bound: 0.0 };
            let exact = closest_points_segment_segment(&piece_a, &piece_b, &settings).distance;
            let bound = slab.bound(&cell, f64::INFINITY);
            assert!(bound <= exact + slack, "case {case}: bound {bound} above the cell's least {exact}");
        }
    }
    assert!(by_slab == 0 && by_ring > cases / 2, "the slab certified {by_slab}, the ring {by_ring} of {cases}");
}
