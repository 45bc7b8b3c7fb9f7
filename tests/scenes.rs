//! Scenes: every shipped scene loads and runs; malformed scenes give the documented errors;
//! the CSV outputs parse with their headers; the Figure-8 scenes show the friction they should.
#![cfg(all(feature = "scene", feature = "report"))]

use std::path::{Path, PathBuf};
use std::time::Instant;

use rugosa::report::{EVENT_COLUMNS, Recording, STATE_COLUMNS};
use rugosa::{BodyDesc, EventKind, Generator, Rugosity, Scene, SceneError, Simulation, SimulationSettings};

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes");
const STEPS: usize = 200;

fn scene_paths() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(SCENES)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    paths.sort();
    paths
}

/// Runs `steps` steps of the scene at `path`, recording every step.
fn run(path: &Path, steps: usize) -> Recording {
    let scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let mut recording = Recording::new(&sim, 1);
    for _ in 0..steps {
        sim.step(sim.settings().time_step);
        recording.record_step(&mut sim);
    }
    sim.validate().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    recording
}

#[test]
fn every_scene_loads_and_runs_200_steps_with_finite_states() {
    let paths = scene_paths();
    assert!(paths.len() >= 9, "expected the shipped scenes in {SCENES}, found {paths:?}");
    for path in paths {
        let start = Instant::now();
        let recording = run(&path, STEPS);
        let name = path.file_name().unwrap().to_string_lossy();
        println!("{name}: {:.2} s, {} events", start.elapsed().as_secs_f64(), recording.events.len());
        assert!(recording.states.iter().all(|s| s.state.is_finite()), "{name}: non-finite state");
        assert!(!recording.events.is_empty(), "{name}: no contact in {STEPS} steps");
    }
}

fn impulse_mus(recording: &Recording) -> Vec<f64> {
    recording.events.iter().map(|e| e.event.mu).collect()
}

#[test]
fn constant_rugosity_gives_one_friction_coefficient_and_random_rugosity_many() {
    let constant = impulse_mus(&run(&Path::new(SCENES).join("fig8-type1-type1.ron"), STEPS));
    let first = constant[0];
    assert!(first > 0.0, "the constant scene should have friction, got μ = {first}");
    assert!(constant.iter().all(|&mu| (mu - first).abs() < 1e-12), "μ varies on constant rugosity: {constant:?}");

    let random = impulse_mus(&run(&Path::new(SCENES).join("fig8-type3-type3.ron"), STEPS));
    let (low, high) = random.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &m| (l.min(m), h.max(m)));
    assert!(high - low > 0.05, "μ barely varies on random rugosity: {low}..{high} over {} events", random.len());
}

/// The rows of a CSV file whose header is `columns` (the reader rejects rows of another width).
fn parse_csv(path: &Path, columns: &[&str]) -> Vec<csv::StringRecord> {
    let mut reader = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(reader.headers().unwrap(), columns);
    reader.records().map(|row| row.unwrap_or_else(|e| panic!("{}: {e}", path.display()))).collect()
}

fn column<'a>(rows: &'a [csv::StringRecord], columns: &[&str], name: &str) -> impl Iterator<Item = &'a str> {
    let index = columns.iter().position(|c| *c == name).unwrap();
    rows.iter().map(move |row| &row[index])
}

