//! Cases of the work-precision report (`examples/work_precision`) against bounds from mechanics.
//! The bounce converges in the step:
//! its apex error stays under a bound derived from where in the band the impact can happen,
//! and falls as the step is refined once one step's travel is shorter than the band.

#[allow(dead_code)]
#[path = "../examples/work_precision/cases.rs"]
mod cases;

use rugosa::SimulationSettings;

/// Restitution, drop height, rugosity and apex count of `cases::bounce` (see there).
const E: f64 = 0.8;
const H0: f64 = 1.0;
const BAND: f64 = 0.002;
const APEXES: i32 = 3;

/// Error bound of the bounce at step `h`.
///
/// An impact at depth `d` into the combined band (width 2λ) rebounds from `d` below the band's
/// edge with the speed gained over `h0 + d`, so apex k misses `e^(2k) h0` by
/// `E_k = e² E_(k−1) − (1 − e²) d_k`; summed, `|E_k| ≤ (1 − e^(2k)) max d`. The impact is
/// applied at the end of the first sub-step that ends inside the band, so `d` is at most the
/// band and at most one step's travel at the impact speed `v = √(2 g (h0 + 2λ))` plus `g h²/2`.
/// The apex is read as `y + v_y²/(2g)`, exact in free flight, and the spline circle's radius
/// error (below 1e-6 m for 64 segments) is far below the bound.
fn bound(h: f64) -> f64 {
    let g = cases::G;
    let impact_speed = (2.0 * g * (H0 + 2.0 * BAND)).sqrt();
    let depth = (2.0 * BAND).min(impact_speed * h + 0.5 * g * h * h);
    (1.0 - E.powi(2 * APEXES)) * depth / H0
}

#[test]
fn bounce_error_is_bounded_by_the_impact_depth_and_falls_with_the_step() {
    let case = cases::bounce();
    let cases::Reference::Analytic(exact) = &case.reference else { panic!("the bounce has an analytic reference") };
    let steps = [1.0 / 60.0, 1.0 / 240.0, 1.0 / 960.0, 1.0 / 1920.0, 1.0 / 3840.0];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| {
            let run = case.run(&SimulationSettings { time_step: h, ..SimulationSettings::default() });
            case.error(&run.observable, exact)
        })
        .collect();
    for (&h, &error) in steps.iter().zip(&errors) {
        assert!(error <= bound(h), "step 1/{:.0}: error {error:.3e} above the bound {:.3e}", 1.0 / h, bound(h));
    }
    // Below h = 2λ/v ≈ 1/1100 s the bound itself halves with the step; the error must fall
    // with it at each refinement (1/960 → 1/1920 → 1/3840), not just stay under it.
    for k in 2..steps.len() - 1 {
        assert!(errors[k + 1] < errors[k], "error did not fall from step {} to {}: {errors:?}", k, k + 1);
    }
}

#[test]
fn sliding_stop_distance_is_within_the_last_step() {
    // The trapezoidal move is exact for the constant deceleration μ g; the only error left is
    // where the stop falls inside the last sub-step, where the speed is at most μ g h and the
    // distance off by at most μ g h² / 2 (1.7e-4 m at the default step, 4.2e-4 of v0²/(2μg)).
    let case = cases::sliding_stop();
    let cases::Reference::Analytic(exact) = &case.reference else { panic!("analytic") };
    let h = SimulationSettings::default().time_step;
    let run = case.run(&SimulationSettings::default());
    let bound = 0.5 * 0.5 * cases::G * h * h / exact[0];
    let error = case.error(&run.observable, exact);
    assert!(error <= bound, "error {error:.3e} above μ g h²/2 relative {bound:.3e}");
}

#[test]
fn rolling_matches_the_rolling_radius_of_the_contact_model() {
    // Against v_R for the rolling radius r + d/2 the only error is the spline circle's radius and
    // inertia (each within 1e-6 relative for 64 segments; the acceleration depends on them with
    // weights below 2): bound 1e-5. The offset from the nominal (2/3) g sin θ t is the band's
    // and is derived, so it must match the derivation to the same 1e-5 at every band.
    let case = cases::rolling();
    let cases::Reference::Analytic(exact) = &case.reference else { panic!("analytic") };
    let run = case.run(&SimulationSettings::default());
    let error = case.error(&run.observable, exact);
    assert!(error < 1e-5, "error {error:.3e} against the rolling radius");
    for offset in cases::rolling_offsets(&SimulationSettings::default()) {
        assert!(
            (offset.measured - offset.derived).abs() < 1e-5,
            "band {}: offset {:.4e}, derived {:.4e}",
            offset.band,
            offset.measured,
            offset.derived
        );
    }
}
