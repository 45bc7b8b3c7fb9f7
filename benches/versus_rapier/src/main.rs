//! Runs the same scenes in rugosa and in rapier2d 0.36 and writes the comparison into the
//! `versus-rapier` section of `docs/performance.md`, with `docs/img/versus_rapier.png`.
//!
//! Run: `cargo run --release -p versus-rapier` (`-- --quick` for a short run that only prints;
//! `-- --help` for the sizes, steps and warm-up options).

mod measure;
mod plot;
mod polygon;
mod rapier_world;
mod scenes;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Parser;
use rugosa::Stage;

use measure::{AccuracyPoint, RapierTiming, RugosaTiming, Run};
use plot::Series;
use scenes::SceneSpec;

const BEGIN: &str = "<!-- versus-rapier:begin -->";
const END: &str = "<!-- versus-rapier:end -->";
/// Geometric errors given to rapier, relative to the body size.
const RELATIVE_TOLERANCES: [f64; 2] = [1e-3, 1e-4];
const THREADS: [usize; 2] = [1, 2];

/// rugosa against rapier2d: step time per scene and thread count, error against cost.
#[derive(Parser, Debug)]
struct Args {
    /// Small scenes and few steps; prints without writing any file.
    #[arg(long)]
    quick: bool,
    /// Pile sizes (number of blobs).
    #[arg(long, value_delimiter = ',', default_value = "100,500,2000")]
    sizes: Vec<usize>,
    /// Measured steps per run (piles above 500 blobs: at most `--large-steps`).
    #[arg(long, default_value_t = 20)]
    steps: usize,
    /// Measured steps for piles above 500 blobs (rugosa takes seconds per step there).
    #[arg(long, default_value_t = 5)]
    large_steps: usize,
    /// Steps run before measuring (the same for both engines).
    #[arg(long, default_value_t = 60)]
    warmup: usize,
    /// Boxes in the pyramid's base.
    #[arg(long, default_value_t = 10)]
    pyramid_base: usize,
    /// Blobs of the accuracy scene.
    #[arg(long, default_value_t = 8)]
    accuracy_blobs: usize,
}

impl Args {
    fn apply_quick(&mut self) {
        if self.quick {
            self.sizes = vec![20];
            self.steps = 3;
            self.large_steps = 3;
            self.warmup = 5;
            self.pyramid_base = 4;
            self.accuracy_blobs = 3;
        }
    }

    fn command(&self) -> String {
        let defaults = Args::parse_from(["versus-rapier"]);
        let mut flags = String::new();
        if self.sizes != defaults.sizes {
            let sizes: Vec<String> = self.sizes.iter().map(ToString::to_string).collect();
            write!(flags, " --sizes {}", sizes.join(",")).unwrap();
        }
        for (name, value, default) in [
            ("steps", self.steps, defaults.steps),
            ("large-steps", self.large_steps, defaults.large_steps),
            ("warmup", self.warmup, defaults.warmup),
            ("pyramid-base", self.pyramid_base, defaults.pyramid_base),
            ("accuracy-blobs", self.accuracy_blobs, defaults.accuracy_blobs),
        ] {
            if value != default {
                write!(flags, " --{name} {value}").unwrap();
            }
        }
        if flags.is_empty() {
            "cargo run --release -p versus-rapier".to_owned()
        } else {
            format!("cargo run --release -p versus-rapier --{flags}")
        }
    }
}

/// One scene's timings: rugosa and rapier at each tolerance, per thread count.
struct SceneRow {
    spec: SceneSpec,
    run: Run,
    rugosa: Vec<RugosaTiming>,
    rapier: Vec<Vec<RapierTiming>>,
}

fn main() {
    let mut args = Args::parse();
    args.apply_quick();
    let started = Instant::now();
    let mut rows = Vec::new();
    for &size in &args.sizes {
        let steps = if size > 500 { args.large_steps } else { args.steps };
        rows.push(time_scene(scenes::pile(size), Run { warmup: args.warmup, steps }));
    }
    let fig12 = scenes::fig12().unwrap_or_else(|e| panic!("fig12 scene: {e}"));
    rows.push(time_scene(fig12, Run { warmup: args.warmup, steps: args.steps }));
    rows.push(time_scene(scenes::pyramid(args.pyramid_base), Run { warmup: args.warmup, steps: args.steps }));
    let horizon = if args.quick { 0.1 } else { 0.5 };
    let accuracy = accuracy_table(&scenes::row(args.accuracy_blobs), horizon);
    let elapsed = started.elapsed();
    let section = section(&args, &rows, (&accuracy, horizon), elapsed);
    println!("{section}");
    if !args.quick {
        write_outputs(&section, &rows, &accuracy);
    }
    eprintln!("total run time {:.0} s", elapsed.as_secs_f64());
}

