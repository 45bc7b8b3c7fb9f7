//! Snapshots: a simulation saved to RON text and restored continues bit-identically — every
//! body's position, angle and velocities (`f64::to_bits`), sleep, the contact and touch events
//! and the touching pairs, at every step — for 1 and 2 threads, from the middle of an
//! `advance`, with the contacts not yet detected, and with the seed's contact model; the
//! snapshot of a restored simulation is the original's, to the byte; a corrupt snapshot is a
//! typed error naming the field, never a panic.
#![cfg(feature = "scene")]

mod common;
#[path = "common/pile.rs"]
mod pile;

use std::sync::Arc;

use common::{box_spline, disc, material};
use glam::DVec2;
use hecs::Entity;
use rugosa::{
    AobbTree, BodyDesc, BodyKind, CollisionGroups, ContactModel, FrictionLaw, MassProperties, Motion, PairAction,
    PairContacts, Rugosity, ShapeError, Simulation, SimulationSettings, Snapshot, SnapshotError,
};

const DT: f64 = 1.0 / 120.0;

/// The bodies of the scene a test acts on.
struct Handles {
    platform: Entity,
    rider: Entity,
    blobs: Vec<Entity>,
}

/// A pile of 12 blobs in a box that lands, rests and sleeps; a kinematic platform carrying a
/// box beside it; a static sensor in the pile; an excluded pair, collision groups, damping,
/// fixed rotation, names; a body removed and another added (so handles have gaps and a reused
/// slot).
fn scene(settings: SimulationSettings) -> (Simulation, Handles) {
    let mut sim = Simulation::new(settings).unwrap();
    let mut blobs = Vec::new();
    for (k, desc) in pile::blob_pile(12, 4).into_iter().enumerate() {
        let desc = match k {
            4 => desc.named("damped").with_motion(Motion {
                linear_damping: 0.5,
                gravity_scale: 0.9,
                ..Motion::default()
            }),
            5 => desc.with_motion(Motion { fixed_rotation: true, ..Motion::default() }),
            6 => desc.with_groups(CollisionGroups::new(0b11, !0b100)),
            _ => desc,
        };
        let body = sim.add_body(desc).unwrap();
        if k >= 3 {
            blobs.push(body);
        }
    }
    sim.exclude_pair(blobs[0], blobs[4]).unwrap(); // blob 4 falls through blob 0
    let friction = FrictionLaw { lambda_min: 0.0, mu_max: 0.6 };
    let sensor = disc(0.25, 16, 0.0, material(0.0, friction)).at(DVec2::new(0.0, 0.3), 0.0).fixed().sensor();
    sim.add_body(sensor.named("sensor")).unwrap();
    let slab = box_spline(1.0, 0.1, 0.05);
    let slab = BodyDesc::new(slab.clone(), Rugosity::constant(slab.segment_count(), 0.002).unwrap())
        .with_material(material(0.0, friction))
        .at(DVec2::new(3.0, 0.5), 0.0)
        .with_velocity(DVec2::new(0.2, 0.0), 0.0);
    let platform = sim.add_body(slab.kinematic().named("platform")).unwrap();
    let doomed = sim.add_body(disc(0.1, 16, 0.002, material(0.3, friction)).at(DVec2::new(-3.0, 2.0), 0.0)).unwrap();
    sim.step(DT);
    assert!(sim.remove_body(doomed));
    let rider = box_spline(0.2, 0.2, 0.05);
    let rider = BodyDesc::new(rider.clone(), Rugosity::constant(rider.segment_count(), 0.002).unwrap())
        .with_material(material(0.0, friction))
        .at(DVec2::new(3.0, 0.65), 0.0);
    let rider = sim.add_body(rider.named("rider")).unwrap();
    (sim, Handles { platform, rider, blobs })
}

/// A contact hook that changes the friction of the rider's and of a blob's contacts: the same
/// function in every copy.
fn install_hook(sim: &mut Simulation, handles: &Handles) {
    let (rider, blob) = (handles.rider, handles.blobs[8]);
    sim.set_contact_hook(Some(Arc::new(move |pair: &PairContacts<'_>| {
        if [rider, blob].iter().any(|&b| pair.body_a == b || pair.body_b == b) {
            PairAction::Modify { friction: Some(0.4), restitution: None }
        } else {
            PairAction::Keep
        }
    })));
}

