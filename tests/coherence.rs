//! Temporal coherence of the narrow phase (docs/model.md §3a) against the full search: random
//! body pairs placed in contact, then moved by small random rigid motions for many consecutive
//! steps; at every step the query that answers from the pair's memory is compared with the
//! query that searches every leaf pair, and with the exact nearest points of each leaf pair.
//!
//! What the memory promises, for a leaf pair whose pieces moved by `δ ≤ tolerance × band`
//! since its last full search: the same intersections (never a missed crossing), a separate
//! leaf pair's gap still a lower bound, and a contact's distance between the true minimum and
//! `2δ` above it.

use std::f64::consts::TAU;

use glam::DVec2;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rugosa::{AobbTree, Generator, Pose, Rugosity, Spline};
use rugosa::{BodyQuery, BodyShape, Coherence, PairState, QuerySettings, query_bodies_within};
use rugosa::{CurvePairSettings, Orientation, closest_points_segment_segment, query_segment_segment};

const CASES: u64 = 48;
const STEPS: usize = 150;

fn random_shape(rng: &mut StdRng, radius: f64) -> Spline {
    loop {
        let generator = match rng.random_range(0..5) {
            0 => Generator::Circle { radius },
            1 => Generator::Ellipse { a: radius, b: radius * rng.random_range(0.3..1.0) },
            2 => {
                let (width, height) = (2.0 * radius, 2.0 * radius * rng.random_range(0.3..1.0));
                Generator::RoundedRectangle { width, height, corner_radius: rng.random_range(0.05..0.5) * height }
            }
            3 => Generator::Superellipse { a: radius, b: radius * rng.random_range(0.4..1.0), exponent: 4.0 },
            _ => Generator::Blob { radius, roughness: rng.random_range(0.0..0.8), seed: rng.random_range(0..u64::MAX) },
        };
        if let Ok(spline) = generator.build(rng.random_range(8..=24)) {
            return spline;
        }
    }
}

struct Body {
    spline: Spline,
    rugosity: Rugosity,
    tree: AobbTree,
}

fn body(rng: &mut StdRng, settings: &QuerySettings, flat: Option<(f64, f64)>) -> Body {
    let radius = rng.random_range(0.3..1.2);
    let spline = match flat {
        Some((width, height)) => {
            let corner_radius = 0.1 * height;
            Generator::RoundedRectangle { width, height, corner_radius }.build(rng.random_range(24..=36)).unwrap()
        }
        None => random_shape(rng, radius),
    };
    let band = rng.random_range(0.005..0.03) * spline.extent();
    let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
    let tree = AobbTree::build(&spline, &rugosity, settings.min_band);
    Body { spline, rugosity, tree }
}

/// A's pose that puts a random point of A against a random point of B, `gap` apart along
/// B's normal there (B at `pose_b`).
fn touching_pose(rng: &mut StdRng, a: &Spline, b: &Spline, pose_b: &Pose, gap: f64) -> Pose {
    let u_b = rng.random_range(0.0..b.segment_count() as f64);
    let u_a = rng.random_range(0.0..a.segment_count() as f64);
    let (x_b, n_b) = (pose_b.transform_point(b.position(u_b)), pose_b.rotate(b.outward_normal(u_b)));
    let (x_a, n_a) = (a.position(u_a), a.outward_normal(u_a));
    let angle = (-n_b).to_angle() - n_a.to_angle();
    Pose::new(x_b + gap * n_b - DVec2::from_angle(angle).rotate(x_a), angle)
}

#[derive(Default, Debug)]
struct Tally {
    steps: usize,
    leaf_pairs: u64,
    recalled: u64,
    contacts_checked: usize,
    intersecting: usize,
    conformal_checked: usize,
    flips: usize,
    gaps_checked: usize,
    largest_excess: f64,
}

