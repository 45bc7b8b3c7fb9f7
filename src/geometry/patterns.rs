//! Rugosity tolerances: the rules from a noise level to a tolerance, the pattern library, and
//! rugosity measured from a detailed outline (MODEL §2).

use std::f64::consts::TAU;

use glam::DVec2;
use rand::RngExt;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::ShapeError;
use crate::geometry::construct::interpolating_control_points;
use crate::geometry::multiresolution::{NoiseEstimator, decompose, segment_noise_levels};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;

/// How a segment's tolerance `R` follows from its noise level `S`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ToleranceRule {
    /// Tolerance interval `R = k·S` (MODEL §2; **our choice** default `k = 3`).
    ToleranceInterval {
        /// Multiple of `S`, finite and `≥ 0`.
        k: f64,
    },
    /// Donoho's universal threshold `R = S·sqrt(2 ln N)`, `N` the number of finest-level
    /// detail coefficients (one per pair of finest control points).
    UniversalThreshold,
}

impl Default for ToleranceRule {
    fn default() -> Self {
        Self::ToleranceInterval { k: 3.0 }
    }
}

impl ToleranceRule {
    /// Tolerance `R` for noise level `sigma`, with `finest_details` finest-level coefficients.
    ///
    /// # Errors
    /// [`ShapeError::InvalidParameter`] naming `tolerance_interval.k` (negative or non-finite),
    /// `tolerance.sigma` (negative or non-finite) or `universal_threshold.details` (`N < 1`).
    pub fn tolerance(&self, sigma: f64, finest_details: usize) -> Result<f64, ShapeError> {
        check_non_negative("tolerance.sigma", sigma)?;
        match *self {
            Self::ToleranceInterval { k } => {
                check_non_negative("tolerance_interval.k", k)?;
                Ok(k * sigma)
            }
            Self::UniversalThreshold if finest_details == 0 => {
                Err(ShapeError::parameter("universal_threshold.details", "needs at least one detail coefficient"))
            }
            Self::UniversalThreshold => Ok(sigma * (2.0 * (finest_details as f64).ln()).sqrt()),
        }
    }
}

/// The library of rugosity patterns: how the tolerance `R_i` varies over the segments of a
/// boundary (MODEL §2, **our choice** for the seed's four types).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum RugosityPattern {
    /// Type 1: the same tolerance on every segment.
    Constant {
        /// Tolerance (m), finite and `≥ 0`.
        value: f64,
    },
    /// Type 2: smooth sinusoidal variation along the boundary,
    /// `R_i = max(0, mean + amplitude · sin(2π · periods · (i + ½)/n + phase))`.
    Smooth {
        /// Mean tolerance (m), finite and `≥ 0`.
        mean: f64,
        /// Amplitude of the variation (m), finite and `≥ 0`.
        amplitude: f64,
        /// Whole periods around the boundary (an integer keeps the pattern continuous where
        /// the closed curve meets itself).
        periods: u32,
        /// Phase (rad), finite.
        phase: f64,
    },
    /// Type 3: non-homogeneous random, `R_i ~ N(mean, std_dev²)` independently per segment from
    /// a generator seeded with `seed`, clamped at 0.
    Random {
        /// Mean tolerance (m), finite and `≥ 0`.
        mean: f64,
        /// Standard deviation (m), finite and `≥ 0`.
        std_dev: f64,
        /// Seed of the generator: the same seed gives the same tolerances.
        seed: u64,
    },
    /// Type 4: patches. The boundary is cut into `2·patches` arcs of whole segments, at
    /// `2·patches − 1` distinct cut points drawn (seeded) from the segment joints `1..n`; arcs
    /// alternate rough, smooth, rough, … starting with a rough arc at segment 0, so around the
    /// closed boundary every rough arc lies between two smooth ones.
    Patches {
        /// Tolerance of the rough arcs (m), finite and `≥ 0`.
        rough: f64,
        /// Tolerance of the smooth arcs (m), finite and `≥ 0`.
        smooth: f64,
        /// Number of rough arcs (as many smooth arcs), `≥ 1` and at most half the segments.
        patches: usize,
        /// Seed of the arc lengths.
        seed: u64,
    },
}

