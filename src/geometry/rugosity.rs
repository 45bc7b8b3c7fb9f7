//! Per-segment rugosity tolerances and the continuous tolerance λ(u) (MODEL §2, seed 4.1).

use serde::{Deserialize, Serialize};

use crate::error::ShapeError;

/// Rugosity of a boundary: one tolerance `R_i ≥ 0` per segment, the half-width of the band
/// that stands for surface detail finer than the explicit curve.
///
/// `R_i` sits at the segment midpoint `u = i + ½`; [`Rugosity::tolerance_at`] interpolates
/// between midpoints with a cubic through four neighbouring samples (MODEL §2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rugosity {
    tolerances: Vec<f64>,
    /// `Some(R)` when every segment has the same tolerance `R`: λ is then that constant.
    constant: Option<f64>,
}

impl Rugosity {
    /// Rugosity from per-segment tolerances.
    ///
    /// # Errors
    /// [`ShapeError::InvalidRugosity`] for a negative or non-finite value.
    pub fn new(tolerances: Vec<f64>) -> Result<Self, ShapeError> {
        check_tolerances(&tolerances)?;
        let constant = tolerances.first().copied().filter(|&r| tolerances.iter().all(|&x| x == r));
        Ok(Self { tolerances, constant })
    }

    /// The same tolerance on each of `segments` segments.
    ///
    /// # Errors
    /// [`ShapeError::InvalidRugosity`] for a negative or non-finite value.
    pub fn constant(segments: usize, tolerance: f64) -> Result<Self, ShapeError> {
        Self::new(vec![tolerance; segments])
    }

    /// Checks the invariants against a curve with `segments` segments.
    ///
    /// # Errors
    /// [`ShapeError::RugosityLength`] or [`ShapeError::InvalidRugosity`].
    pub fn validate(&self, segments: usize) -> Result<(), ShapeError> {
        if self.tolerances.len() != segments {
            return Err(ShapeError::RugosityLength { expected: segments, got: self.tolerances.len() });
        }
        check_tolerances(&self.tolerances)
    }

    /// The per-segment tolerances `R_i`.
    #[must_use]
    pub fn tolerances(&self) -> &[f64] {
        &self.tolerances
    }

    /// `Some(R)` when the tolerance is the same on every segment.
    #[must_use]
    pub fn constant_value(&self) -> Option<f64> {
        self.constant
    }

    fn sample(&self, j: isize) -> f64 {
        let n = self.tolerances.len() as isize;
        self.tolerances[j.rem_euclid(n) as usize]
    }

    /// The interpolating cubic between midpoints `j + ½` and `j + 1 + ½`, as its four samples.
    fn piece(&self, j: isize) -> [f64; 4] {
        [self.sample(j - 1), self.sample(j), self.sample(j + 1), self.sample(j + 2)]
    }

    /// Continuous tolerance λ at global parameter `u` (clamped at 0).
    #[must_use]
    pub fn tolerance_at(&self, u: f64) -> f64 {
        if let Some(r) = self.constant {
            return r;
        }
        let n = self.tolerances.len() as f64;
        let s = (u - 0.5).rem_euclid(n);
        let j = s.floor();
        lagrange_cubic(self.piece(j as isize), s - j).max(0.0)
    }

    /// Continuous tolerance λ at local parameter `t` of segment `segment`.
    #[must_use]
    pub fn tolerance_on_segment(&self, segment: usize, t: f64) -> f64 {
        self.tolerance_at(segment as f64 + t)
    }

    /// Maximum of λ over segment `segment` (`u ∈ [i, i+1]`), exact for the cubic pieces.
    #[must_use]
    pub fn max_on_segment(&self, segment: usize) -> f64 {
        if let Some(r) = self.constant {
            return r;
        }
        let i = segment as isize;
        let first = max_of_cubic(self.piece(i - 1), 0.5, 1.0);
        let second = max_of_cubic(self.piece(i), 0.0, 0.5);
        first.max(second).max(0.0)
    }

    /// The tolerance over one segment as plain data, floored at `floor` (the minimum band).
    #[must_use]
    pub fn segment_tolerance(&self, segment: usize, floor: f64) -> SegmentTolerance {
        let i = segment as isize;
        let pieces = match self.constant {
            Some(r) => [[r; 4]; 2],
            None => [self.piece(i - 1), self.piece(i)],
        };
        SegmentTolerance {
            pieces,
            max: self.max_on_segment(segment).max(floor),
            floor,
            constant: self.constant.is_some(),
        }
    }