/// The actions of step `k` of a run, the same in every copy: in every 200 steps the platform
/// stands for 150 (the rider falls asleep on it) and moves for 50, to and fro; a push on the
/// pile every 300.
fn act(sim: &mut Simulation, handles: &Handles, k: usize) {
    match k % 200 {
        0 => sim.set_velocity(handles.platform, DVec2::ZERO, 0.0).unwrap(),
        150 => {
            let v = if (k / 200).is_multiple_of(2) { 0.2 } else { -0.2 };
            sim.set_velocity(handles.platform, DVec2::new(v, 0.0), 0.0).unwrap();
        }
        _ => {}
    }
    if k % 300 == 250 {
        let blob = handles.blobs[(k / 300) % handles.blobs.len()];
        let at = sim.state(blob).unwrap().position;
        sim.apply_impulse(blob, DVec2::new(0.05, 0.2), at + DVec2::new(0.02, 0.0)).unwrap();
    }
}

fn ron(sim: &Simulation) -> String {
    sim.snapshot().unwrap().to_ron().unwrap()
}

/// A copy of `sim` through RON text, with `threads` workers (every step on them, however light).
fn restored(sim: &Simulation, threads: usize) -> Simulation {
    let text = ron(sim);
    let mut snapshot = Snapshot::from_ron(&text).unwrap();
    snapshot.settings.threads = threads;
    snapshot.settings.min_parallel_work = 0;
    Simulation::from_snapshot(snapshot).unwrap()
}

/// Every body's state bits and sleep, the touching pairs, and the events drained since the last
/// call: what must be identical.
fn observe(sim: &mut Simulation) -> (Vec<(Entity, [u64; 6], bool)>, String) {
    let bodies = sim
        .bodies()
        .map(|e| {
            let s = sim.state(e).unwrap();
            let bits =
                [s.position.x, s.position.y, s.angle, s.linear_velocity.x, s.linear_velocity.y, s.angular_velocity]
                    .map(f64::to_bits);
            (e, bits, sim.is_sleeping(e))
        })
        .collect();
    // Debug prints every f64 as its shortest round-trip text: equal text, equal bits.
    let events = format!(
        "{:?}\n{:?}\n{:?}",
        sim.drain_events().collect::<Vec<_>>(),
        sim.drain_touch_events().collect::<Vec<_>>(),
        sim.touching_pairs()
    );
    (bodies, events)
}

/// Steps the original and the copies through steps `steps` with the same actions, comparing
/// them after every step; returns how many contact events the original recorded.
fn run_in_lockstep(
    original: &mut Simulation,
    copies: &mut [Simulation],
    handles: &Handles,
    steps: std::ops::Range<usize>,
) -> usize {
    let mut events = 0;
    for k in steps {
        for sim in std::iter::once(&mut *original).chain(copies.iter_mut()) {
            act(sim, handles, k);
            sim.step(DT);
        }
        let expected = observe(original);
        events += expected.1.matches("ContactEvent").count();
        for (c, copy) in copies.iter_mut().enumerate() {
            let seen = observe(copy);
            assert!(seen.0 == expected.0, "copy {c} differs from the original after step {k}");
            assert!(seen.1 == expected.1, "copy {c}: events differ after step {k}:\n{}\n---\n{}", seen.1, expected.1);
        }
    }
    events
}

