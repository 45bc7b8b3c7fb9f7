//! Generates `docs/accuracy.md`, `docs/accuracy.csv` and `docs/img/accuracy.png`: error
//! against run time for the analytic cases of MODEL §9 and a multi-contact pile, sweeping the
//! time step and, separately, the Newton tolerance, the minimum band and the retry depth.
//!
//! Run: `cargo run --release --example work_precision` (add `-- --quick` for a reduced sweep
//! that prints without writing files). Exits non-zero if the pile's fine-step reference fails
//! its check (halving its step must change it by at least 10× less than the pile's smallest
//! error).

mod cases;

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use cases::{Case, Reference, RollingOffset, Run, all_cases, rolling_offsets};
use clap::Parser;
use plotters::prelude::*;
use rugosa::report::median;
use rugosa::{SimulationSettings, StepCounters};

/// Runs per configuration in the full sweep; the time is their median.
const RUNS: usize = 5;
/// The four finest steps of a sweep are its asymptotic range for the order fit.
const ASYMPTOTIC_POINTS: usize = 4;
/// Errors below this are rounding, not discretization: no order is fitted.
const FLOATING_POINT_FLOOR: f64 = 1e-10;
/// The reference must change on halving its step by at most this fraction of the smallest error.
const REFERENCE_MARGIN: f64 = 0.1;

const COMMAND: &str = "cargo run --release --example work_precision";
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FONT_FAMILY: &str = "sans-serif";

/// One swept setting: its name, values, and the cases it is swept on.
struct Sweep {
    setting: &'static str,
    values: Vec<f64>,
    cases: &'static [&'static str],
    apply: fn(&mut SimulationSettings, f64),
}

/// One measured configuration.
struct Row {
    case: &'static str,
    setting: &'static str,
    value: f64,
    error: f64,
    /// Normalized distance from the default-settings run at the same step (tolerance sweeps).
    deviation: Option<f64>,
    median_seconds: f64,
    runs: usize,
    steps: u64,
    counters: StepCounters,
}

/// The fine-step reference of a case and its check.
struct ReferenceCheck {
    case: &'static str,
    step: f64,
    /// Normalized change of the reference when its step is halved.
    change_on_halving: f64,
    /// The same for the next halving (informative).
    next_change: f64,
    smallest_error: f64,
}

impl ReferenceCheck {
    fn holds(&self) -> bool {
        self.change_on_halving <= REFERENCE_MARGIN * self.smallest_error
    }
}

/// Measure error against run time and write docs/accuracy.md, docs/accuracy.csv and docs/img/accuracy.png.
///
/// Exits non-zero, writing nothing, if a fine-step reference fails its check.
#[derive(Parser, Debug)]
struct Args {
    /// A reduced sweep (five steps per case, every other tolerance, one run each) that prints without writing files.
    #[arg(long)]
    quick: bool,
}

fn main() {
    let quick = Args::parse().quick;
    let started = Instant::now();
    let cases = all_cases();
    let runs = if quick { 1 } else { RUNS };
    let references: Vec<Vec<f64>> = cases.iter().map(reference_observable).collect();
    let mut rows = Vec::new();
    for (case, reference) in cases.iter().zip(&references) {
        let steps = if quick { case.step_sweep().into_iter().take(5).collect() } else { case.step_sweep() };
        for step in steps {
            let settings = SimulationSettings { time_step: step, ..SimulationSettings::default() };
            rows.push(measure(case, reference, "time_step", step, &settings, None, runs));
        }
    }
    for sweep in sweeps(quick) {
        for (case, reference) in cases.iter().zip(&references).filter(|(c, _)| sweep.cases.contains(&c.name)) {
            let default = case.run(&SimulationSettings::default()).observable;
            for &value in &sweep.values {
                let mut settings = SimulationSettings::default();
                (sweep.apply)(&mut settings, value);
                rows.push(measure(case, reference, sweep.setting, value, &settings, Some(&default), runs));
            }
        }
    }
    let checks: Vec<ReferenceCheck> = cases.iter().filter_map(|c| check_reference(c, &rows)).collect();
    let offsets = rolling_offsets(&SimulationSettings::default());
    let seconds = started.elapsed().as_secs_f64();
    let doc = report(&cases, &rows, &checks, &offsets, seconds, quick);
    print!("{doc}");
    let failed: Vec<_> = checks.iter().filter(|c| !c.holds()).collect();
    if !failed.is_empty() {
        for check in failed {
            eprintln!(
                "REFERENCE CHECK FAILED for {}: halving the reference step 1/{:.0} s changes it by {:.3e}, more than \
                 {REFERENCE_MARGIN} × the smallest error {:.3e}; no file written",
                check.case,
                1.0 / check.step,
                check.change_on_halving,
                check.smallest_error
            );
        }
        std::process::exit(1);
    }
    if !quick {
        write_outputs(&doc, &rows);
    }
}

