//! Generates `docs/performance.md`: the body-pair query against segment count, the step time
//! per stage for piles of blobs with 1 and 2 threads, and what sleeping saves on a settled
//! pyramid. Medians from one run.
//!
//! Run: `cargo run --release --example performance_report` (add `-- --quick` for a short run,
//! `-- --only-query` or `-- --only-pile` for one table; these print without writing the file;
//! `-- --help` lists the flags that print a single row for profiling).

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/common/pile.rs"]
mod pile;
#[path = "../tests/common/stress_cases.rs"]
mod stress_cases;

use std::alloc::System;
use std::fmt::Write as _;
use std::time::{Duration, Instant};

use clap::Parser;
use glam::DVec2;
use rugosa::report::median;
use rugosa::{
    AobbTree, BodyQuery, BodyShape, Generator, Material, Pose, QuerySettings, Rugosity, Simulation, SimulationSettings,
    SleepSettings, Spline, Stage, query_bodies,
};
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

/// Counts the heap the pile table's simulations hold; steady stepping allocates nothing
/// (tests/allocation.rs), so the count costs the timed steps nothing.
#[global_allocator]
static ALLOCATOR: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

const BAND: f64 = 0.01;
/// A median of nothing: zero steps or repeats were asked for.
const NO_SAMPLES: &str = "a median needs at least one timed step or pass";

/// Generate the body-pair query, pile and sleeping tables of docs/performance.md (medians from one run).
///
/// A flag that prints a single row or writes the snapshot does only that (for profiling).
#[derive(Parser, Debug)]
struct Args {
    /// A short run: fewer sizes and steps; prints the tables without writing the file.
    #[arg(long)]
    quick: bool,
    /// Only the body-pair query table; prints it without writing the file.
    #[arg(long)]
    only_query: bool,
    /// Only the pile tables (the snapshot, the pile and sleeping); prints them without writing the file.
    #[arg(long)]
    only_pile: bool,
    /// Write the snapshot assets/bench/pile-100-step-120.ron (the 100-blob pile at step 120) and exit.
    #[arg(long, group = "single")]
    write_snapshot: bool,
    /// Write the snapshot assets/bench/pyramid-210-settled.ron (the settled pyramid, awake) and exit.
    /// Each fixed workload is written on its own, so renewing one keeps the other comparable.
    #[arg(long, group = "single")]
    write_pyramid_snapshot: bool,
    /// Print the snapshot's query over all pairs (median of REPEATS passes) and exit.
    #[arg(long, value_name = "REPEATS", group = "single")]
    snapshot_query: Option<usize>,
    /// Step the snapshot STEPS times, print its pile-table row and exit (for callgrind).
    #[arg(long, value_name = "STEPS", group = "single")]
    snapshot_steps: Option<usize>,
    /// Step the settled pyramid STEPS times awake, print its pile-table row and exit (for callgrind).
    #[arg(long, value_name = "STEPS", group = "single")]
    pyramid_steps: Option<usize>,
    /// Step the pyramid snapshot STEPS times (sleeping off), print its pile-table row and exit
    /// (for callgrind: the same settled contacts for every version of the engine).
    #[arg(long, value_name = "STEPS", group = "single")]
    pyramid_snapshot_steps: Option<usize>,
    /// With `--pyramid-steps`: first step the woken pyramid SETTLE times unmeasured (it goes to
    /// sleep below 0.05 m/s, so right after waking it still settles; after 1500 steps its
    /// contacts barely move).
    #[arg(long, value_name = "SETTLE", default_value_t = 0, requires = "pyramid_steps")]
    pyramid_settle: usize,
    /// Print one row of the pile table: N blobs, THREADS threads, WARMUP settling steps, STEPS
    /// measured steps; then exit.
    #[arg(long, value_name = "N,THREADS,WARMUP,STEPS", value_parser = pile_spec, group = "single")]
    pile: Option<[usize; 4]>,
}

