//! Multiresolution of periodic cubic B-splines: Lane–Riesenfeld synthesis and local
//! reverse-subdivision analysis (Bartels–Samavati), MODEL §2.
//!
//! One step maps a fine closed control polygon `f` (2n points) to a coarse polygon `c = A·f`
//! (n points) and details `d = B·f` (n vectors), and back by `f = P·c + Q·d`, exactly:
//! `A·P = I`, `B·P = 0`, `A·Q = 0`, `B·Q = I` and `P·A + Q·B = I`.
//!
//! **Index alignment.** Fine control point `f_k` sits at fine parameter `k`, which is coarse
//! parameter `k/2`: even points `f_{2i}` belong to coarse points `c_i`, odd points `f_{2i+1}` to
//! the midpoint `u = i + ½` of coarse segment `i`. The coarse filter row `i` is centred on
//! `f_{2i}`; the detail filter row `i` and the reconstruction column `i` are centred on
//! `f_{2i+1}`. So detail `d_i` is a bump of the curve centred on the midpoint of coarse segment
//! `i` and confined to `u ∈ [i − 2, i + 3]` (see [`Decomposition::detail_parameter`]).
//!
//! **Noise level.** [`segment_noise_levels`] estimates, per coarse segment, the standard
//! deviation `S` of i.i.d. `N(0, S²)` displacements of the finest control points (MODEL §2).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::ShapeError;
use crate::geometry::spline::Spline;

/// Taps of the coarse filter A: `c_i` from fine points `f_{2i-3} .. f_{2i+3}`.
pub const ANALYSIS_COARSE_TAPS: [f64; 7] =
    [23.0 / 196.0, -23.0 / 49.0, 9.0 / 28.0, 52.0 / 49.0, 9.0 / 28.0, -23.0 / 49.0, 23.0 / 196.0];

/// Taps of the detail filter B: `d_i` from fine points `f_{2i-1} .. f_{2i+3}`.
pub const ANALYSIS_DETAIL_TAPS: [f64; 5] =
    [13.0 / 98.0, -4.0 * 13.0 / 98.0, 6.0 * 13.0 / 98.0, -4.0 * 13.0 / 98.0, 13.0 / 98.0];

/// Taps of the reconstruction filter Q: detail `d_i` adds to fine points `f_{2i-2} .. f_{2i+4}`.
///
/// Derived as the detail columns of `[A; B]⁻¹`, solved in exact rational arithmetic for
/// periodic polygons of 4, 8 and 16 coarse points; the column is the same for every size.
pub const SYNTHESIS_DETAIL_TAPS: [f64; 7] =
    [-23.0 / 208.0, -23.0 / 52.0, -63.0 / 208.0, 1.0, -63.0 / 208.0, -23.0 / 52.0, -23.0 / 208.0];

/// `Σ b²` over [`ANALYSIS_DETAIL_TAPS`] (= 11830/9604 ≈ 1.2318): the variance gain of one detail
/// component when the fine control points carry i.i.d. unit-variance noise.
pub const DETAIL_NOISE_GAIN: f64 = 70.0 * 169.0 / 9604.0;

/// `Φ⁻¹(¾)`: the median of `|X|` for `X ~ N(0, 1)`, the Donoho–Johnstone constant (≈ 0.6745).
pub const MEDIAN_ABSOLUTE_NORMAL: f64 = 0.674_489_750_196_081_7;

/// Offset of the first fine point of coarse row `i` relative to `2i`.
const COARSE_OFFSET: isize = -3;
/// Offset of the first fine point of detail row `i` relative to `2i`.
const DETAIL_OFFSET: isize = -1;
/// Offset of the first fine point of reconstruction column `i` relative to `2i`.
const SYNTHESIS_OFFSET: isize = -2;

fn at(points: &[DVec2], i: isize) -> DVec2 {
    points[i.rem_euclid(points.len() as isize) as usize]
}

/// `Σ_k taps[k] · points[start + k]` with periodic indexing.
fn weighted_sum(points: &[DVec2], start: isize, taps: &[f64]) -> DVec2 {
    taps.iter().enumerate().fold(DVec2::ZERO, |acc, (k, &w)| acc + w * at(points, start + k as isize))
}