fn sweeps(quick: bool) -> Vec<Sweep> {
    const MAIN: &[&str] = &["bounce", "sliding-stop", "rolling", "free-flight", "pile"];
    let pick = |full: Vec<f64>| if quick { full.into_iter().step_by(2).collect() } else { full };
    vec![
        Sweep {
            setting: "newton_step_tolerance",
            values: pick(vec![1e-13, 1e-10, 1e-7, 1e-5, 1e-3, 1e-2, 1e-1]),
            cases: MAIN,
            apply: |s, v| s.curve_pair.newton_step_tolerance = v,
        },
        Sweep {
            setting: "min_band",
            values: pick(vec![1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]),
            cases: &["bounce-smooth"],
            apply: |s, v| s.min_band = v,
        },
        Sweep {
            setting: "max_retry_depth",
            values: pick(vec![0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0]),
            cases: MAIN,
            apply: |s, v| s.max_retry_depth = v as u32,
        },
    ]
}

/// The analytic observable, or the case's run at its reference step.
fn reference_observable(case: &Case) -> Vec<f64> {
    match &case.reference {
        Reference::Analytic(exact) => exact.clone(),
        Reference::FineStep(step) => {
            case.run(&SimulationSettings { time_step: *step, ..SimulationSettings::default() }).observable
        }
    }
}

/// Runs `settings` `runs` times (the runs must agree exactly) and keeps the median time.
fn measure(
    case: &Case,
    reference: &[f64],
    setting: &'static str,
    value: f64,
    settings: &SimulationSettings,
    default: Option<&[f64]>,
    runs: usize,
) -> Row {
    let results: Vec<Run> = (0..runs).map(|_| case.run(settings)).collect();
    let first = &results[0];
    assert!(
        results.iter().all(|r| r.observable == first.observable),
        "{} is not deterministic at {setting} = {value}",
        case.name
    );
    Row {
        case: case.name,
        setting,
        value,
        error: case.error(&first.observable, reference),
        deviation: default.map(|d| case.error(&first.observable, d)),
        median_seconds: median(results.iter().map(|r| r.stepping)).expect("at least one run").as_secs_f64(),
        runs,
        steps: first.profile.steps,
        counters: first.profile.counters,
    }
}

/// Halves the reference step twice and compares with the case's smallest error.
fn check_reference(case: &Case, rows: &[Row]) -> Option<ReferenceCheck> {
    let Reference::FineStep(step) = case.reference else { return None };
    let at = |h: f64| case.run(&SimulationSettings { time_step: h, ..SimulationSettings::default() }).observable;
    let (r1, r2, r4) = (at(step), at(0.5 * step), at(0.25 * step));
    let smallest_error = rows.iter().filter(|r| r.case == case.name).map(|r| r.error).fold(f64::INFINITY, f64::min);
    Some(ReferenceCheck {
        case: case.name,
        step,
        change_on_halving: case.error(&r1, &r2),
        next_change: case.error(&r2, &r4),
        smallest_error,
    })
}

// ---------------------------------------------------------------- orders

/// Least-squares slope of `ln y` against `ln x`.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// The observed order of a case's step sweep, in words.
struct Order {
    asymptotic: String,
    all_points: String,
    points: String,
}

fn observed_order(rows: &[&Row]) -> Order {
    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.value, r.error)).collect();
    let finest = &points[points.len().saturating_sub(ASYMPTOTIC_POINTS)..];
    let names = finest.iter().map(|(h, _)| format!("1/{:.0}", 1.0 / h)).collect::<Vec<_>>().join(", ");
    let largest = points.iter().map(|p| p.1).fold(0.0, f64::max);
    if largest < FLOATING_POINT_FLOOR {
        let floor = format!("none: floating-point floor (every error ≤ {largest:.1e})");
        return Order { asymptotic: floor.clone(), all_points: floor, points: names };
    }
    if points.iter().any(|p| p.1 <= 0.0) {
        let exact = "none: some errors are exactly 0".to_owned();
        return Order { asymptotic: exact.clone(), all_points: exact, points: names };
    }
    Order {
        asymptotic: format!("{:.2}", log_slope(finest)),
        all_points: format!("{:.2}", log_slope(&points)),
        points: names,
    }
}

// ---------------------------------------------------------------- report

fn step_name(h: f64) -> String {
    format!("1/{:.0}", 1.0 / h)
}