/// The four numbers of `--pile N,THREADS,WARMUP,STEPS`.
fn pile_spec(text: &str) -> Result<[usize; 4], String> {
    let numbers: Vec<usize> = text.split(',').map(str::parse).collect::<Result<_, _>>().map_err(|e| format!("{e}"))?;
    numbers.try_into().map_err(|_| "expected four numbers, N,THREADS,WARMUP,STEPS".to_owned())
}

fn main() {
    let args = Args::parse();
    if args.write_snapshot {
        write_snapshot();
        return;
    }
    if args.write_pyramid_snapshot {
        write_pyramid_snapshot();
        return;
    }
    if let Some(repeats) = args.snapshot_query {
        println!("{}", snapshot_query(repeats).line());
        return;
    }
    if let Some(steps) = args.snapshot_steps {
        let mut sim = snapshot_simulation();
        print!("{}", format_pile_row(100, 1, steps, &measure_steps(&mut sim, steps)));
        return;
    }
    if let Some(steps) = args.pyramid_snapshot_steps {
        let mut sim = pyramid_snapshot_simulation();
        print!("{}", format_pile_row(210, 1, steps, &measure_steps(&mut sim, steps)));
        return;
    }
    if let Some(steps) = args.pyramid_steps {
        let (mut scenario, _, _) = settled_pyramid(false);
        scenario.sim.set_sleep(SleepSettings::off()).expect("sleep off");
        for _ in 0..args.pyramid_settle {
            scenario.sim.step(scenario.sim.settings().time_step);
        }
        print!("{}", format_pile_row(210, 1, steps, &measure_steps(&mut scenario.sim, steps)));
        return;
    }
    if let Some([count, threads, warmup, steps]) = args.pile {
        print!("{}", format_pile_row(count, threads, steps, &measure_pile(count, threads, warmup, steps)));
        return;
    }
    let quick = args.quick;
    let (query, pile) = match (args.only_query, args.only_pile) {
        (false, false) => (true, true),
        selected => selected,
    };
    let mut doc = String::new();
    writeln!(
        doc,
        "Generated by `cargo run --release --example performance_report` (medians from one run). \
         Machine: {}.\n",
        rugosa::report::machine_description()
    )
    .unwrap();
    if query {
        doc.push_str(&query_table(quick));
    }
    if pile {
        doc.push_str(&snapshot_table(quick));
        doc.push_str(&pile_table(quick));
        doc.push_str(&sleeping_table(quick));
    }
    print!("{doc}");
    if !quick && query && pile {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/performance.md");
        let existing = std::fs::read_to_string(path).unwrap_or_else(|_| "# Performance\n".to_owned());
        std::fs::write(path, replace_section(&existing, &doc)).expect("write docs/performance.md");
        eprintln!("wrote its section of docs/performance.md");
    }
}

/// Markers of the part of `docs/performance.md` this command writes; the rest of the file
/// (other commands' sections, the optimisation log) is kept as it is.
const BEGIN: &str = "<!-- performance-report:begin -->";
const END: &str = "<!-- performance-report:end -->";

/// `existing` with its marked section replaced by `section` (inserted after the title if absent).
fn replace_section(existing: &str, section: &str) -> String {
    let marked = format!("{BEGIN}\n{}\n{END}", section.trim_end());
    match (existing.find(BEGIN), existing.find(END)) {
        (Some(begin), Some(end)) if end > begin => {
            format!("{}{marked}{}", &existing[..begin], &existing[end + END.len()..])
        }
        _ => {
            let title_end = existing.find('\n').map_or(existing.len(), |k| k + 1);
            format!("{}\n{marked}\n\n{}", &existing[..title_end], &existing[title_end..])
        }
    }
}

// ---------------------------------------------------------------- body-pair query

struct Body {
    spline: Spline,
    rugosity: Rugosity,
    tree: AobbTree,
}

fn blob(segments: usize, seed: u64) -> Body {
    let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed }.build(segments).unwrap();
    let rugosity = Rugosity::constant(segments, BAND).unwrap();
    let tree = AobbTree::build(&spline, &rugosity, QuerySettings::default().min_band);
    Body { spline, rugosity, tree }
}