fn time_scene(spec: SceneSpec, run: Run) -> SceneRow {
    eprintln!("{}: {} bodies, {} + {} steps", spec.name, spec.bodies.len(), run.warmup, run.steps);
    let rugosa = THREADS.iter().map(|&t| measure::time_rugosa(&spec, t, run)).collect();
    let rapier = RELATIVE_TOLERANCES
        .iter()
        .map(|&rel| THREADS.iter().map(|&t| measure::time_rapier(&spec, rel * spec.body_size, t, run)).collect())
        .collect();
    SceneRow { spec, run, rugosa, rapier }
}

/// The accuracy runs: one engine variant, its points.
struct AccuracyRow {
    engine: String,
    points: Vec<AccuracyPoint>,
}

/// Base step of both engines (rugosa's default), the steps tried, and the reference (step/16).
const BASE_DT: f64 = 1.0 / 120.0;
/// The last, twice the reference step, shows whether the reference itself has converged.
const ACCURACY_STEPS: [f64; 5] = [1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 480.0, 1.0 / 960.0];

fn accuracy_table(spec: &SceneSpec, horizon: f64) -> Vec<AccuracyRow> {
    let reference = BASE_DT / 16.0;
    eprintln!("accuracy: {} for {horizon} s, reference step {reference:.6} s", spec.name);
    let mut rows = vec![AccuracyRow {
        engine: "rugosa".to_owned(),
        points: measure::accuracy(spec, &ACCURACY_STEPS, reference, |dt| measure::run_rugosa(spec, dt, horizon)),
    }];
    for rel in RELATIVE_TOLERANCES {
        let tolerance = rel * spec.body_size;
        rows.push(AccuracyRow {
            engine: format!("rapier, polygon {rel:.0e}"),
            points: measure::accuracy(spec, &ACCURACY_STEPS, reference, |dt| {
                measure::run_rapier(spec, tolerance, dt, horizon)
            }),
        });
    }
    rows
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn section(args: &Args, rows: &[SceneRow], accuracy: (&[AccuracyRow], f64), elapsed: Duration) -> String {
    let mut out = String::new();
    writeln!(out, "{BEGIN}").unwrap();
    writeln!(out, "## rugosa against rapier2d 0.36\n").unwrap();
    writeln!(
        out,
        "Generated by `{}` (medians from one run; this run took {:.0} s). It replaces only the text \
         between the `versus-rapier` markers; the rest of this file comes from `performance_report`.\n",
        args.command(),
        elapsed.as_secs_f64()
    )
    .unwrap();
    writeln!(out, "Machine: {}.\n", rugosa::report::machine_description()).unwrap();
    out.push_str(&settings_text(rows));
    out.push_str(&shape_table(rows));
    out.push_str(&timing_table(rows));
    out.push_str(&stage_table(rows));
    out.push_str(&accuracy_text(accuracy.0, args.accuracy_blobs, accuracy.1));
    out.push_str(&reading(rows));
    writeln!(out, "{END}").unwrap();
    out
}

fn settings_text(rows: &[SceneRow]) -> String {
    let mut out = String::new();
    writeln!(out, "### Settings\n").unwrap();
    writeln!(
        out,
        "- Both engines: gravity (0, −9.81) m/s², step 1/120 s (rugosa's default), the same bodies at the \
         same centre of mass, angle and velocity, the same density (1000 kg/m²). rugosa's sub-steps and \
         retries are its own; rapier runs its defaults (4 solver sub-steps, CCD off, speculative contacts), \
         sleeping off (rugosa has none), f32 (`rapier2d`; `rapier2d-f64` was not built, to keep the \
         build short — each engine is compared against itself in the accuracy table, so its own precision \
         is in its own numbers)."
    )
    .unwrap();
    writeln!(
        out,
        "- Friction: rugosa's μ follows from the local band through the friction law \
         μ(λ) = μ_max (λ − λ_min)/λ with the max rule at a contact; rapier gets, per body, the μ that law \
         gives at the body's mean band, combined with `CoefficientCombineRule::Max`. Restitution: \
         rapier gets rugosa's collision restitution e (max rule); rugosa's push-out inside the band \
         follows e_c(δ), rising to e_max, which rapier has no counterpart for."
    )
    .unwrap();
    for row in rows {
        let pairs: Vec<String> =
            row.spec.coefficients().iter().map(|(mu, e)| format!("μ = {mu:.3}, e = {e:.2}")).collect();
        writeln!(out, "  - {}: {}.", row.spec.name, pairs.join("; ")).unwrap();
    }
    writeln!(
        out,
        "- Shapes in rapier: each spline is sampled on the curve, every spline segment cut into the \
         fewest equal parameter pieces whose chord lies within the tolerance of its arc; the bound below \
         is the largest distance between any polygon edge and its own arc (both directions, 32 samples \
         per edge), an upper bound of the Hausdorff distance. A body whose convex hull is within the \
         tolerance is one `SharedShape::convex_polyline`; a blob (star-shaped about its generator's \
         centre) is the exact fan of triangles from that centre, merged into convex pieces, as a \
         `SharedShape::compound`. parry's `convex_decomposition` (VHACD) is approximate — its hulls \
         fill concavities by an amount set by its own concavity parameter — so it is only the fallback \
         for a polygon that is not star-shaped (the last column counts such bodies). Static walls and \
         ground are the closed polygon as a `SharedShape::polyline`. A body counts as convex below only \
         if its polygon's hull is within the tolerance; the pyramid's rounded squares are (their sides \
         are exactly straight), so rapier gets each as one convex polygon.\n"
    )
    .unwrap();
    out
}

fn shape_table(rows: &[SceneRow]) -> String {
    let mut out = String::new();
    writeln!(out, "### Polygons given to rapier\n").unwrap();
    writeln!(out, "| scene | body size m | tolerance / size | tolerance m | vertices per dynamic body (mean, max) | convex pieces (mean) | convex bodies | largest bound m | VHACD bodies |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|").unwrap();
    for row in rows {
        for (k, rel) in RELATIVE_TOLERANCES.iter().enumerate() {
            let shapes: Vec<_> = row.rapier[k][0]
                .shapes
                .iter()
                .zip(&row.spec.bodies)
                .filter(|(_, b)| !b.is_static)
                .map(|(s, _)| *s)
                .collect();
            let all = &row.rapier[k][0].shapes;
            let count = shapes.len().max(1) as f64;
            let mean_vertices = shapes.iter().map(|s| s.vertices as f64).sum::<f64>() / count;
            let max_vertices = shapes.iter().map(|s| s.vertices).max().unwrap_or(0);
            let mean_pieces = shapes.iter().map(|s| s.pieces as f64).sum::<f64>() / count;
            let convex = shapes.iter().filter(|s| s.pieces == 1).count();
            let bound = all.iter().map(|s| s.hausdorff).fold(0.0, f64::max);
            let vhacd = all.iter().filter(|s| s.vhacd).count();
            writeln!(
                out,
                "| {} | {:.3} | {rel:.0e} | {:.1e} | {mean_vertices:.0}, {max_vertices} | {mean_pieces:.1} | {convex} of {} | {bound:.2e} | {vhacd} |",
                row.spec.name,
                row.spec.body_size,
                rel * row.spec.body_size,
                shapes.len()
            )
            .unwrap();
        }
    }
    writeln!(out).unwrap();
    out
}

fn timing_table(rows: &[SceneRow]) -> String {
    let mut out = String::new();
    writeln!(out, "### Step time\n").unwrap();
    writeln!(
        out,
        "Median step time (ms) after the warm-up; all columns of a row come from this one run, side by side. \
         rapier's threads are a rayon pool of that size entered with `install` (its `parallel` feature).\n"
    )
    .unwrap();
    writeln!(out, "| scene | bodies | warm-up + measured steps | threads | rugosa ms | rapier 1e-3 ms | rapier 1e-4 ms | rugosa / rapier 1e-3 | rugosa / rapier 1e-4 |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|").unwrap();
    for row in rows {
        for (t, threads) in THREADS.iter().enumerate() {
            let rugosa = ms(row.rugosa[t].step);
            let (coarse, fine) = (ms(row.rapier[0][t].step), ms(row.rapier[1][t].step));
            writeln!(
                out,
                "| {} | {} | {} + {} | {threads} | {rugosa:.2} | {coarse:.3} | {fine:.3} | {} | {} |",
                row.spec.name,
                row.spec.dynamic_count(),
                row.run.warmup,
                row.run.steps,
                ratio(rugosa / coarse),
                ratio(rugosa / fine)
            )
            .unwrap();
        }
    }
    writeln!(out).unwrap();
    out
}

fn stage_table(rows: &[SceneRow]) -> String {
    let mut out = String::new();
    writeln!(out, "### rugosa per stage\n").unwrap();
    writeln!(out, "Median of each stage's time per step (ms), from `Simulation::take_profile`; sub-steps and pairs are per step, averaged.\n").unwrap();
    write!(out, "| scene | threads |").unwrap();
    for stage in Stage::ALL {
        write!(out, " {} |", stage.name()).unwrap();
    }
    writeln!(out, " sub-steps | pairs | contacts |").unwrap();
    writeln!(out, "|---|---:|{}---:|---:|---:|", "---:|".repeat(Stage::ALL.len())).unwrap();
    for row in rows {
        for (t, threads) in THREADS.iter().enumerate() {
            let timing = &row.rugosa[t];
            write!(out, "| {} | {threads} |", row.spec.name).unwrap();
            for stage in &timing.stages {
                write!(out, " {:.2} |", ms(*stage)).unwrap();
            }
            let per = |v: u64| v as f64 / row.run.steps.max(1) as f64;
            writeln!(
                out,
                " {:.2} | {:.0} | {:.0} |",
                per(timing.counters.substeps),
                per(timing.counters.candidate_pairs),
                per(timing.counters.contacts)
            )
            .unwrap();
        }
    }
    writeln!(out).unwrap();
    out
}

fn accuracy_text(rows: &[AccuracyRow], blobs: usize, horizon: f64) -> String {
    let mut out = String::new();
    writeln!(out, "### Error against cost\n").unwrap();
    writeln!(
        out,
        "A row of {} blobs of the pile (0.35 m apart, dropped 0.2 m onto the floor of the same box, landing at \
         about 0.2 s) run for {horizon} s at each step, one thread, against the same engine at step \
         (1/120)/16 s: RMS over the dynamic bodies of the distance to the reference position at the horizon, divided by the body size. Contacts make \
         such scenes sensitive to small differences, so the error measures convergence in the step, not \
         closeness to the other engine. Wall time is the whole horizon. The last step of each engine, \
         1/960 s, is twice the reference step: where its error is not much below the others', that \
         engine's result on this scene has not converged at any step tried, and its errors say how much \
         the step changes the outcome rather than how fast it converges.\n",
        blobs
    )
    .unwrap();
    writeln!(out, "| engine | step s | steps | wall ms | RMS position error / body size |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|").unwrap();
    for row in rows {
        for p in &row.points {
            writeln!(
                out,
                "| {} | 1/{:.0} | {} | {:.1} | {:.2e} |",
                row.engine,
                1.0 / p.dt,
                (horizon / p.dt).round(),
                ms(p.wall),
                p.error
            )
            .unwrap();
        }
    }
    writeln!(out, "\n![step time and error against cost](img/versus_rapier.png)\n").unwrap();
    out
}

fn reading(rows: &[SceneRow]) -> String {
    let mut out = String::new();
    writeln!(out, "### Reading\n").unwrap();
    let ratios: Vec<f64> = rows.iter().map(|r| ms(r.rugosa[0].step) / ms(r.rapier[1][0].step)).collect();
    let (lo, hi) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(*r), hi.max(*r)));
    let narrow = Stage::ALL.iter().position(|s| s.name() == "narrow_phase").expect("a narrow_phase stage");
    let shares = rows.iter().map(|r| {
        let total: f64 = r.rugosa[0].stages.iter().map(|d| ms(*d)).sum();
        100.0 * ms(r.rugosa[0].stages[narrow]) / total.max(f64::MIN_POSITIVE)
    });
    let share = shares.fold((f64::INFINITY, 0.0f64), |(lo, hi), s| (lo.min(s), hi.max(s)));
    writeln!(
        out,
        "- With one thread the ratio of rugosa's step time to rapier's with the finer (1e-4) polygons \
         ranges from {} to {} across these scenes. The narrow phase (curve-pair Newton solves, repeated \
         for every sub-step of conservative advancement) takes {:.0}% to {:.0}% of rugosa's stage time \
         (one thread, per scene).\n\
         - The two engines do not do the same work: rugosa keeps the spline exactly, resolves contact within \
         a rugosity band with an iterated impulse solver and never lets bodies pass through each other \
         (it splits steps instead), while rapier solves polygon contacts with a soft, sub-stepped solver and \
         speculative contacts. The ratios are what a user pays today for the same scene, not a comparison \
         of equal algorithms.\n\
         - The two thread counts run one after the other on a shared 2-core machine, so each median carries \
         that run's noise.",
        ratio(lo),
        ratio(hi),
        share.0,
        share.1
    )
    .unwrap();
    out
}