impl RugosityPattern {
    /// The seed's type number, 1 to 4.
    #[must_use]
    pub fn type_number(&self) -> u8 {
        match self {
            Self::Constant { .. } => 1,
            Self::Smooth { .. } => 2,
            Self::Random { .. } => 3,
            Self::Patches { .. } => 4,
        }
    }

    /// The tolerance of each of `segments` segments.
    ///
    /// # Errors
    /// [`ShapeError::InvalidParameter`] naming the offending parameter, e.g. `random.std_dev`,
    /// or `<type>.segments` for zero segments.
    pub fn tolerances(&self, segments: usize) -> Result<Vec<f64>, ShapeError> {
        if segments == 0 {
            return Err(ShapeError::parameter(format!("{}.segments", self.name()), "needs at least one segment"));
        }
        match *self {
            Self::Constant { value } => {
                check_non_negative("constant.value", value)?;
                Ok(vec![value; segments])
            }
            Self::Smooth { mean, amplitude, periods, phase } => smooth(segments, mean, amplitude, periods, phase),
            Self::Random { mean, std_dev, seed } => random(segments, mean, std_dev, seed),
            Self::Patches { rough, smooth, patches, seed } => patches_pattern(segments, rough, smooth, patches, seed),
        }
    }

    /// The pattern as a [`Rugosity`] on `segments` segments.
    ///
    /// # Errors
    /// As [`RugosityPattern::tolerances`].
    pub fn rugosity(&self, segments: usize) -> Result<Rugosity, ShapeError> {
        Rugosity::new(self.tolerances(segments)?)
    }

    fn name(&self) -> &'static str {
        match self {
            Self::Constant { .. } => "constant",
            Self::Smooth { .. } => "smooth",
            Self::Random { .. } => "random",
            Self::Patches { .. } => "patches",
        }
    }
}

fn check_non_negative(what: &str, value: f64) -> Result<(), ShapeError> {
    if !value.is_finite() {
        return Err(ShapeError::parameter(what, format!("{value} is not finite")));
    }
    if value < 0.0 {
        return Err(ShapeError::parameter(what, format!("{value} is negative; it must be >= 0")));
    }
    Ok(())
}

fn smooth(segments: usize, mean: f64, amplitude: f64, periods: u32, phase: f64) -> Result<Vec<f64>, ShapeError> {
    check_non_negative("smooth.mean", mean)?;
    check_non_negative("smooth.amplitude", amplitude)?;
    if !phase.is_finite() {
        return Err(ShapeError::parameter("smooth.phase", format!("{phase} is not finite")));
    }
    let n = segments as f64;
    Ok((0..segments)
        .map(|i| (mean + amplitude * (TAU * f64::from(periods) * (i as f64 + 0.5) / n + phase).sin()).max(0.0))
        .collect())
}

fn random(segments: usize, mean: f64, std_dev: f64, seed: u64) -> Result<Vec<f64>, ShapeError> {
    check_non_negative("random.mean", mean)?;
    check_non_negative("random.std_dev", std_dev)?;
    let normal = Normal::new(mean, std_dev).map_err(|e| ShapeError::parameter("random.std_dev", e.to_string()))?;
    let mut rng = crate::random::seeded(seed);
    Ok((0..segments).map(|_| normal.sample(&mut rng).max(0.0)).collect())
}