#[test]
fn csv_outputs_parse_with_their_headers() {
    let recording = run(&Path::new(SCENES).join("fig8-type2-type3.ron"), 60);
    let dir = std::env::temp_dir().join(format!("rugosa-scenes-csv-{}", std::process::id()));
    recording.write_csv_files(&dir).unwrap();

    let events = parse_csv(&dir.join("events.csv"), &EVENT_COLUMNS);
    assert_eq!(events.len(), recording.events.len());
    for name in ["time", "mu", "point_x", "impulse_y", "lambda_a"] {
        assert!(column(&events, &EVENT_COLUMNS, name).all(|v| v.parse::<f64>().is_ok_and(f64::is_finite)), "{name}");
    }
    let kinds: Vec<&str> = EventKind::ALL.iter().map(|k| k.name()).collect();
    assert!(column(&events, &EVENT_COLUMNS, "kind").all(|k| kinds.contains(&k)));
    assert!(column(&events, &EVENT_COLUMNS, "body_a").all(|b| b == "circle" || b == "block"));

    let states = parse_csv(&dir.join("states.csv"), &STATE_COLUMNS);
    assert_eq!(states.len(), 2 * 61, "two bodies, initial state and 60 steps");
    for name in STATE_COLUMNS.iter().filter(|c| **c != "body") {
        assert!(column(&states, &STATE_COLUMNS, name).all(|v| v.parse::<f64>().is_ok_and(f64::is_finite)), "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn body_names_with_commas_quotes_and_line_breaks_survive_the_csv_files() {
    let name = "a \"round\", disc\nline two";
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let disc = Generator::Circle { radius: 0.2 }.build(16).unwrap();
    sim.add_body(BodyDesc::new(disc, Rugosity::constant(16, 0.002).unwrap()).named(name)).unwrap();
    let mut out = Vec::new();
    Recording::new(&sim, 1).write_states_csv(&mut out).unwrap();
    let labels: Vec<String> =
        csv::Reader::from_reader(out.as_slice()).records().map(|r| r.unwrap()[1].to_owned()).collect();
    assert_eq!(labels, [name]);
}

#[test]
fn states_are_sampled_every_kth_step() {
    let scene = Scene::load(Path::new(SCENES).join("fig8-type1-type1.ron")).unwrap();
    let mut sim = scene.build().unwrap();
    let mut recording = Recording::new(&sim, 5);
    for _ in 0..12 {
        sim.step(sim.settings().time_step);
        recording.record_step(&mut sim);
    }
    // Steps 0 (initial), 5 and 10, two bodies each.
    assert_eq!(recording.states.len(), 6);
}

// ---- malformed scenes ----

const BLOCK: &str = r#"(name: "block", static: true,
    shape: Generator(generator: RoundedRectangle(width: 4.0, height: 0.4, corner_radius: 0.05), segments: 32))"#;

/// A scene of the block and one body written as `body`, with `settings` as given.
fn scene_text(settings: &str, body: &str) -> String {
    format!("(\n    settings: ({settings}),\n    bodies: [\n        {BLOCK},\n        {body},\n    ],\n)")
}

fn build_error(text: &str) -> String {
    match Scene::from_ron_str(text, "test.ron").and_then(|scene| scene.build()) {
        Ok(_) => panic!("scene was accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const WHEEL_SHAPE: &str = "shape: Generator(generator: Circle(radius: 0.2), segments: 16)";

#[test]
fn syntax_error_reports_line_and_column() {
    let text = "(\n    bodies: [\n        (name: \"a\" shape: Circle),\n    ],\n)";
    let err = Scene::from_ron_str(text, "broken.ron").unwrap_err();
    assert!(matches!(err, SceneError::Parse { line: 3, .. }), "{err:?}");
    assert!(err.to_string().starts_with("broken.ron:3:"), "{err}");
}

#[test]
fn unknown_field_is_refused_with_its_position() {
    let text = scene_text("", &format!("(name: \"wheel\", {WHEEL_SHAPE}, colour: 3)"));
    let err = build_error(&text);
    assert!(err.starts_with("test.ron:6:"), "{err}");
    assert!(err.contains("colour"), "{err}");
}

#[test]
fn unknown_field_in_a_nested_generator_is_refused() {
    let text = scene_text("", "(shape: Generator(generator: Circle(radius: 0.2, radios: 1.0), segments: 16))");
    let err = build_error(&text);
    assert!(err.contains("radios"), "{err}");
}

#[test]
fn explicit_rugosity_with_the_wrong_count_names_body_and_field() {
    let values = ["0.001"; 12].join(", ");
    let err = build_error(&scene_text("", &format!("(name: \"wheel\", {WHEEL_SHAPE}, rugosity: Values([{values}]))")));
    assert_eq!(err, "test.ron: body 1 ('wheel'): rugosity: 12 values for 16 segments");
}

#[test]
fn negative_density_names_the_material_field() {
    let err = build_error(&scene_text("", &format!("(name: \"wheel\", {WHEEL_SHAPE}, material: (density: -2.0))")));
    assert_eq!(err, "test.ron: body 1 ('wheel'): material.density: -2 must lie in [0.000001, 1000000000000]");
}

#[test]
fn setting_only_restitution_is_valid_and_raises_its_maximum_with_it() {
    // e_max must lie in [e, 1]; left out, it is max(e, 0.5), so e = 0.8 alone is a valid material
    // (it used to be refused with "material.restitution_max: 0.5 must lie in [0.8, 1]").
    for (material, e_max) in [("(restitution: 0.8)", 0.8), ("(restitution: 0.2)", 0.5), ("(restitution_max: 0.9)", 0.9)]
    {
        let text = scene_text("", &format!("(name: \"wheel\", {WHEEL_SHAPE}, material: {material})"));
        let sim = Scene::from_ron_str(&text, "test.ron").and_then(|scene| scene.build()).unwrap();
        let wheel = sim.bodies().nth(1).unwrap();
        let got = sim.world().get::<&rugosa::Material>(wheel).unwrap().restitution_max;
        assert_eq!(got, e_max, "{material}");
    }
    let err = build_error(&scene_text(
        "",
        &format!("(name: \"wheel\", {WHEEL_SHAPE}, material: (restitution: 0.8, restitution_max: 0.6))"),
    ));
    assert_eq!(err, "test.ron: body 1 ('wheel'): material.restitution_max: 0.6 must lie in [0.8, 1]");
}

#[test]
fn self_intersecting_control_points_are_refused() {
    // A figure of eight with unequal lobes (a bow tie of zero area would fail earlier).
    // Listed with a positive net area (clockwise input is refused before this check).
    let looped = "(0.0, 1.0), (3.0, 2.0), (3.0, 3.0), (0.0, 3.0), (0.0, 2.0), (2.0, 1.0), (2.0, 0.0), (0.0, 0.0)";
    let err = build_error(&scene_text("", &format!("(shape: ControlPoints([{looped}]))")));
    assert_eq!(err, "test.ron: body 1: shape: the boundary intersects itself: segments 0 and 4 cross");
}

#[test]
fn from_outline_without_an_outline_is_refused() {
    let err = build_error(&scene_text("", &format!("(name: \"wheel\", {WHEEL_SHAPE}, rugosity: FromOutline)")));
    assert_eq!(
        err,
        "test.ron: body 1 ('wheel'): rugosity: FromOutline needs an Outline shape to measure the rugosity from"
    );
}

#[test]
fn unknown_generator_is_refused_with_its_position() {
    let err = build_error(&scene_text("", "(shape: Generator(generator: Triangle(side: 1.0), segments: 16))"));
    assert!(err.starts_with("test.ron:6:"), "{err}");
    assert!(err.contains("Triangle"), "{err}");
}

#[test]
fn bad_pattern_parameter_names_it() {
    let err = build_error(&scene_text(
        "",
        &format!("({WHEEL_SHAPE}, rugosity: Pattern(Random(mean: 0.004, std_dev: -1.0, seed: 1)))"),
    ));
    assert_eq!(err, "test.ron: body 1: rugosity: random.std_dev: -1 is negative; it must be >= 0");
}

#[test]
fn bad_settings_value_names_the_setting() {
    let err = build_error(&scene_text("time_step: -0.01", &format!("({WHEEL_SHAPE})")));
    assert!(err.starts_with("test.ron: settings: setting `time_step` = -0.01: must lie in"), "{err}");
}

#[test]
fn sleep_settings_are_read_and_checked() {
    let text = scene_text("sleep: (enabled: false, time: 2.0)", &format!("({WHEEL_SHAPE})"));
    let scene = Scene::from_ron_str(&text, "test.ron").unwrap();
    assert!(!scene.settings.sleep.enabled);
    assert_eq!((scene.settings.sleep.time, scene.settings.sleep.speed), (2.0, 0.05), "left-out fields default");
    let err = build_error(&scene_text("sleep: (speed: -1.0)", &format!("({WHEEL_SHAPE})")));
    assert!(err.starts_with("test.ron: settings: setting `sleep.speed` = -1: must"), "{err}");
}

#[test]
fn body_motion_is_read_and_checked() {
    let body = format!("({WHEEL_SHAPE}, motion: (gravity_scale: 0.5, fixed_rotation: true), groups: (filter: 6))");
    let scene = Scene::from_ron_str(&scene_text("", &body), "test.ron").unwrap();
    let motion = scene.bodies[1].motion;
    assert_eq!((motion.gravity_scale, motion.linear_damping, motion.fixed_rotation), (0.5, 0.0, true));
    assert_eq!(scene.bodies[1].groups, rugosa::CollisionGroups::new(u32::MAX, 6));
    let err = build_error(&scene_text("", &format!("({WHEEL_SHAPE}, motion: (angular_damping: -2.0))")));
    assert!(err.starts_with("test.ron: body 1: motion.angular_damping: -2 must"), "{err}");
}

#[test]
fn missing_file_names_the_path() {
    let err = Scene::load("no/such/scene.ron").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().starts_with("cannot read scene no/such/scene.ron: "), "{err}");
}

#[test]
fn too_few_segments_for_a_generator_is_refused() {
    let err = build_error(&scene_text("", "(shape: Generator(generator: Circle(radius: 0.2), segments: 3))"));
    assert_eq!(err, "test.ron: body 1: shape: a closed cubic B-spline needs at least 4 control points, got 3");
}

#[test]
fn non_finite_initial_state_is_refused() {
    let err = build_error(&scene_text("", &format!("({WHEEL_SHAPE}, velocity: (inf, 0.0))")));
    assert_eq!(err, "test.ron: body 1: velocity: must be finite");
}

#[test]
fn missing_shape_is_refused() {
    let err = build_error(&scene_text("", "(name: \"ghost\")"));
    assert!(err.starts_with("test.ron:6:"), "{err}");
    assert!(err.contains("shape"), "{err}");
}

#[test]
fn bad_duration_is_refused() {
    let err = build_error("(duration: 0.0, bodies: [])");
    assert_eq!(err, "test.ron: duration: 0 must be finite and > 0");
}

#[test]
fn outline_with_indivisible_point_count_is_refused() {
    let points: Vec<String> = (0..30)
        .map(|k| {
            let theta = std::f64::consts::TAU * f64::from(k) / 30.0;
            format!("({}, {})", 0.2 * theta.cos(), 0.2 * theta.sin())
        })
        .collect();
    let text =
        scene_text("", &format!("(shape: Outline(points: [{}], levels: 3), rugosity: FromOutline)", points.join(", ")));
    let err = build_error(&text);
    assert!(err.starts_with("test.ron: body 1: shape: "), "{err}");
}

#[cfg(feature = "plot")]
#[test]
fn plots_and_frames_are_written_as_png() {
    use rugosa::report::plot::{FrameStyle, write_plots};
    let recording = run(&Path::new(SCENES).join("fig10-blob-constant.ron"), 40);
    let dir = std::env::temp_dir().join(format!("rugosa-scenes-png-{}", std::process::id()));
    let frames = write_plots(&recording, &dir, 3, &FrameStyle::default()).unwrap();
    assert_eq!(frames, 3);
    let mut files = vec![dir.join("friction.png"), dir.join("velocity.png")];
    files.extend((0..3).map(|k| dir.join("frames").join(format!("{k:04}.png"))));
    for file in files {
        let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.len() > 1000, "{} is not a drawn PNG", file.display());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(feature = "plot")]
#[test]
fn unwritable_output_directory_is_a_typed_error() {
    let recording = run(&Path::new(SCENES).join("fig10-blob-constant.ron"), 2);
    let file = std::env::temp_dir().join(format!("rugosa-scenes-file-{}", std::process::id()));
    std::fs::write(&file, "not a directory").unwrap();
    let err = recording.write_csv_files(&file.join("sub")).unwrap_err();
    assert!(err.to_string().starts_with("cannot write "), "{err}");
    std::fs::remove_file(&file).unwrap();
}

#[test]
fn the_example_in_docs_scenes_md_builds_and_runs() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scenes.md")).unwrap();
    let start = doc.find("```ron\n").expect("a ```ron block in docs/scenes.md") + "```ron\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let scene = Scene::from_ron_str(&doc[start..end], "docs/scenes.md").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.duration, 2.0);
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..50 {
        sim.step(sim.settings().time_step);
    }
    sim.validate().unwrap();
}