#[test]
fn a_restored_pile_continues_bit_identically_for_1_and_2_threads() {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let (mut original, handles) = scene(settings);
    install_hook(&mut original, &handles);
    let step = |sim: &mut Simulation, k: usize| {
        act(sim, &handles, k);
        sim.take_profile();
        sim.step(DT);
    };
    // Over the last ten steps before the snapshot: leaf pairs answered from their memory, and
    // pairs carried from their last query with their contacts reused.
    let (mut recalled, mut reused) = (0, 0);
    for k in 0..120 {
        step(&mut original, k);
        if k >= 110 {
            recalled += original.profile().counters.recalled_leaf_pairs;
            reused += original.profile().counters.reused_pairs;
        }
    }
    // The pile has landed and is settling, answering leaf pairs from their memory and
    // warm-started; a force is pending for the next step. Events are not saved: drain them.
    assert!(handles.blobs.iter().any(|&b| !original.is_sleeping(b)), "the pile is at rest already");
    assert!(recalled > 0 && reused > 0, "temporal coherence was not exercised: {recalled} recalled, {reused} reused");
    assert!(original.profile().counters.resting_contacts > 0, "nothing rests");
    original.apply_force_to_centre(handles.blobs[11], DVec2::new(1.0, 0.0)).unwrap();
    observe(&mut original);
    let mut copies = vec![restored(&original, 1), restored(&original, 2)];
    for copy in &mut copies {
        install_hook(copy, &handles);
        assert!(copy.drain_events().next().is_none(), "undrained events are not restored");
    }
    run_in_lockstep(&mut original, &mut copies, &handles, 120..150);
    // The rider sleeps on the platform, which starts moving in the next step: it is woken
    // before that step by the platform's last swept bounds (saved too).
    assert!(original.is_sleeping(handles.rider), "the rider does not sleep");
    let mut late = restored(&original, 1);
    install_hook(&mut late, &handles);
    copies.push(late);
    let events = run_in_lockstep(&mut original, &mut copies, &handles, 150..1150);
    assert!(events > 1000, "only {events} contact events in 1000 steps");
    assert!(handles.blobs.iter().any(|&b| original.is_sleeping(b)), "nothing slept again");
}

#[test]
fn a_snapshot_taken_in_the_middle_of_advance_continues_bit_identically() {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let (mut original, handles) = scene(settings);
    // Frames that are not a whole number of steps: time is left in the accumulator.
    let frame = 0.0123;
    for _ in 0..150 {
        original.advance(frame);
    }
    let snapshot = original.snapshot().unwrap();
    assert!(snapshot.accumulator > 0.0, "nothing accumulated");
    let mut copy = Simulation::from_snapshot(Snapshot::from_ron(&snapshot.to_ron().unwrap()).unwrap()).unwrap();
    observe(&mut original);
    let interpolated = |sim: &Simulation, alpha: f64| -> Vec<[u64; 6]> {
        sim.bodies()
            .map(|e| {
                let s = sim.interpolated_state(e, alpha).unwrap();
                [s.position.x, s.position.y, s.angle, s.linear_velocity.x, s.linear_velocity.y, s.angular_velocity]
                    .map(f64::to_bits)
            })
            .collect()
    };
    assert_eq!(interpolated(&copy, 0.3), interpolated(&original, 0.3));
    for k in 0..600 {
        let (a, b) = (original.advance(frame), copy.advance(frame));
        assert_eq!(a.to_bits(), b.to_bits(), "blend factors differ at frame {k}");
        assert_eq!(interpolated(&copy, a), interpolated(&original, a), "frame {k}");
        assert!(observe(&mut copy) == observe(&mut original), "frame {k}");
    }
    assert!(handles.blobs.iter().any(|&b| original.is_sleeping(b)));
}

#[test]
fn a_snapshot_before_contacts_are_detected_and_one_of_the_seed_model_continue_bit_identically() {
    for model in [ContactModel::Solver, ContactModel::SeedMicroCollisions] {
        let settings = SimulationSettings { threads: 1, contact_model: model, ..SimulationSettings::default() };
        let (mut original, handles) = scene(settings);
        for k in 0..120 {
            act(&mut original, &handles, k);
            original.step(DT);
        }
        // A body added: contacts must be detected before the next step (nothing of them saved).
        let ball = disc(0.08, 16, 0.002, material(0.3, FrictionLaw::default())).at(DVec2::new(0.0, 1.5), 0.0);
        original.add_body(ball).unwrap();
        let snapshot = original.snapshot().unwrap();
        assert!(snapshot.needs_detection);
        observe(&mut original);
        let mut copies = [restored(&original, 2)];
        run_in_lockstep(&mut original, &mut copies, &handles, 120..420);
    }
}