fn patches_pattern(
    segments: usize,
    rough: f64,
    smooth: f64,
    patches: usize,
    seed: u64,
) -> Result<Vec<f64>, ShapeError> {
    check_non_negative("patches.rough", rough)?;
    check_non_negative("patches.smooth", smooth)?;
    if patches == 0 || patches > segments / 2 {
        return Err(ShapeError::parameter(
            "patches.patches",
            format!("{patches} rough patches need 1 <= patches <= segments/2 = {}", segments / 2),
        ));
    }
    let cuts = arc_cuts(segments, 2 * patches, seed);
    let mut tolerances = Vec::with_capacity(segments);
    let mut start = 0;
    for (arc, &end) in cuts.iter().chain(std::iter::once(&segments)).enumerate() {
        let value = if arc % 2 == 0 { rough } else { smooth };
        tolerances.extend(std::iter::repeat_n(value, end - start));
        start = end;
    }
    Ok(tolerances)
}

/// `arcs − 1` distinct sorted cut points from `1..segments` (partial Fisher–Yates, seeded).
fn arc_cuts(segments: usize, arcs: usize, seed: u64) -> Vec<usize> {
    let mut rng = crate::random::seeded(seed);
    let mut joints: Vec<usize> = (1..segments).collect();
    for k in 0..arcs - 1 {
        let pick = rng.random_range(k..joints.len());
        joints.swap(k, pick);
    }
    joints.truncate(arcs - 1);
    joints.sort_unstable();
    joints
}

/// Rugosity measured from a detailed closed outline.
///
/// `points` (dense, closed, either orientation) are interpolated by a fine periodic cubic
/// B-spline ([`interpolating_control_points`]), oriented counter-clockwise, decomposed `levels`
/// times, and the coarse polygon becomes the returned curve. Each coarse segment's noise level
/// `S` comes from its finest-level details ([`segment_noise_levels`]: normal components, divided
/// by the detail filter gain, so `S` is the standard deviation of the fine **control points**'
/// displacement); `rule` turns it into the tolerance, with `N = points.len() / 2` for the
/// universal threshold.
///
/// If the outline *points* carry i.i.d. noise instead, the interpolation amplifies it on its way
/// to the control points (its inverse has gain up to 3 at the highest frequency); the estimate
/// then measures the control-point roughness that reproduces the outline.
///
/// # Errors
/// As [`interpolating_control_points`], [`decompose`] (count not divisible by `2^levels`, fewer
/// than 4 coarse points) and [`Spline::from_control_points`];
/// [`ShapeError::InvalidParameter`] (`noise.levels`) for `levels = 0`, or from `rule`.
pub fn rugosity_from_outline(
    points: &[DVec2],
    levels: usize,
    rule: ToleranceRule,
    estimator: NoiseEstimator,
) -> Result<(Spline, Rugosity), ShapeError> {
    let mut fine = interpolating_control_points(points)?;
    if Spline::from_control_points_unchecked(fine.clone()).signed_area() < 0.0 {
        fine.reverse();
    }
    let decomposition = decompose(&fine, levels)?;
    let sigmas = segment_noise_levels(&decomposition, estimator)?;
    let curve = Spline::from_control_points(decomposition.coarse().to_vec())?;
    if curve.control_points() != decomposition.coarse() {
        return Err(ShapeError::parameter(
            "outline.levels",
            "the coarse curve runs opposite to the outline: too few coarse points to follow it",
        ));
    }
    let finest_details = fine.len() / 2;
    let tolerances = sigmas.iter().map(|&s| rule.tolerance(s, finest_details)).collect::<Result<Vec<_>, _>>()?;
    Ok((curve, Rugosity::new(tolerances)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_cuts_are_distinct_sorted_interior_joints() {
        for seed in 0..20 {
            let cuts = arc_cuts(10, 10, seed);
            assert_eq!(cuts, (1..10).collect::<Vec<_>>());
            let cuts = arc_cuts(50, 6, seed);
            assert_eq!(cuts.len(), 5);
            assert!(cuts.windows(2).all(|w| w[0] < w[1]) && cuts[0] >= 1 && cuts[4] < 50);
        }
    }
}