fn run_case(index: u64, tolerance: f64, tally: &mut Tally) {
    let settings = QuerySettings::default();
    let mut rng = StdRng::seed_from_u64(0xc0_4e_5e_4c_e0 ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    // One case in three: two rounded boxes flat on flat (a conformal contact, two ends).
    let boxes = index.is_multiple_of(3);
    let size_of = |rng: &mut StdRng| (rng.random_range(0.5..2.0), rng.random_range(0.3..1.0));
    let (flat_a, flat_b) = if boxes { (Some(size_of(&mut rng)), Some(size_of(&mut rng))) } else { (None, None) };
    let (a, b) = (body(&mut rng, &settings, flat_a), body(&mut rng, &settings, flat_b));
    let (shape_a, shape_b) = (BodyShape::new(&a.spline, &a.rugosity), BodyShape::new(&b.spline, &b.rugosity));
    let band_a = a.rugosity.constant_value().unwrap().max(settings.min_band);
    let band_b = b.rugosity.constant_value().unwrap().max(settings.min_band);
    let band = band_a + band_b;
    let size = a.spline.extent().max(b.spline.extent());
    let pose_b =
        Pose::new(DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)), rng.random_range(0.0..TAU));
    let gap = rng.random_range(0.2..0.8) * band;
    let mut pose_a = match (flat_a, flat_b) {
        (Some((width_a, height_a)), Some((width_b, height_b))) => {
            // A on B's top face, shifted along it by up to a quarter of the shorter width.
            let shift = rng.random_range(-0.25..0.25) * width_a.min(width_b);
            let centre = DVec2::new(shift, 0.5 * (height_a + height_b) + gap);
            Pose::new(pose_b.transform_point(centre), pose_b.angle())
        }
        _ => touching_pose(&mut rng, &a.spline, &b.spline, &pose_b, gap),
    };
    // Per step: a small random translation and turn (a walk that slides and rocks the contact),
    // 1–50 % of the trust radius, so that memories are kept for a while and renewed; over the
    // run the walk carries some pairs out of the band and some into each other.
    let step = rng.random_range(0.01..0.5) * tolerance * band;
    let (mut warm, mut cold) = (BodyQuery::default(), BodyQuery::default());
    let mut memory = Vec::new();
    for k in 0..STEPS {
        let coherence = Coherence { memory: &memory, tolerance, front: None };
        let margin = 0.1 * band;
        let got = query_bodies_within(
            &shape_a, &a.tree, &pose_a, &shape_b, &b.tree, &pose_b, margin, coherence, &settings, &mut warm,
        )
        .clone();
        let full = query_bodies_within(
            &shape_a,
            &a.tree,
            &pose_a,
            &shape_b,
            &b.tree,
            &pose_b,
            margin,
            Coherence::OFF,
            &settings,
            &mut cold,
        );
        let context = format!("case {index}, step {k}, tolerance {tolerance}");
        assert_eq!(
            got.state == PairState::Intersecting,
            full.state == PairState::Intersecting,
            "{context}: crossing decided differently"
        );
        // A contact that is not an end of a conformal overlap is a nearest point: its distance
        // lies between the leaf pair's true minimum and 2 δ ≤ 2 × tolerance × band above it.
        // (An overlap's end lies in the band, farther than the minimum.)
        let eps = 1e-9 * size;
        for contact in &got.contacts {
            let leaf_a = shape_a.world_segment(contact.segment_a as usize, &pose_a, settings.min_band);
            let leaf_b = shape_b.world_segment(contact.segment_b as usize, &pose_b, settings.min_band);
            let exact = closest_points_segment_segment(&leaf_a.segment, &leaf_b.segment, &settings.curve_pair).distance;
            let excess = contact.contact.distance - exact;
            assert!(
                excess >= -eps,
                "{context}: a contact nearer ({}) than the pieces ({exact})",
                contact.contact.distance
            );
            let searched = query_segment_segment(&leaf_a, &leaf_b, Orientation::CounterClockwise, &settings.curve_pair);
            let ends = got
                .contacts
                .iter()
                .filter(|c| (c.segment_a, c.segment_b) == (contact.segment_a, contact.segment_b))
                .count();
            if searched.contacts.as_slice().len() == 2 {
                continue;
            }
            if ends == 2 {
                tally.flips += 1;
                continue;
            }
            assert!(
                excess <= 2.0 * tolerance * band + eps,
                "{context}: contact at distance {} with the leaf pair's minimum {exact}",
                contact.contact.distance
            );
            tally.largest_excess = tally.largest_excess.max(excess / band);
            tally.contacts_checked += 1;
        }
        // A conformal overlap has the same two ends whichever point of it the search starts from.
        for leaf in got.contacts.chunk_by(|x, y| (x.segment_a, x.segment_b) == (y.segment_a, y.segment_b)) {
            let same = |c: &&rugosa::BodyContact| (c.segment_a, c.segment_b) == (leaf[0].segment_a, leaf[0].segment_b);
            let searched: Vec<_> = full.contacts.iter().filter(same).collect();
            if leaf.len() != 2 || searched.len() != 2 {
                continue;
            }
            for end in leaf {
                let nearest = searched
                    .iter()
                    .map(|c| c.contact.point_a.distance(end.contact.point_a))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest <= 1e-6 * size,
                    "{context}: an end of the overlap {nearest} from the search's\n{leaf:#?}\n{searched:#?}"
                );
            }
            tally.conformal_checked += 1;
        }
        // Gaps stay lower bounds.
        for gap in &got.gaps {
            let exact =
                closest_points_segment_segment(&gap.piece_a, &gap.piece_b, &CurvePairSettings::default()).distance;
            assert!(gap.gap + gap.approach <= exact + eps, "{context}: gap {} above the distance {exact}", gap.gap);
            tally.gaps_checked += 1;
        }
        // The deepest contact agrees with the search's to 2 δ, and contact is found wherever the
        // search finds it deeper than 2 δ inside the band.
        let deepest =
            |m: &rugosa::Manifold| m.contacts.iter().map(|c| c.contact.distance).fold(f64::INFINITY, f64::min);
        let (d_warm, d_cold) = (deepest(&got), deepest(full));
        if d_cold < band - 2.0 * tolerance * band - eps && full.state == PairState::Contact {
            assert!(
                (d_warm - d_cold).abs() <= 2.0 * tolerance * band + eps,
                "{context}: deepest contact {d_warm} against the search's {d_cold}"
            );
        }
        tally.intersecting += usize::from(full.state == PairState::Intersecting);
        tally.leaf_pairs += warm.leaf_pairs.len() as u64;
        tally.recalled += got.recalled_leaf_pairs;
        tally.steps += 1;
        memory.clone_from(&warm.memory);
        let turn = rng.random_range(-1.0..1.0) * step / size;
        let shift = DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * step;
        pose_a = Pose::new(pose_a.position + shift, pose_a.angle() + turn);
    }
}