    /// [`Rugosity::segment_tolerance`] of every segment at once where the tolerance is the same
    /// on each (the same value, worked out once), else `None`.
    #[must_use]
    pub fn uniform_tolerance(&self, floor: f64) -> Option<SegmentTolerance> {
        self.constant.map(|r| SegmentTolerance::constant(r, floor))
    }

    /// Largest tolerance on the whole boundary.
    #[must_use]
    pub fn max_tolerance(&self) -> f64 {
        (0..self.tolerances.len()).map(|i| self.max_on_segment(i)).fold(0.0, f64::max)
    }

    /// A body's band: its largest tolerance, floored at `min_band` (the floor of smooth
    /// surfaces, `SimulationSettings::min_band`).
    #[must_use]
    pub fn body_band(&self, min_band: f64) -> f64 {
        self.max_tolerance().max(min_band)
    }
}

/// λ over one segment `t ∈ [0, 1]`: two Lagrange cubics (for `t < ½` and `t ≥ ½`), floored.
///
/// Plain `Copy` data so the curve-pair solver can evaluate λ without touching the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentTolerance {
    /// Samples of the cubic pieces: `pieces[0]` covers `t < ½`, `pieces[1]` covers `t ≥ ½`.
    pieces: [[f64; 4]; 2],
    /// Maximum of the floored λ over the segment.
    pub max: f64,
    /// The minimum band: λ is never reported below it.
    pub floor: f64,
    constant: bool,
}

impl SegmentTolerance {
    /// A constant tolerance (floored).
    #[must_use]
    pub fn constant(value: f64, floor: f64) -> Self {
        Self { pieces: [[value; 4]; 2], max: value.max(floor), floor, constant: true }
    }

    /// λ at local parameter `t ∈ [0, 1]`, never below the floor.
    #[must_use]
    pub fn at(&self, t: f64) -> f64 {
        let raw = if self.constant {
            self.pieces[0][0]
        } else if t < 0.5 {
            lagrange_cubic(self.pieces[0], t + 0.5)
        } else {
            lagrange_cubic(self.pieces[1], t - 0.5)
        };
        raw.max(self.floor)
    }

    /// The floored λ when it is the same all over the segment (a constant rugosity).
    #[must_use]
    pub fn uniform(&self) -> Option<f64> {
        self.constant.then(|| self.pieces[0][0].max(self.floor))
    }

    /// λ at `t` without the floor (clamped at 0): the surface's own tolerance, used for friction.
    #[must_use]
    pub fn raw_at(&self, t: f64) -> f64 {
        if self.constant {
            self.pieces[0][0]
        } else if t < 0.5 {
            lagrange_cubic(self.pieces[0], t + 0.5).max(0.0)
        } else {
            lagrange_cubic(self.pieces[1], t - 0.5).max(0.0)
        }
    }
}

fn check_tolerances(tolerances: &[f64]) -> Result<(), ShapeError> {
    match tolerances.iter().enumerate().find(|(_, r)| !r.is_finite() || **r < 0.0) {
        Some((segment, &value)) => Err(ShapeError::InvalidRugosity { segment, value }),
        None => Ok(()),
    }
}

/// Cubic through `(−1, y0), (0, y1), (1, y2), (2, y3)` evaluated at `x`.
#[must_use]
pub fn lagrange_cubic([y0, y1, y2, y3]: [f64; 4], x: f64) -> f64 {
    let l0 = -x * (x - 1.0) * (x - 2.0) / 6.0;
    let l1 = (x + 1.0) * (x - 1.0) * (x - 2.0) / 2.0;
    let l2 = -(x + 1.0) * x * (x - 2.0) / 2.0;
    let l3 = (x + 1.0) * x * (x - 1.0) / 6.0;
    y0 * l0 + y1 * l1 + y2 * l2 + y3 * l3
}