/// One Lane–Riesenfeld subdivision of a closed control polygon (n → 2n points):
/// `f_{2i} = (c_{i-1} + 6c_i + c_{i+1})/8`, `f_{2i+1} = (c_i + c_{i+1})/2`. Same curve, finer polygon,
/// with fine parameter `2u` at coarse parameter `u`.
#[must_use]
pub fn subdivide(coarse: &[DVec2]) -> Vec<DVec2> {
    let mut fine = Vec::with_capacity(coarse.len() * 2);
    for i in 0..coarse.len() as isize {
        fine.push((at(coarse, i - 1) + 6.0 * at(coarse, i) + at(coarse, i + 1)) / 8.0);
        fine.push((at(coarse, i) + at(coarse, i + 1)) / 2.0);
    }
    fine
}

/// One analysis step of a closed control polygon with an even number of points (2n → n + n):
/// returns `(coarse, details)`. `None` when the count is odd or the coarse polygon would have
/// fewer than 4 points.
#[must_use]
pub fn reverse_subdivide(fine: &[DVec2]) -> Option<(Vec<DVec2>, Vec<DVec2>)> {
    if !fine.len().is_multiple_of(2) || fine.len() < 8 {
        return None;
    }
    let n = fine.len() / 2;
    let coarse = (0..n as isize).map(|i| weighted_sum(fine, 2 * i + COARSE_OFFSET, &ANALYSIS_COARSE_TAPS)).collect();
    let details = (0..n as isize).map(|i| weighted_sum(fine, 2 * i + DETAIL_OFFSET, &ANALYSIS_DETAIL_TAPS)).collect();
    Some((coarse, details))
}

/// One synthesis step, the inverse of [`reverse_subdivide`]: `fine = P·coarse + Q·details`.
///
/// # Errors
/// [`ShapeError::InvalidParameter`] (`synthesize.details`) when the two lists differ in length,
/// [`ShapeError::TooFewControlPoints`] for fewer than 4 coarse points.
pub fn synthesize(coarse: &[DVec2], details: &[DVec2]) -> Result<Vec<DVec2>, ShapeError> {
    if coarse.len() < 4 {
        return Err(ShapeError::TooFewControlPoints { count: coarse.len() });
    }
    if details.len() != coarse.len() {
        return Err(ShapeError::parameter(
            "synthesize.details",
            format!("{} details for {} coarse points: one per coarse point is needed", details.len(), coarse.len()),
        ));
    }
    let mut fine = subdivide(coarse);
    let m = fine.len() as isize;
    for (i, &d) in details.iter().enumerate() {
        let start = 2 * i as isize + SYNTHESIS_OFFSET;
        for (k, &q) in SYNTHESIS_DETAIL_TAPS.iter().enumerate() {
            fine[(start + k as isize).rem_euclid(m) as usize] += q * d;
        }
    }
    Ok(fine)
}

/// A closed control polygon split into a coarse polygon and the details of each level.
///
/// Levels are stored **coarsest first**: `details()[0]` has as many entries as the coarse
/// polygon and turns it into a polygon twice as fine; `details()[l]` has `coarse().len() · 2^l`
/// entries; the last level leads back to the original (finest) polygon. Built only through
/// [`decompose`] or [`Decomposition::from_parts`], which check those lengths (so it is not
/// `Deserialize`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Decomposition {
    coarse: Vec<DVec2>,
    details: Vec<Vec<DVec2>>,
}

impl Decomposition {
    /// Assembles a decomposition from a coarse polygon and its details, coarsest level first.
    ///
    /// # Errors
    /// [`ShapeError::TooFewControlPoints`] for fewer than 4 coarse points;
    /// [`ShapeError::InvalidParameter`] (`decomposition.details`) when level `l` does not hold
    /// `coarse.len() · 2^l` details.
    pub fn from_parts(coarse: Vec<DVec2>, details: Vec<Vec<DVec2>>) -> Result<Self, ShapeError> {
        if coarse.len() < 4 {
            return Err(ShapeError::TooFewControlPoints { count: coarse.len() });
        }
        for (level, level_details) in details.iter().enumerate() {
            let expected = coarse.len().checked_shl(level as u32).unwrap_or(0);
            if level_details.len() != expected {
                return Err(ShapeError::parameter(
                    "decomposition.details",
                    format!("level {level} holds {} details, expected {expected}", level_details.len()),
                ));
            }
        }
        Ok(Self { coarse, details })
    }

    /// The coarse control polygon.
    #[must_use]
    pub fn coarse(&self) -> &[DVec2] {
        &self.coarse
    }

    /// The details of every level, coarsest first.
    #[must_use]
    pub fn details(&self) -> &[Vec<DVec2>] {
        &self.details
    }