/// Smallest distance between the two curves (B translated by `offset`), from 2048 samples of A
/// and the exact nearest point on B.
fn curve_distance(a: &Spline, b: &Spline, offset: DVec2) -> f64 {
    let samples = 2048;
    (0..samples)
        .map(|k| {
            let p = a.position(k as f64 * a.segment_count() as f64 / samples as f64) - offset;
            b.nearest_point(p).distance
        })
        .fold(f64::INFINITY, f64::min)
}

/// Offset along x at which the curves are `target` apart (bisection).
fn place(a: &Spline, b: &Spline, target: f64) -> DVec2 {
    let (mut near, mut far) = (0.0, 5.0);
    for _ in 0..40 {
        let mid = 0.5 * (near + far);
        if curve_distance(a, b, DVec2::new(mid, 0.0)) < target {
            near = mid;
        } else {
            far = mid;
        }
    }
    DVec2::new(far, 0.0)
}

fn query_table(quick: bool) -> String {
    let mut out = String::new();
    writeln!(out, "## Body-pair query against segment count\n").unwrap();
    writeln!(
        out,
        "Two random blobs (radius 1 m, roughness 0.5) with a constant band of {BAND} m each. *Near miss*: \
         the curves {} m apart (bands 0.02 m clear of each other); *touching*: the curves {} m apart \
         (0.005 m into the combined band). Time is the median of repeated `query_bodies` calls.\n",
        2.0 * BAND + 0.02,
        2.0 * BAND - 0.005
    )
    .unwrap();
    writeln!(out, "| segments | case | time µs | box tests | leaf pairs | contacts | Newton iterations / contact |")
        .unwrap();
    writeln!(out, "|---:|---|---:|---:|---:|---:|---:|").unwrap();
    let counts: &[usize] = if quick { &[16, 64] } else { &[16, 64, 256, 1024] };
    for &segments in counts {
        let a = blob(segments, 1);
        let b = blob(segments, 2);
        for (case, gap) in [("near miss", 2.0 * BAND + 0.02), ("touching", 2.0 * BAND - 0.005)] {
            let offset = place(&a.spline, &b.spline, gap);
            let row = measure_query(&a, &b, Pose::new(offset, 0.0));
            writeln!(
                out,
                "| {segments} | {case} | {:.2} | {} | {} | {} | {} |",
                row.time.as_secs_f64() * 1e6,
                row.box_tests,
                row.leaf_pairs,
                row.contacts,
                if row.contacts > 0 { format!("{:.1}", row.newton as f64 / row.contacts as f64) } else { "–".into() }
            )
            .unwrap();
        }
    }
    out.push('\n');
    out
}

struct QueryRow {
    time: Duration,
    box_tests: usize,
    leaf_pairs: usize,
    contacts: usize,
    newton: u64,
}

fn measure_query(a: &Body, b: &Body, pose_b: Pose) -> QueryRow {
    let settings = QuerySettings::default();
    let shape_a = BodyShape::new(&a.spline, &a.rugosity);
    let shape_b = BodyShape::new(&b.spline, &b.rugosity);
    let mut query = BodyQuery::default();
    let mut run = || {
        let start = Instant::now();
        query_bodies(&shape_a, &a.tree, &Pose::IDENTITY, &shape_b, &b.tree, &pose_b, &settings, &mut query);
        start.elapsed()
    };
    run();
    let samples: Vec<Duration> = (0..201).map(|_| run()).collect();
    QueryRow {
        time: median(samples).expect(NO_SAMPLES),
        box_tests: query.counters.box_tests,
        leaf_pairs: query.counters.leaf_pairs,
        contacts: query.manifold.contacts.len(),
        newton: query.manifold.newton_iterations,
    }
}

// ---------------------------------------------------------------- blob pile

/// The blob pile of `tests/common/pile.rs`, `count` blobs in a square-ish grid.
fn pile(count: usize, threads: usize) -> Simulation {
    let settings = SimulationSettings {
        threads,
        record_events: false,
        sleep: SleepSettings::off(),
        ..SimulationSettings::default()
    };
    let mut sim = Simulation::new(settings).unwrap();
    for body in pile::blob_pile(count, pile::square_columns(count)) {
        sim.add_body(body).unwrap();
    }
    sim
}