/// Maximum of [`lagrange_cubic`] over `[x0, x1]`: end points and interior critical points.
fn max_of_cubic(samples: [f64; 4], x0: f64, x1: f64) -> f64 {
    let [y0, y1, y2, y3] = samples;
    // Power form c3 x³ + c2 x² + c1 x + c0 of the Lagrange cubic.
    let c3 = (-y0 + 3.0 * y1 - 3.0 * y2 + y3) / 6.0;
    let c2 = (y0 - 2.0 * y1 + y2) / 2.0;
    let c1 = (-2.0 * y0 - 3.0 * y1 + 6.0 * y2 - y3) / 6.0;
    let mut best = lagrange_cubic(samples, x0).max(lagrange_cubic(samples, x1));
    let width = x1 - x0;
    // Critical points: 3 c3 x² + 2 c2 x + c1 = 0, searched on the rescaled interval.
    let (a, b, c) =
        (3.0 * c3 * width * width, (6.0 * c3 * x0 + 2.0 * c2) * width, 3.0 * c3 * x0 * x0 + 2.0 * c2 * x0 + c1);
    for r in crate::geometry::quadrature::unit_roots_of_quadratic(a, b, c).into_iter().flatten() {
        best = best.max(lagrange_cubic(samples, x0 + r * width));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_tolerance_is_each_segments() {
        let constant = Rugosity::constant(5, 0.002).unwrap();
        for floor in [0.0, 0.001, 0.003] {
            let uniform = constant.uniform_tolerance(floor).unwrap();
            for segment in 0..5 {
                assert_eq!(uniform, constant.segment_tolerance(segment, floor));
            }
        }
        assert_eq!(Rugosity::new(vec![0.001, 0.002, 0.001]).unwrap().uniform_tolerance(0.001), None);
    }

    #[test]
    fn lagrange_cubic_interpolates_its_samples() {
        let y = [0.3, 1.0, -2.0, 0.5];
        for (k, &v) in y.iter().enumerate() {
            assert!((lagrange_cubic(y, k as f64 - 1.0) - v).abs() < 1e-15);
        }
    }

    #[test]
    fn tolerance_hits_the_samples_at_midpoints() {
        let r = Rugosity::new(vec![0.1, 0.3, 0.2, 0.05, 0.4]).unwrap();
        for (i, &v) in r.tolerances().iter().enumerate() {
            assert!((r.tolerance_at(i as f64 + 0.5) - v).abs() < 1e-15);
        }
    }

    #[test]
    fn tolerance_is_continuous_across_joints_and_midpoints() {
        // The cubic pieces change at the midpoints u = i + ½ (and segments at u = i): the left
        // and right limits must agree there, as a jump in λ would make friction jump.
        let r = Rugosity::new(vec![0.1, 0.9, 0.0, 0.05, 0.4, 0.7, 0.2]).unwrap();
        let eps = 1e-12;
        for k in 0..14 {
            let u = 0.5 * k as f64;
            let (left, right) = (r.tolerance_at(u - eps), r.tolerance_at(u + eps));
            assert!((left - right).abs() < 1e-10, "jump at u = {u}: {left} vs {right}");
            if k % 2 == 0 {
                let i = k / 2;
                let end_of_previous = r.tolerance_on_segment((i + 6) % 7, 1.0);
                let start_of_next = r.tolerance_on_segment(i, 0.0);
                assert!((end_of_previous - start_of_next).abs() < 1e-15, "joint {i}");
            }
        }
    }

    #[test]
    fn max_on_segment_bounds_dense_samples() {
        let r = Rugosity::new(vec![0.1, 0.9, 0.0, 0.05, 0.4, 0.7]).unwrap();
        for i in 0..6 {
            let sampled = (0..=10_000).map(|k| r.tolerance_on_segment(i, k as f64 / 1e4)).fold(0.0, f64::max);
            let exact = r.max_on_segment(i);
            assert!(exact >= sampled - 1e-15, "segment {i}: {exact} < {sampled}");
            assert!(exact - sampled < 1e-7, "segment {i}: {exact} vs {sampled}");
        }
    }

    #[test]
    fn segment_tolerance_matches_the_global_lambda() {
        let r = Rugosity::new(vec![0.1, 0.9, 0.0, 0.05, 0.4, 0.7]).unwrap();
        for i in 0..6 {
            let seg = r.segment_tolerance(i, 0.0);
            for k in 0..=20 {
                let t = k as f64 / 20.0;
                assert!((seg.at(t) - r.tolerance_on_segment(i, t)).abs() < 1e-15, "segment {i} t {t}");
            }
            assert_eq!(seg.max, r.max_on_segment(i));
            assert!(r.segment_tolerance(i, 0.5).at(0.3) >= 0.5);
        }
    }

    #[test]
    fn constant_rugosity_takes_the_fast_path() {
        let r = Rugosity::constant(8, 0.02).unwrap();
        assert_eq!(r.constant_value(), Some(0.02));
        assert_eq!(r.tolerance_at(3.7), 0.02);
        assert_eq!(r.max_on_segment(5), 0.02);
    }
}