    /// Number of analysis levels.
    #[must_use]
    pub fn levels(&self) -> usize {
        self.details.len()
    }

    /// Number of points of the finest (original) polygon.
    #[must_use]
    pub fn fine_count(&self) -> usize {
        self.coarse.len() << self.details.len()
    }

    /// The coarse polygon and the details, coarsest first.
    #[must_use]
    pub fn into_parts(self) -> (Vec<DVec2>, Vec<Vec<DVec2>>) {
        (self.coarse, self.details)
    }

    /// Coarse-curve parameter `u` on which detail `index` of `level` (coarsest first) is centred:
    /// `(index + ½) / 2^level`, the midpoint of its level's segment `index`.
    ///
    /// Its bump on the curve spans `u ± 2.5 / 2^level` (reconstruction column of 7 fine points,
    /// each with a B-spline support of 4 fine segments).
    #[must_use]
    pub fn detail_parameter(&self, level: usize, index: usize) -> f64 {
        (index as f64 + 0.5) / (1u64 << level.min(63)) as f64
    }

    /// The coarse segment that detail `index` of `level` belongs to: `index / 2^level`, the
    /// segment that contains [`Decomposition::detail_parameter`].
    #[must_use]
    pub fn detail_segment(&self, level: usize, index: usize) -> usize {
        index.checked_shr(level as u32).unwrap_or(0)
    }
}

/// Decomposes a closed control polygon `levels` times (2^levels·n points → n coarse points).
///
/// `levels = 0` returns the polygon itself with no details.
///
/// # Errors
/// [`ShapeError::TooFewControlPoints`] or [`ShapeError::NonFiniteControlPoint`] for a bad
/// polygon; [`ShapeError::InvalidParameter`] (`decompose.levels`) when the count is not
/// divisible by `2^levels` or the coarse polygon would have fewer than 4 points.
pub fn decompose(fine_control_points: &[DVec2], levels: usize) -> Result<Decomposition, ShapeError> {
    check_polygon(fine_control_points)?;
    check_levels(fine_control_points.len(), levels)?;
    let mut current = fine_control_points.to_vec();
    let mut details = Vec::with_capacity(levels);
    for _ in 0..levels {
        let (coarse, level_details) = reverse_subdivide(&current)
            .ok_or_else(|| ShapeError::parameter("decompose.levels", "internal: odd or too small polygon"))?;
        details.push(level_details);
        current = coarse;
    }
    details.reverse();
    Ok(Decomposition { coarse: current, details })
}

/// Rebuilds the finest polygon from a decomposition: `f = P·c + Q·d`, coarsest level first.
#[must_use]
pub fn reconstruct(decomposition: &Decomposition) -> Vec<DVec2> {
    decomposition.details.iter().fold(decomposition.coarse.clone(), |coarse, details| {
        // Lengths are checked at construction, so synthesis cannot fail here.
        synthesize(&coarse, details).unwrap_or_default()
    })
}

fn check_polygon(points: &[DVec2]) -> Result<(), ShapeError> {
    if points.len() < 4 {
        return Err(ShapeError::TooFewControlPoints { count: points.len() });
    }
    match points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        Some((index, p)) => Err(ShapeError::NonFiniteControlPoint { index, x: p.x, y: p.y }),
        None => Ok(()),
    }
}

fn check_levels(count: usize, levels: usize) -> Result<(), ShapeError> {
    let factor = 1usize.checked_shl(levels as u32).filter(|_| levels < usize::BITS as usize);
    match factor {
        Some(f) if count.is_multiple_of(f) && count / f >= 4 => Ok(()),
        Some(f) if count.is_multiple_of(f) => Err(ShapeError::parameter(
            "decompose.levels",
            format!("{levels} levels leave {} coarse points from {count}; at least 4 are needed", count / f),
        )),
        _ => Err(ShapeError::parameter(
            "decompose.levels",
            format!("{count} control points are not divisible by 2^{levels}"),
        )),
    }
}

/// How the noise level `S` is estimated from detail components.
///
/// Both work on the component of each detail along the coarse curve's outward normal, divided
/// by `sqrt(`[`DETAIL_NOISE_GAIN`]`)` so the result is the standard deviation of the finest
/// control points' displacement, not of the details.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum NoiseEstimator {
    /// Root mean square about zero, `sqrt(mean d²)`: efficient for pure Gaussian noise.
    StandardDeviation,
    /// Donoho–Johnstone `median|d| / 0.6745`: robust to a few large details (corners, features
    /// the coarse level does not capture). The default.
    #[default]
    MedianAbsolute,
}