struct PileRow {
    stages: Vec<Duration>,
    step: Duration,
    counters: rugosa::StepCounters,
}

fn measure_pile(count: usize, threads: usize, warmup: usize, steps: usize) -> PileRow {
    let mut sim = settled_pile(count, threads, warmup);
    measure_steps(&mut sim, steps)
}

/// What `make` returns, and the heap it left allocated (MB): what the value holds, when `make`
/// frees all else it allocated.
fn held_heap<T>(make: impl FnOnce() -> T) -> (T, f64) {
    let region = Region::new(ALLOCATOR);
    let value = make();
    let change = region.change();
    let held = change.bytes_allocated as f64 - change.bytes_deallocated as f64 + change.bytes_reallocated as f64;
    (value, held / 1e6)
}

/// The pile after `warmup` steps.
fn settled_pile(count: usize, threads: usize, warmup: usize) -> Simulation {
    let mut sim = pile(count, threads);
    let dt = sim.settings().time_step;
    let started = Instant::now();
    for k in 0..warmup {
        sim.step(dt);
        if k % 30 == 29 {
            eprintln!(
                "pile {count} × {threads} threads: settling step {} ({:.1} s)",
                k + 1,
                started.elapsed().as_secs_f64()
            );
        }
    }
    sim.take_profile();
    sim
}

/// Median step and stage times over `steps` steps, with the counters summed (under callgrind:
/// `--toggle-collect='*measure_steps*'` counts only the steps).
#[inline(never)]
fn measure_steps(sim: &mut Simulation, steps: usize) -> PileRow {
    sim.take_profile();
    let mut samples = StepSamples::default();
    for _ in 0..steps {
        samples.step(sim);
    }
    samples.row()
}

/// Per-step times and counters of one simulation.
#[derive(Default)]
struct StepSamples {
    per_stage: Vec<Vec<Duration>>,
    per_step: Vec<Duration>,
    counters: rugosa::StepCounters,
}

impl StepSamples {
    /// Times one step of `sim` and records its profile.
    fn step(&mut self, sim: &mut Simulation) {
        let start = Instant::now();
        sim.step(sim.settings().time_step);
        self.per_step.push(start.elapsed());
        let profile = sim.take_profile();
        self.per_stage.resize(Stage::ALL.len(), Vec::new());
        for (k, stage) in Stage::ALL.iter().enumerate() {
            self.per_stage[k].push(profile.time(*stage));
        }
        self.counters.accumulate(&profile.counters);
    }

    fn row(self) -> PileRow {
        PileRow {
            stages: self.per_stage.into_iter().map(|samples| median(samples).expect(NO_SAMPLES)).collect(),
            step: median(self.per_step).expect(NO_SAMPLES),
            counters: self.counters,
        }
    }
}

// ---------------------------------------------------------------- sleeping

/// The stress cases' pyramid (base 20, 210 rounded boxes; base 5 with `quick`), one thread,
/// stepped with sleeping on until every box sleeps (at most 1200 steps): the scenario, its
/// boxes and the steps it took. `--pyramid-steps N` steps it N times awake and prints the
/// pile row (for callgrind: N = 1 and 5).
fn settled_pyramid(quick: bool) -> (stress_cases::Scenario, usize, usize) {
    let size = if quick { stress_cases::Size::Ci } else { stress_cases::Size::Full };
    let mut scenario = (stress_cases::case("pyramid").build)(size);
    // The full-size stress cases use every core; this table is one thread (a restored snapshot
    // goes on bit for bit, so the round trip only sets the thread count).
    let mut snapshot = scenario.sim.snapshot().expect("snapshot of the pyramid");
    snapshot.settings.threads = 1;
    scenario.sim = Simulation::from_snapshot(snapshot).expect("restore the pyramid on one thread");
    let sim = &mut scenario.sim;
    sim.set_sleep(SleepSettings::default()).expect("default sleep settings");
    let boxes = sim.bodies().filter(|&e| sim.world().get::<&rugosa::Static>(e).is_err()).count();
    let mut settle = 0;
    while settle < 1200 && sim.bodies().any(|e| sim.world().get::<&rugosa::Static>(e).is_err() && !sim.is_sleeping(e)) {
        sim.step(sim.settings().time_step);
        settle += 1;
    }
    (scenario, boxes, settle)
}