/// A swept value as it reads best: steps as 1/N s, depths as integers, tolerances as powers.
fn setting_value(setting: &str, value: f64) -> String {
    match setting {
        "time_step" => step_name(value),
        "max_retry_depth" => format!("{value:.0}"),
        _ => format!("{value:.0e}"),
    }
}

fn report(
    cases: &[Case],
    rows: &[Row],
    checks: &[ReferenceCheck],
    offsets: &[RollingOffset],
    seconds: f64,
    quick: bool,
) -> String {
    let mut out = String::new();
    writeln!(out, "# Work-precision report\n").unwrap();
    writeln!(
        out,
        "Generated by `{COMMAND}` ({}; the whole command took {seconds:.0} s). Machine: {} (every run on 1 thread). Times are the \
         median wall time of the stepping over {} runs (bodies are built outside the timer); every count is \
         from the first run (the runs agree exactly). CSV: [`accuracy.csv`](accuracy.csv).\n",
        if quick { "`--quick`: reduced sweep, one run each" } else { "full sweep" },
        rugosa::report::machine_description(),
        rows.first().map_or(0, |r| r.runs)
    )
    .unwrap();
    writeln!(out, "![error against run time](img/accuracy.png)\n").unwrap();
    write_cases(&mut out, cases);
    write_checks(&mut out, checks);
    write_orders(&mut out, cases, rows);
    write_step_tables(&mut out, cases, rows);
    write_rolling_offsets(&mut out, offsets);
    for setting in ["newton_step_tolerance", "min_band", "max_retry_depth"] {
        write_setting_table(&mut out, setting, rows);
    }
    write_min_band_order(&mut out, rows);
    write_limits(&mut out, cases, rows);
    out
}

fn write_cases(out: &mut String, cases: &[Case]) {
    writeln!(out, "## Cases, errors and references\n").unwrap();
    writeln!(out, "| case | set-up | error (normalized) | reference |").unwrap();
    writeln!(out, "|---|---|---|---|").unwrap();
    for case in cases {
        let cell = |text: &str| text.replace('|', "\\|");
        writeln!(
            out,
            "| {} | {} | {} | {} |",
            case.name,
            cell(case.setup),
            cell(case.error_definition),
            cell(case.reference_definition)
        )
        .unwrap();
    }
    writeln!(
        out,
        "\nAll other settings are the defaults (`SimulationSettings::default()`: step 1/120 s, min_band 1e-3 m, \
         retry depth 8, Newton step tolerance 1e-13). Each tolerance sweep runs at the default step and also \
         gives the *deviation*: the same normalized error measured against the default-settings run at that \
         step, which isolates the setting's own effect from the step's.\n"
    )
    .unwrap();
}

fn write_rolling_offsets(out: &mut String, offsets: &[RollingOffset]) {
    writeln!(out, "## Rolling radius\n").unwrap();
    writeln!(
        out,
        "The rolling case at the default step for other rugosities (disc and ground alike, μ = 0.5 at each, the disc started with \
         its curve ¾ of the combined band 2λ from the ground's, d = 1.5 λ). The contact point lies halfway between \
         the curves, so the disc rolls on the radius R = r + d/2 and accelerates at g sin θ / (1 + r²/(2R²)) \
         instead of (2/3) g sin θ. *Derived* is that offset from the nominal speed; *measured* is the engine's. \
         The offset shrinks in proportion to the band, as derived.\n"
    )
    .unwrap();
    writeln!(out, "| rugosity λ (m) | d (m) | R (m) | offset, derived | offset, measured | measured − derived |")
        .unwrap();
    writeln!(out, "|---:|---:|---:|---:|---:|---:|").unwrap();
    for o in offsets {
        let gap = 1.5 * o.band;
        writeln!(
            out,
            "| {} | {} | {:.4} | {:.3e} | {:.3e} | {:.1e} |",
            o.band,
            gap,
            cases::rolling_radius(0.2, gap),
            o.derived,
            o.measured,
            o.measured - o.derived
        )
        .unwrap();
    }
    out.push('\n');
}

fn write_checks(out: &mut String, checks: &[ReferenceCheck]) {
    writeln!(out, "## Reference check\n").unwrap();
    for c in checks {
        writeln!(
            out,
            "- **{}**: reference step {} s. Halving it to {} s changes the observable by {:.2e} (normalized as the \
             error); the smallest error of the case is {:.2e}, so the change is {:.0}× smaller (required ≥ {:.0}×): \
             **{}**. Informative: halving once more (to {} s) changes it by {:.2e}.",
            c.case,
            step_name(c.step),
            step_name(0.5 * c.step),
            c.change_on_halving,
            c.smallest_error,
            c.smallest_error / c.change_on_halving,
            1.0 / REFERENCE_MARGIN,
            if c.holds() { "holds" } else { "FAILS" },
            step_name(0.25 * c.step),
            c.next_change
        )
        .unwrap();
    }
    out.push('\n');
}