#[test]
fn the_snapshot_of_a_restored_simulation_is_the_original_snapshot() {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let (mut original, handles) = scene(settings);
    for k in 0..200 {
        act(&mut original, &handles, k);
        original.step(DT);
    }
    let text = ron(&original);
    let mut copy = Simulation::from_snapshot(Snapshot::from_ron(&text).unwrap()).unwrap();
    assert!(ron(&copy) == text, "the restored simulation's snapshot differs from the one it came from");
    // Mass properties and trees are rebuilt, not saved: to the bit.
    let derived = |sim: &Simulation, e: Entity| {
        let world = sim.world();
        format!("{:?} {:?}", *world.get::<&AobbTree>(e).unwrap(), *world.get::<&MassProperties>(e).unwrap())
    };
    assert!(original.bodies().all(|e| derived(&copy, e) == derived(&original, e)), "a rebuilt tree or mass differs");
    assert!(text.contains("leaves: [(segment_a:"), "no leaf memory saved");
    assert!(text.contains("normal_force:"), "no warm start saved");
    for k in 200..260 {
        act(&mut original, &handles, k);
        act(&mut copy, &handles, k);
        original.step(DT);
        copy.step(DT);
    }
    assert!(ron(&copy) == ron(&original), "the snapshots differ 60 steps later");
    // Handles stay valid; a body added afterwards gets none of the original's handles.
    assert_eq!(copy.state(handles.rider), original.state(handles.rider));
    let added = copy.add_body(disc(0.05, 16, 0.0, material(0.0, FrictionLaw::default()))).unwrap();
    assert!(original.bodies().all(|e| e != added) && original.state(added).is_none());
}