#[test]
fn memory_answers_as_the_search_does_over_many_steps() {
    for tolerance in [1e-3, 1e-2, 0.1] {
        let mut tally = Tally::default();
        for index in 0..CASES {
            run_case(index, tolerance, &mut tally);
        }
        println!("tolerance {tolerance}: {tally:?}");
        // The memory is used (most leaf pairs move little per step here), and what was checked
        // is not empty.
        assert!(tally.recalled * 2 > tally.leaf_pairs, "{tally:?}");
        assert!(tally.contacts_checked > 1000 && tally.gaps_checked > 1000, "{tally:?}");
        assert!(tally.conformal_checked > 500, "{tally:?}");
        // Whether pieces are conformal is a threshold on their curvature at a point of the
        // distance's valley; the memory judges it a few Newton steps into the valley, the
        // search at its bottom. Only pairs at the threshold can be judged differently: none at
        // the default tolerance, rarely at the larger ones.
        if tolerance <= 1e-3 {
            assert_eq!(tally.flips, 0, "{tally:?}");
        }
        assert!(tally.flips * 200 <= tally.conformal_checked, "{tally:?}");
    }
}

#[test]
fn zero_tolerance_searches_every_leaf_pair() {
    let mut tally = Tally::default();
    for index in 0..4 {
        run_case(index, 0.0, &mut tally);
    }
    assert_eq!(tally.recalled, 0);
}