/// The settled pyramid timed asleep, then woken (sleeping off) and timed awake at the same
/// settled poses.
fn sleeping_table(quick: bool) -> String {
    let (mut scenario, boxes, settle) = settled_pyramid(quick);
    let sim = &mut scenario.sim;
    let asleep = measure_steps(sim, if quick { 10 } else { 60 });
    sim.set_sleep(SleepSettings::off()).expect("sleep off");
    let awake = measure_steps(sim, if quick { 3 } else { 20 });
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut out = String::from(
        "\n## Sleeping: a settled pyramid\n\nThe stress cases' pyramid of rounded boxes (`tests/common/stress_cases.rs`), one thread, \
         stepped with sleeping on (`SleepSettings::default()`: still below 0.05 m/s for 0.5 s) until every box sleeps, then \
         the median step time asleep and, after `set_sleep(SleepSettings::off())` wakes it, awake at the same settled poses. \
         Asleep, a step only checks each body's sleep state: no stage runs.\n\n\
         | boxes | steps until all asleep | asleep: step ms | awake: step ms | awake / asleep |\n|---:|---:|---:|---:|---:|\n",
    );
    writeln!(
        out,
        "| {boxes} | {settle} | {:.4} | {:.2} | {:.0}× |",
        ms(asleep.step),
        ms(awake.step),
        awake.step.as_secs_f64() / asleep.step.as_secs_f64().max(1e-12)
    )
    .unwrap();
    out
}

// ---------------------------------------------------------------- a fixed narrow-phase workload

/// The pile of 100 blobs at step 120 of its landing (after `--write-snapshot`): a fixed set of
/// resting and colliding contacts, the same for every version of the solver.
const SNAPSHOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bench/pile-100-step-120.ron");
const SNAPSHOT_STEP: usize = 120;

/// The settled pyramid of the sleeping table, woken and stepped [`PYRAMID_SETTLE`] more steps
/// awake (after `--write-pyramid-snapshot`): a fixed set of resting flat-on-flat contacts.
const PYRAMID_SNAPSHOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bench/pyramid-210-settled.ron");
const PYRAMID_SETTLE: usize = 1500;

/// Runs the 100-blob pile for [`SNAPSHOT_STEP`] steps and writes it as a scene file.
fn write_snapshot() {
    let mut sim = pile(100, 1);
    for _ in 0..SNAPSHOT_STEP {
        sim.step(sim.settings().time_step);
    }
    let header = format!(
        "// The pile of 100 blobs of `performance_report` at step {SNAPSHOT_STEP} of its landing: a fixed\n\
         // narrow-phase workload. Regenerate: cargo run --release --example performance_report -- --write-snapshot\n"
    );
    write_scene(&sim, SNAPSHOT, &header);
}

/// Settles the pyramid, wakes it, steps it [`PYRAMID_SETTLE`] times and writes the simulation's
/// own snapshot.
fn write_pyramid_snapshot() {
    let (mut scenario, _, _) = settled_pyramid(false);
    scenario.sim.set_sleep(SleepSettings::off()).expect("sleep off");
    for _ in 0..PYRAMID_SETTLE {
        scenario.sim.step(scenario.sim.settings().time_step);
    }
    // The simulation's own snapshot, not a scene: it keeps the contacts' warm-start forces and the
    // leaf pairs' memories, so the steps from it are those of the settled pyramid, bit for bit.
    let snapshot = scenario.sim.snapshot().expect("snapshot of the pyramid");
    write_file(PYRAMID_SNAPSHOT, &snapshot.to_ron().expect("serialize the pyramid snapshot"));
}

/// Writes a snapshot file, creating assets/bench if needed.
fn write_file(path: &str, text: &str) {
    std::fs::create_dir_all(std::path::Path::new(path).parent().unwrap()).expect("create assets/bench");
    std::fs::write(path, text).expect("write snapshot");
    eprintln!("wrote {path}");
}