fn write_orders(out: &mut String, cases: &[Case], rows: &[Row]) {
    writeln!(out, "## Observed convergence order in the step\n").unwrap();
    writeln!(
        out,
        "Least-squares slope of ln(error) against ln(step). The asymptotic range is the {ASYMPTOTIC_POINTS} finest \
         steps of each sweep (listed); the slope over all steps is given beside it.\n"
    )
    .unwrap();
    writeln!(out, "| case | order, finest steps | finest steps used | order, all steps | error range |").unwrap();
    writeln!(out, "|---|---:|---|---:|---|").unwrap();
    for case in cases {
        let sweep = step_rows(rows, case.name);
        let order = observed_order(&sweep);
        let (lo, hi) = sweep.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(r.error), hi.max(r.error)));
        writeln!(
            out,
            "| {} | {} | {} | {} | {lo:.2e} … {hi:.2e} |",
            case.name, order.asymptotic, order.points, order.all_points
        )
        .unwrap();
    }
    out.push('\n');
}

fn step_rows<'a>(rows: &'a [Row], case: &str) -> Vec<&'a Row> {
    rows.iter().filter(|r| r.case == case && r.setting == "time_step").collect()
}

const COUNT_HEADER: &str =
    "steps | sub-steps | retries | retry-limit hits | Newton iterations | impulses | micro-collisions";

fn counts(row: &Row) -> String {
    let c = &row.counters;
    format!(
        "{} | {} | {} | {} | {} | {} | {}",
        row.steps, c.substeps, c.retries, c.retry_limit_hits, c.newton_iterations, c.impulses, c.micro_collisions
    )
}

fn write_step_tables(out: &mut String, cases: &[Case], rows: &[Row]) {
    writeln!(out, "## Step sweep\n").unwrap();
    for case in cases {
        writeln!(out, "### {}\n", case.name).unwrap();
        writeln!(out, "| step (s) | error | time (ms) | {COUNT_HEADER} |").unwrap();
        writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|").unwrap();
        for row in step_rows(rows, case.name) {
            writeln!(
                out,
                "| {} | {:.3e} | {:.3} | {} |",
                step_name(row.value),
                row.error,
                1e3 * row.median_seconds,
                counts(row)
            )
            .unwrap();
        }
        out.push('\n');
    }
}

fn write_setting_table(out: &mut String, setting: &str, rows: &[Row]) {
    let selected: Vec<&Row> = rows.iter().filter(|r| r.setting == setting).collect();
    if selected.is_empty() {
        return;
    }
    writeln!(out, "## Sweep of `{setting}` (step 1/120 s)\n").unwrap();
    writeln!(out, "| case | {setting} | error | deviation from default | time (ms) | {COUNT_HEADER} |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|").unwrap();
    for row in selected {
        writeln!(
            out,
            "| {} | {} | {:.3e} | {:.2e} | {:.3} | {} |",
            row.case,
            setting_value(setting, row.value),
            row.error,
            row.deviation.unwrap_or(f64::NAN),
            1e3 * row.median_seconds,
            counts(row)
        )
        .unwrap();
    }
    out.push('\n');
}

/// The slope of the error in `min_band` over the sweep's values below the disc's drop scale.
fn write_min_band_order(out: &mut String, rows: &[Row]) {
    let points: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.setting == "min_band" && r.error > 0.0).map(|r| (r.value, r.error)).collect();
    if points.len() < 2 {
        return;
    }
    let ratios = points.iter().map(|(band, e)| format!("{:.3}", e / band)).collect::<Vec<_>>().join(", ");
    writeln!(
        out,
        "Observed order of bounce-smooth in `min_band` (least squares over all {} values): **{:.2}**; error / min_band for each value: {ratios}.\n",
        points.len(),
        log_slope(&points)
    )
    .unwrap();
}