/// A time ratio with two significant digits.
fn ratio(value: f64) -> String {
    if value >= 10.0 { format!("{value:.0}×") } else { format!("{value:.2}×") }
}

fn write_outputs(section: &str, rows: &[SceneRow], accuracy: &[AccuracyRow]) {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let doc_path = root.join("docs/performance.md");
    let existing = std::fs::read_to_string(&doc_path).unwrap_or_default();
    std::fs::write(&doc_path, replace_section(&existing, section)).expect("write docs/performance.md");
    eprintln!("wrote {}", doc_path.display());
    let image = root.join("docs/img/versus_rapier.png");
    let (left, right) = plot_series(rows, accuracy);
    plot::write(
        &image,
        ("Pile of blobs: step time", "blobs", "median step time (ms)", &left),
        (
            "Error against cost (row of blobs, 0.5 s)",
            "wall time of the horizon (ms)",
            "RMS position error / body size",
            &right,
        ),
    )
    .unwrap_or_else(|e| panic!("plot {}: {e}", image.display()));
    eprintln!("wrote {}", image.display());
}

/// `existing` with the text between the markers (markers included) replaced by `section`, or
/// `section` appended after a blank line if the markers are absent.
fn replace_section(existing: &str, section: &str) -> String {
    match (existing.find(BEGIN), existing.find(END)) {
        (Some(begin), Some(end)) if end > begin => {
            let after = &existing[end + END.len()..];
            format!("{}{}{}", &existing[..begin], section.trim_end(), after)
        }
        _ => format!("{}\n{}", existing.trim_end_matches('\n').to_owned() + "\n", section),
    }
}