#[test]
fn a_snapshot_at_every_step_of_a_collision_continues_bit_identically() {
    // Two discs without gravity: approaching (the leaf gaps bound the sub-step), colliding off
    // centre, then flying apart (no candidate pair, their last contacts still remembered).
    let settings = SimulationSettings { threads: 1, gravity: DVec2::ZERO, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    let friction = FrictionLaw { lambda_min: 0.0, mu_max: 0.5 };
    let ball = |at: DVec2| disc(0.1, 16, 0.002, material(0.8, friction)).at(at, 0.0);
    sim.add_body(ball(DVec2::new(0.0, 0.0)).with_velocity(DVec2::new(2.0, 0.0), 3.0)).unwrap();
    sim.add_body(ball(DVec2::new(0.5, 0.08))).unwrap();
    let (snapshots, follow) = (100, 40);
    let mut texts = Vec::new();
    let mut observed = Vec::new();
    for k in 0..snapshots + follow {
        if k < snapshots {
            texts.push(ron(&sim));
        }
        sim.step(DT);
        observed.push(observe(&mut sim));
    }
    assert!(observed.iter().any(|(_, events)| events.contains("ContactEvent")), "no collision");
    let remembered = |t: &String| t.contains("candidate_pairs: [],") && !t.contains("detected_pairs: 0,");
    assert!(texts.iter().any(remembered), "never apart with contacts remembered");
    for (k, text) in texts.iter().enumerate() {
        let mut copy = Simulation::from_snapshot(Snapshot::from_ron(text).unwrap()).unwrap();
        assert!(ron(&copy) == *text, "step {k}: the restored simulation's snapshot differs");
        for (j, expected) in observed[k..k + follow].iter().enumerate() {
            copy.step(DT);
            assert!(observe(&mut copy) == *expected, "restored at step {k}: differs {j} steps later");
        }
    }
}

/// The snapshot of the pile after 120 steps.
fn pile_snapshot() -> Snapshot {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let (mut sim, handles) = scene(settings);
    for k in 0..120 {
        act(&mut sim, &handles, k);
        sim.step(DT);
    }
    let snapshot = sim.snapshot().unwrap();
    assert!(!snapshot.needs_detection);
    snapshot
}

/// Restores `snapshot` through RON text: the error it gives.
fn restore_error(snapshot: &Snapshot) -> SnapshotError {
    restore_text_error(&snapshot.to_ron().unwrap())
}

fn restore_text_error(text: &str) -> SnapshotError {
    match Snapshot::from_ron(text).and_then(Simulation::from_snapshot) {
        Ok(_) => panic!("a corrupt snapshot was restored"),
        Err(e) => e,
    }
}

fn field_of(error: &SnapshotError) -> &str {
    match error {
        SnapshotError::Field { field, .. } => field,
        other => panic!("not a field error: {other}"),
    }
}

/// Replaces the number after the first `key` in `text` with `value`.
fn replace_number(text: &str, key: &str, value: &str) -> String {
    let start = text.find(key).unwrap_or_else(|| panic!("no `{key}` in the snapshot")) + key.len();
    let end = start + text[start..].find([',', ')', '\n']).unwrap();
    format!("{}{value}{}", &text[..start], &text[end..])
}

#[test]
fn a_corrupt_snapshot_is_a_typed_error_naming_the_field() {
    let good = pile_snapshot();
    Simulation::from_snapshot(good.clone()).unwrap();

    let mut nan = good.clone();
    nan.bodies[5].state.linear_velocity.x = f64::NAN;
    let error = restore_error(&nan);
    assert_eq!(field_of(&error), "bodies[5].state.linear_velocity", "{error}");

    let mut settings = good.clone();
    settings.settings.solver.tolerance = -1.0;
    match restore_error(&settings) {
        SnapshotError::Settings(e) => assert_eq!(e.field, "solver.tolerance"),
        other => panic!("{other}"),
    }

    let mut rough = good.clone();
    let segments = rough.bodies[4].spline.segment_count();
    let mut tolerances = vec![0.002; segments];
    tolerances[3] = -0.002;
    rough.bodies[4].rugosity = ron::from_str(&format!("(tolerances: {tolerances:?}, constant: None)")).unwrap();
    match restore_error(&rough) {
        SnapshotError::Body(e) => {
            assert_eq!(e.body.index, Some(4));
            assert!(matches!(e.reason, ShapeError::InvalidRugosity { segment: 3, .. }), "{e}");
        }
        other => panic!("{other}"),
    }

    let mut stranger = good.clone();
    let unknown = Entity::from_bits((u64::from(u32::MAX - 7) << 32) | 999).unwrap();
    stranger.excluded_pairs.push((stranger.bodies[0].entity, unknown));
    let error = restore_error(&stranger);
    assert_eq!(field_of(&error), "excluded_pairs[1]", "{error}");

    let mut twins = good.clone();
    twins.bodies[7].entity = twins.bodies[6].entity;
    assert_eq!(field_of(&restore_error(&twins)), "bodies[7].entity");

    let mut huge = good.clone();
    huge.bodies[3].entity = Entity::from_bits((1 << 52) | u64::from(u32::MAX - 1)).unwrap();
    assert_eq!(field_of(&restore_error(&huge)), "bodies[3].entity");

    let mut late = good.clone();
    late.accumulator = late.settings.time_step;
    assert_eq!(field_of(&restore_error(&late)), "accumulator");

    let mut asleep = good.clone();
    let BodyKind::Dynamic { sleep, .. } = &mut asleep.bodies[8].kind else { panic!("body 8 is dynamic") };
    sleep.still_for = f64::INFINITY;
    assert_eq!(field_of(&restore_error(&asleep)), "bodies[8].kind.sleep.still_for");

    // The step's memory, edited in the text: a negative warm-start force (the solver's clamp
    // would panic on it), a body slot out of range.
    let text = good.to_ron().unwrap();
    let negative = replace_number(&text, "normal_force: ", "-1.0");
    assert_eq!(field_of(&restore_text_error(&negative)), "step.contact_cache[0]");
    let far = text.replacen("candidate_pairs: [", "candidate_pairs: [(0, 999), ", 1);
    assert_eq!(field_of(&restore_text_error(&far)), "step.candidate_pairs[0]");
    let tilted = replace_number(&text, "normal: (", "0.5");
    assert!(field_of(&restore_text_error(&tilted)).starts_with("step.pairs["));
    // Where a pair was queried, and how far it has moved since (docs/model.md §3b).
    let backwards = replace_number(&text, "drift: (a: ", "-1.0");
    let field = field_of(&restore_text_error(&backwards)).to_owned();
    assert!(field.starts_with("step.pairs[") && field.ends_with("].drift"), "{field}");
    let lost = replace_number(&text, "margin: ", "inf");
    let field = field_of(&restore_text_error(&lost)).to_owned();
    assert!(field.starts_with("step.pairs[") && field.ends_with("].solved_at"), "{field}");
    // B's angle when a pair's contacts were last evaluated (their reuse turns normals from it).
    let spun = replace_number(&text, "evaluated_angle_b: Some(", "inf");
    let field = field_of(&restore_text_error(&spun)).to_owned();
    assert!(field.starts_with("step.pairs[") && field.ends_with("].evaluated_angle_b"), "{field}");
    // Where a pair's contacts were last evaluated again (its reuse skips motions below it).
    let stale = replace_number(&text, "reused_at: Some((((", "NaN");
    let field = field_of(&restore_text_error(&stale)).to_owned();
    assert!(field.starts_with("step.pairs[") && field.ends_with("].reused_at"), "{field}");
    // The bodies' poses at the last narrow phase (the next one measures their motion from them).
    let poses = text.find("phase_poses: [").expect("the snapshot keeps the poses of the last narrow phase");
    let first = poses + text[poses..].find("((").expect("a pose per body") + 2;
    let nowhere = format!("{}NaN{}", &text[..first], &text[first + text[first..].find(',').unwrap()..]);
    assert_eq!(field_of(&restore_text_error(&nowhere)), "step.phase_poses[0]");
    let one_more = text.replacen("phase_poses: [", "phase_poses: [((0.0, 0.0), 0.0),", 1);
    assert_eq!(field_of(&restore_text_error(&one_more)), "step.phase_poses");

    // Text that is not a snapshot.
    assert!(matches!(restore_text_error(&text[..text.len() / 2]), SnapshotError::Text(_)));
    let unknown_field = text.replacen("time:", "tiem:", 1);
    assert!(matches!(restore_text_error(&unknown_field), SnapshotError::Text(_)));
    let mut future = good;
    future.version = 2;
    assert_eq!(field_of(&restore_error(&future)), "version");
}

#[test]
fn a_body_broken_through_world_mut_cannot_be_saved() {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let (mut sim, handles) = scene(settings);
    sim.world_mut().remove_one::<rugosa::Sleep>(handles.rider).unwrap();
    match sim.snapshot() {
        Err(SnapshotError::Broken { body, reason }) => {
            assert_eq!(body.name.as_deref(), Some("rider"));
            assert!(reason.contains("Sleep"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_leaf_gap_of_an_older_snapshot_has_an_unknown_band() {
    // Before the approach depth was a setting, a leaf gap kept `half_band` (its approach then)
    // and no band. Such a snapshot restores: the band is unknown (NaN), so the pair is not
    // carried until its next query, and the simulation goes on; an infinite band is refused.
    // Two boxes 10.5 mm apart (bands of 5 mm) gliding side by side at 0.1 m/s without gravity: a
    // separate pair whose leaf gaps are listed and which, moving as one, is carried at every step.
    let settings = SimulationSettings { gravity: DVec2::ZERO, threads: 1, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    let boxed = |x: f64| {
        let spline = box_spline(1.0, 1.0, 0.1);
        let rugosity = Rugosity::constant(spline.segment_count(), 0.005).unwrap();
        let desc = BodyDesc::new(spline, rugosity).with_material(material(0.5, FrictionLaw::default()));
        desc.at(DVec2::new(x, 0.0), 0.0).with_velocity(DVec2::new(0.0, 0.1), 0.0)
    };
    sim.add_body(boxed(0.0)).unwrap();
    sim.add_body(boxed(1.0105)).unwrap();
    for _ in 0..3 {
        sim.step(DT);
    }
    let text = sim.snapshot().unwrap().to_ron().unwrap();
    let gaps = text.matches(", band: ").count();
    assert!(gaps > 0 && text.matches("approach: ").count() == gaps, "the snapshot keeps leaf gaps");
    let mut older = String::new();
    let mut rest = text.as_str();
    while let Some(at) = rest.find(", band: ") {
        older.push_str(&rest[..at]);
        let after = &rest[at + ", band: ".len()..];
        rest = &after[after.find([',', ')']).unwrap()..];
    }
    older.push_str(rest);
    let older = older.replace("approach: ", "half_band: ");
    let carried_in_first_step = |text: &str| {
        let mut sim = Snapshot::from_ron(text).and_then(Simulation::from_snapshot).unwrap();
        sim.step(DT);
        (sim.profile().counters.carried_pairs, sim)
    };
    let (now, _) = carried_in_first_step(&text);
    let (then, mut sim) = carried_in_first_step(&older);
    assert_eq!((now, then), (1, 0), "pairs carried in the first step with their bands and with unknown bands");
    for _ in 0..30 {
        sim.step(DT);
    }
    sim.validate().unwrap();
    let wide = replace_number(&text, ", band: ", "inf");
    let field = field_of(&restore_text_error(&wide)).to_owned();
    assert!(field.starts_with("step.pairs[") && field.contains("].manifold.gaps["), "{field}");
}
