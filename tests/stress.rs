//! Stress suite at CI sizes: the cases of `tests/common/stress_cases.rs` (which states every
//! bound and its derivation), each asserting finite states, no tunnelling, penetration within
//! the band, no energy gain beyond the band's slack and creep below its bound. The same cases
//! at full size: `cargo run --release --example stability_report` (writes docs/stability.md).
//!
//! `pyramid` runs base 5 here and base 20 (210 boxes) in the report, where its top ends
//! 3.0 mm from its start against a 5 mm bound (docs/stability.md; 9.7 mm, a failure, while
//! the contact solver ran a fixed 30 sweeps).

mod common;
#[path = "common/stress_cases.rs"]
mod stress_cases;

use stress_cases::{Size, case, run};

/// Runs the case at CI size and fails with every broken bound.
fn check(name: &str) {
    let measured = run(case(name), Size::Ci);
    eprintln!("{measured:?}");
    let failures = measured.failures();
    assert!(failures.is_empty(), "{name}: {}", failures.join("; "));
}

macro_rules! stress_tests {
    ($($(#[$attribute:meta])* $name:ident),* $(,)?) => {
        $(
            #[test]
            $(#[$attribute])*
            fn $name() {
                check(stringify!($name));
            }
        )*
    };
}

stress_tests!(
    heavy_on_light,
    light_on_heavy,
    thin_wall,
    scale_millimetre,
    scale_kilometre,
    repeated_points,
    collinear_points,
    c_shape,
    segments_1024,
    stack_of_10,
    pyramid,
    pile,
    resting_flat,
    resting_slope,
    restitution_0,
    restitution_1,
    spinning,
);

#[test]
fn every_case_has_a_test() {
    // The macro above must list every case of the shared table (so none is silently skipped).
    let listed = include_str!("stress.rs");
    for case in &stress_cases::CASES {
        assert!(listed.contains(&format!("    {},\n", case.name)), "no test for stress case {}", case.name);
    }
}