fn plot_series(rows: &[SceneRow], accuracy: &[AccuracyRow]) -> (Vec<Series>, Vec<Series>) {
    let piles: Vec<&SceneRow> = rows.iter().filter(|r| r.spec.name.starts_with("pile")).collect();
    let mut left = Vec::new();
    for (t, threads) in THREADS.iter().enumerate() {
        let dashed = t > 0;
        let n = |r: &SceneRow| r.spec.dynamic_count() as f64;
        left.push(Series {
            label: format!("rugosa, {threads} thread(s)"),
            points: piles.iter().map(|r| (n(r), ms(r.rugosa[t].step))).collect(),
            colour: 0,
            dashed,
        });
        for (k, rel) in RELATIVE_TOLERANCES.iter().enumerate() {
            left.push(Series {
                label: format!("rapier {rel:.0e}, {threads} thread(s)"),
                points: piles.iter().map(|r| (n(r), ms(r.rapier[k][t].step))).collect(),
                colour: k + 1,
                dashed,
            });
        }
    }
    let right = accuracy
        .iter()
        .enumerate()
        .map(|(k, row)| Series {
            label: row.engine.clone(),
            points: row.points.iter().map(|p| (ms(p.wall), p.error)).collect(),
            colour: k,
            dashed: false,
        })
        .collect();
    (left, right)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn section_is_replaced_between_the_markers_and_appended_when_absent() {
        let section = format!("{BEGIN}\nnew\n{END}\n");
        let appended = replace_section("# Performance\n\ntext\n", &section);
        assert_eq!(appended, format!("# Performance\n\ntext\n\n{section}"));
        let replaced = replace_section(&appended.replace("new", "old"), &section);
        assert_eq!(replaced.trim_end(), appended.trim_end());
        assert_eq!(replaced.matches(BEGIN).count(), 1);
    }
}