impl NoiseEstimator {
    /// Noise level `S` of the finest control points from detail normal components, or `None`
    /// for an empty list.
    #[must_use]
    pub fn estimate(self, normal_components: &[f64]) -> Option<f64> {
        if normal_components.is_empty() {
            return None;
        }
        let spread = match self {
            Self::StandardDeviation => {
                (normal_components.iter().map(|d| d * d).sum::<f64>() / normal_components.len() as f64).sqrt()
            }
            Self::MedianAbsolute => median_absolute(normal_components) / MEDIAN_ABSOLUTE_NORMAL,
        };
        Some(spread / DETAIL_NOISE_GAIN.sqrt())
    }
}

fn median_absolute(values: &[f64]) -> f64 {
    let mut magnitudes: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    magnitudes.sort_by(f64::total_cmp);
    let mid = magnitudes.len() / 2;
    if magnitudes.len() % 2 == 1 { magnitudes[mid] } else { 0.5 * (magnitudes[mid - 1] + magnitudes[mid]) }
}

/// Normal components of the finest-level details, grouped by the coarse segment they belong to.
///
/// Detail `j` of the finest level `L − 1` is centred at coarse parameter `u = (j + ½)/2^(L−1)`
/// and belongs to coarse segment `j / 2^(L−1)`; its component along the coarse curve's outward
/// normal at `u` is kept (the tangential component mostly slides points along the curve and
/// does not widen the band). Each segment gets `2^(L−1)` values.
///
/// # Errors
/// [`ShapeError::InvalidParameter`] (`noise.levels`) for a decomposition without details.
pub fn segment_normal_details(decomposition: &Decomposition) -> Result<Vec<Vec<f64>>, ShapeError> {
    let level = decomposition
        .levels()
        .checked_sub(1)
        .ok_or_else(|| ShapeError::parameter("noise.levels", "at least one level of details is needed"))?;
    let curve = Spline::from_control_points_unchecked(decomposition.coarse.clone());
    let mut groups = vec![Vec::with_capacity(1 << level); decomposition.coarse.len()];
    for (j, d) in decomposition.details[level].iter().enumerate() {
        let normal = curve.outward_normal(decomposition.detail_parameter(level, j));
        groups[decomposition.detail_segment(level, j)].push(d.dot(normal));
    }
    Ok(groups)
}

/// Noise level `S` per coarse segment, from that segment's finest-level details
/// (`segment_normal_details`) with `estimator`.
///
/// Only the finest level is used: coarser details of pure noise are attenuated by the coarse
/// filter, so whatever shape the coarse curve misses dominates them (Donoho–Johnstone estimate
/// the noise from the finest scale for the same reason).
///
/// # Errors
/// As `segment_normal_details`.
pub fn segment_noise_levels(decomposition: &Decomposition, estimator: NoiseEstimator) -> Result<Vec<f64>, ShapeError> {
    Ok(segment_normal_details(decomposition)?.iter().map(|g| estimator.estimate(g).unwrap_or(0.0)).collect())
}

/// Noise level `S` of the whole boundary: `estimator` over all finest-level normal components.
///
/// # Errors
/// As `segment_normal_details`.
pub fn noise_level(decomposition: &Decomposition, estimator: NoiseEstimator) -> Result<f64, ShapeError> {
    let all: Vec<f64> = segment_normal_details(decomposition)?.concat();
    Ok(estimator.estimate(&all).unwrap_or(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detail_noise_gain_is_the_sum_of_squared_taps() {
        let sum: f64 = ANALYSIS_DETAIL_TAPS.iter().map(|b| b * b).sum();
        assert!((sum - DETAIL_NOISE_GAIN).abs() < 1e-15);
    }

    #[test]
    fn median_absolute_handles_odd_and_even_counts() {
        assert_eq!(median_absolute(&[-3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median_absolute(&[-3.0, 1.0, 2.0, -4.0]), 2.5);
    }

    #[test]
    fn levels_are_checked() {
        let square = vec![DVec2::ZERO; 24];
        assert!(check_levels(24, 2).is_ok());
        assert!(check_levels(24, 3).is_err()); // 24 / 8 = 3 < 4
        assert!(check_levels(20, 2).is_ok());
        assert!(check_levels(20, 3).is_err()); // not divisible
        assert!(check_levels(20, 200).is_err()); // shift overflow, no panic
        assert!(decompose(&square, 0).unwrap().details().is_empty());
    }
}