/// Writes the simulation's state as a scene file (body-frame control points, tolerances,
/// centre-of-mass poses and velocities) behind `header`.
fn write_scene(sim: &Simulation, path: &str, header: &str) {
    let bodies: Vec<rugosa::BodyScene> = sim
        .bodies()
        .map(|entity| {
            let world = sim.world();
            let body = world.entity(entity).unwrap();
            let state = *body.get::<&rugosa::RigidState>().unwrap();
            rugosa::BodyScene {
                name: None,
                shape: rugosa::ShapeScene::ControlPoints(body.get::<&Spline>().unwrap().control_points().to_vec()),
                rugosity: rugosa::RugosityScene::Values(body.get::<&Rugosity>().unwrap().tolerances().to_vec()),
                material: *body.get::<&Material>().unwrap(),
                is_static: body.has::<rugosa::Static>(),
                position: state.position,
                angle: state.angle,
                velocity: state.linear_velocity,
                angular_velocity: state.angular_velocity,
                motion: body.get::<&rugosa::Motion>().map(|m| *m).unwrap_or_default(),
                groups: body.get::<&rugosa::CollisionGroups>().map(|g| *g).unwrap_or_default(),
                sensor: body.has::<rugosa::Sensor>(),
                kinematic: body.has::<rugosa::Kinematic>(),
            }
        })
        .collect();
    let scene = rugosa::Scene { settings: sim.settings().clone(), duration: 1.0, bodies, origin: String::new() };
    let text = ron::ser::to_string_pretty(&scene, ron::ser::PrettyConfig::default()).expect("serialize snapshot");
    write_file(path, &(header.to_owned() + &text));
}

/// Time and work of the body-pair query over every pair of the snapshot.
struct SnapshotRow {
    per_pass: Duration,
    pairs: usize,
    leaf_pairs: usize,
    contacts: usize,
    newton_iterations: u64,
}

impl SnapshotRow {
    fn line(&self) -> String {
        format!(
            "snapshot: {:.3} ms per pass over all pairs; {} pairs in contact, {} leaf pairs, {} contacts, {} Newton iterations",
            self.per_pass.as_secs_f64() * 1e3,
            self.pairs,
            self.leaf_pairs,
            self.contacts,
            self.newton_iterations
        )
    }
}

/// Queries every body pair of the snapshot `repeats` times (one thread); median pass time.
fn snapshot_query(repeats: usize) -> SnapshotRow {
    let scene = rugosa::Scene::load(SNAPSHOT).expect("load the snapshot (run --write-snapshot)");
    let settings = QuerySettings { min_band: scene.settings.min_band, ..QuerySettings::default() };
    let bodies: Vec<(Body, Pose)> = scene
        .body_descs()
        .expect("snapshot bodies")
        .into_iter()
        .map(|desc| {
            let tree = AobbTree::build(&desc.spline, &desc.rugosity, settings.min_band);
            let pose = Pose::new(desc.position, desc.angle);
            (Body { spline: desc.spline, rugosity: desc.rugosity, tree }, pose)
        })
        .collect();
    let mut query = BodyQuery::default();
    let mut passes = Vec::new();
    let mut row = SnapshotRow { per_pass: Duration::ZERO, pairs: 0, leaf_pairs: 0, contacts: 0, newton_iterations: 0 };
    for _ in 0..repeats {
        let started = Instant::now();
        row = query_all_pairs(&bodies, &settings, &mut query);
        passes.push(started.elapsed());
    }
    row.per_pass = median(passes).expect(NO_SAMPLES);
    row
}

