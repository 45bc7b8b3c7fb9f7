//! The bounce of the work-precision report (`examples/work_precision`) converges in the step:
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