fn write_limits(out: &mut String, cases: &[Case], rows: &[Row]) {
    writeln!(out, "## What limits each case\n").unwrap();
    for case in cases {
        writeln!(out, "- **{}**: {}", case.name, case.limit).unwrap();
    }
    let depth_rows: Vec<&Row> = rows.iter().filter(|r| r.setting == "max_retry_depth").collect();
    let no_retries = depth_rows.iter().all(|r| r.counters.retries == 0 && r.counters.retry_limit_hits == 0);
    let no_effect = depth_rows.iter().all(|r| r.deviation == Some(0.0));
    if no_retries && no_effect {
        writeln!(
            out,
            "- **max_retry_depth**: no case retries a sub-step (retries and retry-limit hits are 0 in every run of \
             its sweep), and every depth gives bit-identical results (deviation 0): conservative advancement \
             shortens sub-steps so that no pair can pass into intersection, and retries only happen when its data \
             are stale (a body moved behind the engine's back, `tests/step_control.rs`). Here the depth only sets \
             the floor below which a short sub-step is counted as an `advancement_floor_hit`.\n"
        )
        .unwrap();
    } else {
        writeln!(out, "- **max_retry_depth**: some runs retried or changed with the depth; see its table.\n").unwrap();
    }
}

// ---------------------------------------------------------------- files

fn write_outputs(doc: &str, rows: &[Row]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::write(root.join("docs/accuracy.md"), doc).expect("write docs/accuracy.md");
    write_csv(rows, &root.join("docs/accuracy.csv")).expect("write docs/accuracy.csv");
    plot(rows, &root.join("docs/img/accuracy.png")).expect("write docs/img/accuracy.png");
    eprintln!("wrote docs/accuracy.md, docs/accuracy.csv and docs/img/accuracy.png");
}

const CSV_COLUMNS: [&str; 16] = [
    "case",
    "setting",
    "value",
    "error",
    "deviation_from_default",
    "median_seconds",
    "runs",
    "steps",
    "substeps",
    "retries",
    "retry_limit_hits",
    "newton_iterations",
    "impulses",
    "micro_collisions",
    "contacts",
    "leaf_pairs",
];

/// One row per measured configuration; reals in exponent notation, an empty deviation outside
/// the tolerance sweeps.
fn write_csv(rows: &[Row], path: &Path) -> csv::Result<()> {
    let mut csv = csv::Writer::from_path(path)?;
    csv.write_record(CSV_COLUMNS)?;
    for r in rows {
        let c = &r.counters;
        csv.write_record([
            r.case.to_owned(),
            r.setting.to_owned(),
            format!("{:e}", r.value),
            format!("{:e}", r.error),
            r.deviation.map_or(String::new(), |d| format!("{d:e}")),
            format!("{:e}", r.median_seconds),
            r.runs.to_string(),
            r.steps.to_string(),
            c.substeps.to_string(),
            c.retries.to_string(),
            c.retry_limit_hits.to_string(),
            c.newton_iterations.to_string(),
            c.impulses.to_string(),
            c.micro_collisions.to_string(),
            c.contacts.to_string(),
            c.leaf_pairs.to_string(),
        ])?;
    }
    Ok(csv.flush()?)
}

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(90, 90, 90),
];

/// Error against median run time, log-log, one curve per case of the step sweep; the coarsest
/// and finest steps are labelled.
fn plot(rows: &[Row], path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT).map_err(|_| "font registration failed")?;
    let sweep: Vec<&Row> = rows.iter().filter(|r| r.setting == "time_step").collect();
    let bounds = |f: fn(&Row) -> f64| {
        sweep.iter().map(|r| f(r)).fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (t_lo, t_hi) = bounds(|r| r.median_seconds.max(1e-7));
    let (e_lo, e_hi) = bounds(|r| r.error.max(1e-17));
    let root = BitMapBackend::new(path, (1000, 650)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Work-precision: error against run time, step 1/30 … 1/7680 s (pile 1/3840 s)", (FONT_FAMILY, 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((t_lo / 2.0..t_hi * 2.0).log_scale(), (e_lo / 3.0..e_hi * 3.0).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("median run time of the stepping (s)")
        .y_desc("normalized error")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .label_style((FONT_FAMILY, 14))
        .draw()?;
    let names: Vec<&str> = sweep.iter().fold(Vec::new(), |mut names, r| {
        if !names.contains(&r.case) {
            names.push(r.case);
        }
        names
    });
    for (k, name) in names.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let points: Vec<(f64, f64)> = sweep
            .iter()
            .filter(|r| r.case == *name)
            .map(|r| (r.median_seconds.max(1e-7), r.error.max(1e-17)))
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
        let labelled = sweep.iter().filter(|r| r.case == *name).collect::<Vec<_>>();
        for row in [labelled[0], labelled[labelled.len() - 1]] {
            let at = (row.median_seconds.max(1e-7), row.error.max(1e-17));
            chart.draw_series(std::iter::once(Text::new(step_name(row.value), at, (FONT_FAMILY, 12))))?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::MiddleLeft)
        .label_font((FONT_FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