/// One pass of the body-pair query over every pair (under callgrind:
/// `--toggle-collect='*query_all_pairs*'` counts only this).
#[inline(never)]
fn query_all_pairs(bodies: &[(Body, Pose)], settings: &QuerySettings, query: &mut BodyQuery) -> SnapshotRow {
    let mut row = SnapshotRow { per_pass: Duration::ZERO, pairs: 0, leaf_pairs: 0, contacts: 0, newton_iterations: 0 };
    for (i, (a, pose_a)) in bodies.iter().enumerate() {
        for (b, pose_b) in &bodies[i + 1..] {
            let shape_a = BodyShape::new(&a.spline, &a.rugosity);
            let shape_b = BodyShape::new(&b.spline, &b.rugosity);
            let manifold = query_bodies(&shape_a, &a.tree, pose_a, &shape_b, &b.tree, pose_b, settings, query);
            row.pairs += usize::from(!manifold.contacts.is_empty());
            row.contacts += manifold.contacts.len();
            row.newton_iterations += manifold.newton_iterations;
            row.leaf_pairs += query.counters.leaf_pairs;
        }
    }
    row
}

/// The pile snapshot's simulation, one thread, sleeping off (the workload is its contacts).
fn snapshot_simulation() -> Simulation {
    let mut scene = rugosa::Scene::load(SNAPSHOT).expect("load the snapshot (run --write-snapshot)");
    scene.settings.sleep = SleepSettings::off();
    scene.settings.threads = 1;
    scene.build().expect("snapshot scene")
}

/// The fixed workload: the query over every pair of the snapshot, and steps from it.
fn snapshot_table(quick: bool) -> String {
    let (repeats, steps) = if quick { (3, 5) } else { (11, 30) };
    let query = snapshot_query(repeats);
    let mut sim = snapshot_simulation();
    let row = measure_steps(&mut sim, steps);
    let mut out = String::new();
    writeln!(out, "## A fixed workload: the pile of 100 blobs at step {SNAPSHOT_STEP}\n").unwrap();
    writeln!(
        out,
        "`assets/bench/pile-100-step-{SNAPSHOT_STEP}.ron` holds the pile below at step {SNAPSHOT_STEP} of its landing \
         (written by `-- --write-snapshot`), so that every version of the engine is measured on the same \
         contacts. The body-pair query over all {} pairs (median of {repeats} passes): **{:.2} ms** per pass, \
         {} pairs in contact, {} leaf pairs, {} contacts, {} Newton iterations. {steps} steps from the \
         snapshot, one thread (µs, medians; counters per step):\n",
        103 * 102 / 2,
        query.per_pass.as_secs_f64() * 1e3,
        query.pairs,
        query.leaf_pairs,
        query.contacts,
        query.newton_iterations
    )
    .unwrap();
    out.push_str(&pile_header());
    out.push_str(&format_pile_row(100, 1, steps, &row));
    writeln!(
        out,
        "\nUnder callgrind (instructions, repeatable on a loaded machine): \
         `valgrind --tool=callgrind --toggle-collect='*measure_steps*' target/release/examples/performance_report \
         --snapshot-steps N` for N = 1 and 5 (or 15); the difference over the steps between is the instructions per step.\n"
    )
    .unwrap();
    let mut sim = pyramid_snapshot_simulation();
    let row = measure_steps(&mut sim, steps);
    writeln!(
        out,
        "The settled pyramid of the sleeping table below, woken and stepped {PYRAMID_SETTLE} times awake, is the \
         second fixed workload: `assets/bench/pyramid-210-settled.ron` is the engine's own snapshot of it \
         (`Simulation::snapshot`, written by `-- --write-pyramid-snapshot`), so its contacts' warm-start forces and leaf \
         memories come with it and the steps from it are those of the settled pyramid, bit for bit. {steps} steps, \
         one thread (`--pyramid-snapshot-steps N` under callgrind as above):\n"
    )
    .unwrap();
    out.push_str(&pile_header());
    out.push_str(&format_pile_row(210, 1, steps, &row));
    out
}

/// The pyramid snapshot's simulation, one thread (its settings keep sleeping off).
fn pyramid_snapshot_simulation() -> Simulation {
    let text =
        std::fs::read_to_string(PYRAMID_SNAPSHOT).expect("read the pyramid snapshot (run --write-pyramid-snapshot)");
    let mut snapshot = rugosa::Snapshot::from_ron(&text).expect("pyramid snapshot");
    snapshot.settings.threads = 1;
    Simulation::from_snapshot(snapshot).expect("restore the pyramid snapshot")
}

fn pile_header() -> String {
    let mut out = String::from("| N | threads |");
    for stage in Stage::ALL {
        write!(out, " {} |", stage.name()).unwrap();
    }
    writeln!(
        out,
        " step | sub-steps | pairs | leaf pairs | recalled | contacts | Newton iterations | impulses | micro |"
    )
    .unwrap();
    writeln!(out, "|---:|---:|{}---:|---:|---:|---:|---:|---:|---:|---:|---:|", "---:|".repeat(Stage::ALL.len()))
        .unwrap();
    out
}

fn format_pile_row(count: usize, threads: usize, steps: usize, row: &PileRow) -> String {
    let mut out = format!("| {count} | {threads} |");
    for t in &row.stages {
        write!(out, " {:.0} |", t.as_secs_f64() * 1e6).unwrap();
    }
    let per = |v: u64| v as f64 / steps as f64;
    writeln!(
        out,
        " {:.0} | {:.2} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} |",
        row.step.as_secs_f64() * 1e6,
        per(row.counters.substeps),
        per(row.counters.candidate_pairs),
        per(row.counters.leaf_pairs),
        per(row.counters.recalled_leaf_pairs),
        per(row.counters.contacts),
        per(row.counters.newton_iterations),
        per(row.counters.impulses),
        per(row.counters.micro_collisions)
    )
    .unwrap();
    out
}

fn pile_table(quick: bool) -> String {
    let mut out = String::new();
    let (warmup, steps) = if quick { (30, 10) } else { (120, 30) };
    writeln!(out, "## Step time per stage: a pile of blobs\n").unwrap();
    writeln!(
        out,
        "N blobs (16 segments, radius 0.1 m, band 2 mm) dropped into a static box, step 1/120 s; \
         {warmup} steps of settling, then the median over {steps} steps of each stage's time (µs). \
         Counters are per step, averaged over the measured steps; *recalled*: leaf pairs answered from \
         their memory (temporal coherence, docs/model.md §3a) instead of a search.\n"
    )
    .unwrap();
    out.push_str(&pile_header());
    let sizes: &[usize] = if quick { &[100] } else { &[100, 500] };
    let mut speedups = Vec::new();
    let mut heaps = Vec::new();
    for &count in sizes {
        // The two simulations are the same pile (the engine is deterministic for any thread
        // count) and step in turn, so the machine's noise falls on both alike.
        let (one, one_heap) = held_heap(|| settled_pile(count, 1, warmup));
        let (two, two_heap) = held_heap(|| settled_pile(count, 2, warmup));
        heaps.push((count, one_heap, two_heap));
        let mut sims = [one, two];
        let mut samples = [StepSamples::default(), StepSamples::default()];
        for _ in 0..steps {
            for (sim, samples) in sims.iter_mut().zip(&mut samples) {
                samples.step(sim);
            }
        }
        let [one, two] = samples.map(StepSamples::row);
        out.push_str(&format_pile_row(count, 1, steps, &one));
        out.push_str(&format_pile_row(count, 2, steps, &two));
        let c = &one.counters;
        let push_out = (c.push_out_sweeps as f64 / steps as f64, c.push_out_unconverged);
        speedups.push((count, one.step.as_secs_f64() / two.step.as_secs_f64(), push_out));
    }
    writeln!(out).unwrap();
    for (count, speedup, (sweeps, capped)) in speedups {
        writeln!(
            out,
            "- N = {count}: 2-thread speedup of the whole step {speedup:.2}×; the push-out swept {sweeps:.1} \
             times a step (its largest island), and stopped at its cap in {capped} sub-steps of the {steps} steps."
        )
        .unwrap();
    }
    for (count, one, two) in heaps {
        writeln!(
            out,
            "- N = {count}: heap the simulation holds after its {warmup} steps of settling, {one:.1} MB on one \
             thread, {two:.1} MB on two."
        )
        .unwrap();
    }
    writeln!(
        out,
        "\nThe one- and two-thread simulations of a size step in turn (the same pile: results are \
         bit-identical for any thread count), so the machine's noise falls on both alike."
    )
    .unwrap();
    out
}
