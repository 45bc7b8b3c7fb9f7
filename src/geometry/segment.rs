//! One cubic piece of a boundary in Bézier form, with exact evaluation, bounds and splitting.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::pose::Pose;
use crate::geometry::quadrature::{gauss_legendre_16, unit_roots_of_quadratic};

/// A cubic Bézier piece `p(t)`, `t ∈ [0, 1]`, given by its four Bézier points.
///
/// The piece lies in the convex hull of its Bézier points, a tighter bound than the
/// B-spline control points it was made from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CubicSegment {
    /// Bézier control points `b0..b3`; `p(0) = b0`, `p(1) = b3`.
    pub bezier: [DVec2; 4],
}

/// Power-basis coefficients `p(t) = ((a t + b) t + c) t + d`.
#[derive(Clone, Copy, Debug)]
struct PowerBasis {
    a: DVec2,
    b: DVec2,
    c: DVec2,
    d: DVec2,
}

impl CubicSegment {
    /// The Bézier form of the uniform cubic B-spline piece with control points `c0..c3`
    /// (MODEL §1: `b0 = (c0+4c1+c2)/6`, `b1 = (2c1+c2)/3`, `b2 = (c1+2c2)/3`, `b3 = (c1+4c2+c3)/6`).
    #[must_use]
    pub fn from_bspline(c0: DVec2, c1: DVec2, c2: DVec2, c3: DVec2) -> Self {
        Self {
            bezier: [
                (c0 + 4.0 * c1 + c2) / 6.0,
                (2.0 * c1 + c2) / 3.0,
                (c1 + 2.0 * c2) / 3.0,
                (c1 + 4.0 * c2 + c3) / 6.0,
            ],
        }
    }

    fn power(&self) -> PowerBasis {
        let [b0, b1, b2, b3] = self.bezier;
        PowerBasis { a: -b0 + 3.0 * b1 - 3.0 * b2 + b3, b: 3.0 * b0 - 6.0 * b1 + 3.0 * b2, c: 3.0 * (b1 - b0), d: b0 }
    }

    /// The piece moved by `pose` (Bézier control points move with the curve).
    #[must_use]
    pub fn transformed(&self, pose: &Pose) -> Self {
        Self { bezier: self.bezier.map(|p| pose.transform_point(p)) }
    }

    /// Position at `t`.
    #[must_use]
    pub fn position(&self, t: f64) -> DVec2 {
        let p = self.power();
        ((p.a * t + p.b) * t + p.c) * t + p.d
    }

    /// First derivative `dp/dt` at `t`.
    #[must_use]
    pub fn derivative(&self, t: f64) -> DVec2 {
        let p = self.power();
        (3.0 * p.a * t + 2.0 * p.b) * t + p.c
    }

    /// Second derivative `d²p/dt²` at `t`.
    #[must_use]
    pub fn second_derivative(&self, t: f64) -> DVec2 {
        let p = self.power();
        6.0 * p.a * t + 2.0 * p.b
    }

    /// Third derivative `d³p/dt³`, the same at every `t` of a cubic.
    #[must_use]
    pub fn third_derivative(&self) -> DVec2 {
        6.0 * self.power().a
    }

    /// Position, first and second derivative at `t` in one pass.
    #[must_use]
    pub fn jet(&self, t: f64) -> [DVec2; 3] {
        let p = self.power();
        [((p.a * t + p.b) * t + p.c) * t + p.d, (3.0 * p.a * t + 2.0 * p.b) * t + p.c, 6.0 * p.a * t + 2.0 * p.b]
    }

    /// Splits at `t` by de Casteljau into the pieces over `[0, t]` and `[t, 1]`.
    #[must_use]
    pub fn split(&self, t: f64) -> (Self, Self) {
        let [b0, b1, b2, b3] = self.bezier;
        let p01 = b0.lerp(b1, t);
        let p12 = b1.lerp(b2, t);
        let p23 = b2.lerp(b3, t);
        let p012 = p01.lerp(p12, t);
        let p123 = p12.lerp(p23, t);
        let mid = p012.lerp(p123, t);
        (Self { bezier: [b0, p01, p012, mid] }, Self { bezier: [mid, p123, p23, b3] })
    }

    /// The piece restricted to `[t0, t1]`, reparametrized to `[0, 1]`.
    #[must_use]
    pub fn subsegment(&self, t0: f64, t1: f64) -> Self {
        if t1 <= t0 {
            let p = self.position(t0);
            return Self { bezier: [p; 4] };
        }
        let (_, right) = self.split(t0);
        let (piece, _) = right.split(((t1 - t0) / (1.0 - t0)).clamp(0.0, 1.0));
        if t0 >= 1.0 { Self { bezier: [self.bezier[3]; 4] } } else { piece }
    }

    /// Exact range of `p(t)·axis` over `t ∈ [0, 1]` (end points and the roots of the derivative).
    #[must_use]
    pub fn projection_range(&self, axis: DVec2) -> (f64, f64) {
        let p = self.power();
        let (a, b, c) = (p.a.dot(axis), p.b.dot(axis), p.c.dot(axis));
        let d = p.d.dot(axis);
        let value = |t: f64| ((a * t + b) * t + c) * t + d;
        let mut low = value(0.0).min(value(1.0));
        let mut high = value(0.0).max(value(1.0));
        for t in unit_roots_of_quadratic(3.0 * a, 2.0 * b, c).into_iter().flatten() {
            let v = value(t);
            low = low.min(v);
            high = high.max(v);
        }
        (low, high)
    }

    /// Tight axis-aligned bounds `(min, max)` of the piece.
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let (x0, x1) = self.projection_range(DVec2::X);
        let (y0, y1) = self.projection_range(DVec2::Y);
        (DVec2::new(x0, y0), DVec2::new(x1, y1))
    }

    /// Arc length over `[0, 1]` to near machine precision (adaptive 16-point Gauss–Legendre).
    #[must_use]
    pub fn arc_length(&self) -> f64 {
        self.arc_length_between(0.0, 1.0, 0)
    }

    fn arc_length_between(&self, t0: f64, t1: f64, depth: u32) -> f64 {
        let speed = |t: f64| self.derivative(t).length();
        let whole = gauss_legendre_16(t0, t1, speed);
        let mid = 0.5 * (t0 + t1);
        let halves = gauss_legendre_16(t0, mid, speed) + gauss_legendre_16(mid, t1, speed);
        if depth >= 12 || (whole - halves).abs() <= 1e-14 * halves.abs().max(f64::MIN_POSITIVE) {
            halves
        } else {
            self.arc_length_between(t0, mid, depth + 1) + self.arc_length_between(mid, t1, depth + 1)
        }
    }

    /// Squared distance lower bound: the distance from `point` to the axis-aligned box of the Bézier hull.
    #[must_use]
    pub fn hull_distance_squared_lower_bound(&self, point: DVec2) -> f64 {
        let low = self.bezier.iter().copied().fold(DVec2::splat(f64::INFINITY), DVec2::min);
        let high = self.bezier.iter().copied().fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
        let outside = (low - point).max(point - high).max(DVec2::ZERO);
        outside.length_squared()
    }

    /// Nearest point of the piece to `point`: `(t, distance)`.
    ///
    /// The stationary points of `|p(t) − x|²` are the roots of the quintic `(p(t) − x)·p'(t)`,
    /// whose Bernstein coefficients follow exactly from the Bézier points. Its sign changes
    /// from − to + (the minima) are isolated by subdividing the coefficients until each
    /// interval holds at most one sign change (Descartes' rule for Bernstein polynomials), then
    /// refined by safeguarded Newton; the end points are always candidates, so the global
    /// minimum is found whatever the shape (no grid to slip between two close roots).
    ///
    /// A straight piece whose Bézier points run in order along its chord (the sides of a rounded
    /// polygon) has one stationary point at most, where `point` projects inside the chord:
    /// there the isolation is skipped and the parameter found on the scalar cubic along the chord.
    #[must_use]
    pub fn nearest_parameter(&self, point: DVec2) -> (f64, f64) {
        if let Some(line) = self.straight() {
            let t = line.parameter(line.fraction(point));
            return (t, self.position(t).distance(point));
        }
        self.nearest_by_isolation(point)
    }

    /// The general path of [`Self::nearest_parameter`]: every minimum isolated and refined, and
    /// the end points.
    fn nearest_by_isolation(&self, point: DVec2) -> (f64, f64) {
        let mut best = (0.0, self.position(0.0).distance(point));
        let end = self.position(1.0).distance(point);
        if end < best.1 {
            best = (1.0, end);
        }
        let mut consider = |lo: f64, hi: f64| {
            let root = refine_minimum(self, point, lo, hi);
            let distance = self.position(root).distance(point);
            if distance < best.1 {
                best = (root, distance);
            }
        };
        isolate_minima(self.slope_coefficients(point), 0.0, 1.0, 0, &mut consider);
        best
    }

    /// The piece as a stretch of its chord, if it is straight (its inner Bézier points within
    /// [`STRAIGHT_TOLERANCE`] of the chord's length off it, or within the rounding of their
    /// coordinates) and runs monotonically along the chord (their projections in order, to the
    /// same tolerance). Then `p(t) = b₀ + (b₃ − b₀) φ(t)` with `φ` non-decreasing, so
    /// `(p(t) − x)·p'(t) = |b₃ − b₀|² φ'(t) (φ(t) − τ)` changes sign once, from − to +, where
    /// `φ(t) = τ`, the projection of `x`: the nearest point is there, or at the end nearer `τ`
    /// when `τ ∉ (0, 1)`.
    #[must_use]
    pub(crate) fn straight(&self) -> Option<StraightPiece> {
        let [b0, b1, b2, b3] = self.bezier;
        let chord = b3 - b0;
        let length_squared = chord.length_squared();
        let off = |b: DVec2| (b - b0).perp_dot(chord).abs();
        // Distances off and along the chord, times its length: the tolerance, and the rounding
        // of coordinates this far from the origin.
        let size = b0.abs().max(b3.abs()).max_element();
        let limit = (STRAIGHT_TOLERANCE * length_squared.sqrt() + 8.0 * f64::EPSILON * size) * length_squared.sqrt();
        // Written so that a NaN or a zero chord refuses the shortcut.
        if !(length_squared > 0.0 && off(b1) <= limit && off(b2) <= limit) {
            return None;
        }
        let along = |b: DVec2| (b - b0).dot(chord);
        let (c1, c2) = (along(b1), along(b2));
        let ordered = c1 >= -limit && c2 - c1 >= -limit && length_squared - c2 >= -limit;
        ordered.then_some(StraightPiece {
            start: b0,
            chord,
            length_squared,
            inner: (c1 / length_squared, c2 / length_squared),
        })
    }

    /// Bernstein coefficients (degree 5) of `(p(t) − x)·p'(t)`: the product of the cubic
    /// `Σ (b_i − x) B³_i` and the quadratic `Σ 3(b_{j+1} − b_j) B²_j`, with
    /// `B³_i B²_j = C(3,i) C(2,j) / C(5,i+j) B⁵_{i+j}`.
    fn slope_coefficients(&self, point: DVec2) -> [f64; 6] {
        const CUBIC: [f64; 4] = [1.0, 3.0, 3.0, 1.0];
        const QUADRATIC: [f64; 3] = [1.0, 2.0, 1.0];
        const QUINTIC: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
        let offsets = self.bezier.map(|b| b - point);
        let hodograph = [0, 1, 2].map(|j| 3.0 * (self.bezier[j + 1] - self.bezier[j]));
        let mut coefficients = [0.0; 6];
        for (i, offset) in offsets.iter().enumerate() {
            for (j, velocity) in hodograph.iter().enumerate() {
                coefficients[i + j] += CUBIC[i] * QUADRATIC[j] * offset.dot(*velocity);
            }
        }
        for (c, binomial) in coefficients.iter_mut().zip(QUINTIC) {
            *c /= binomial;
        }
        coefficients
    }
}

/// A straight piece (see [`CubicSegment::straight`]): `p(t) = start + chord φ(t)` with `φ`
/// non-decreasing, of Bernstein coefficients `0, φ₁, φ₂, 1` (`inner = (φ₁, φ₂)`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct StraightPiece {
    /// `b₀`.
    pub start: DVec2,
    /// `b₃ − b₀`.
    pub chord: DVec2,
    /// `|b₃ − b₀|²`.
    pub length_squared: f64,
    /// `(φ₁, φ₂)`.
    pub inner: (f64, f64),
}

impl StraightPiece {
    /// Where `point` projects on the chord, as a fraction `τ` of it.
    #[must_use]
    pub fn fraction(&self, point: DVec2) -> f64 {
        (point - self.start).dot(self.chord) / self.length_squared
    }

    /// The parameter `t` with `φ(t) = τ`: 0 for `τ ≤ 0`, 1 for `τ ≥ 1`, else the root of the
    /// scalar cubic from `τ` (exact for evenly spaced points) by safeguarded Newton.
    #[must_use]
    pub fn parameter(&self, tau: f64) -> f64 {
        if tau <= 0.0 {
            return 0.0;
        }
        if tau >= 1.0 {
            return 1.0;
        }
        let (c1, c2) = self.inner;
        let phi = |t: f64| {
            let u = 1.0 - t;
            let value = 3.0 * t * u * (c1 * u + c2 * t) + t * t * t - tau;
            (value, 3.0 * (c1 * u * u + 2.0 * (c2 - c1) * t * u + (1.0 - c2) * t * t))
        };
        safeguarded_root(phi, tau, 0.0, 1.0)
    }
}

/// The root in `[lo, hi]` of a function negative before it and positive after (`f` gives its
/// value and slope), by Newton from `start` inside a bracket that every evaluation narrows,
/// bisecting where Newton would leave it.
fn safeguarded_root(mut f: impl FnMut(f64) -> (f64, f64), start: f64, mut lo: f64, mut hi: f64) -> f64 {
    let mut t = start;
    for _ in 0..64 {
        let (value, slope) = f(t);
        if value == 0.0 {
            return t;
        }
        if value < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let newton = if slope > 0.0 { t - value / slope } else { f64::NAN };
        let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        // Converged: a Newton step within the bracket has stopped moving (it approaches the root
        // from one side, so the bracket itself need not shrink), or the bracket is that narrow.
        if (next - t).abs() <= 4.0 * f64::EPSILON || hi - lo <= 4.0 * f64::EPSILON {
            return next;
        }
        t = next;
    }
    t
}

/// How far (relative to the chord's length) the inner Bézier points of a piece may lie off its
/// chord, or behind each other along it, for the piece to count as straight in
/// [`CubicSegment::nearest_parameter`]: the sides of a rounded polygon are straight to rounding
/// (about 1e-16), and a deviation this small moves no answer by more than it.
const STRAIGHT_TOLERANCE: f64 = 1e-14;

/// Subdivision depth at which an interval still holding several sign changes is handed to the
/// refinement as it is (2⁻⁴⁰ of the parameter range: roots closer than that are one minimum).
const MAX_ISOLATION_DEPTH: u32 = 40;

/// Calls `consider(lo, hi)` for every subinterval of `[lo, hi]` in which the Bernstein
/// polynomial `coefficients` goes from negative to positive.
fn isolate_minima(coefficients: [f64; 6], lo: f64, hi: f64, depth: u32, consider: &mut impl FnMut(f64, f64)) {
    let changes = coefficients.windows(2).filter(|w| (w[0] < 0.0) != (w[1] < 0.0)).count();
    if changes == 0 {
        return;
    }
    let (first, last) = (coefficients[0], coefficients[5]);
    if changes == 1 || depth >= MAX_ISOLATION_DEPTH {
        if first < 0.0 && last >= 0.0 {
            consider(lo, hi);
        }
        return;
    }
    let (left, right) = split_bernstein(coefficients);
    let mid = 0.5 * (lo + hi);
    isolate_minima(left, lo, mid, depth + 1, consider);
    isolate_minima(right, mid, hi, depth + 1, consider);
}

/// de Casteljau split of a degree-5 Bernstein polynomial at ½.
fn split_bernstein(mut c: [f64; 6]) -> ([f64; 6], [f64; 6]) {
    let mut left = [0.0; 6];
    let mut right = [0.0; 6];
    for level in 0..6 {
        left[level] = c[0];
        right[5 - level] = c[5 - level];
        for k in 0..5 - level {
            c[k] = 0.5 * (c[k] + c[k + 1]);
        }
    }
    (left, right)
}

/// Finds the root of `(p(t) − x)·p'(t)` in a bracket `[lo, hi]` where it goes from − to +.
fn refine_minimum(segment: &CubicSegment, point: DVec2, lo: f64, hi: f64) -> f64 {
    // Start from the point's projection on the chord (nearly the answer on a nearly straight
    // piece), kept inside the bracket; the midpoint where the chord says nothing.
    let chord = segment.bezier[3] - segment.bezier[0];
    let along = (point - segment.bezier[0]).dot(chord) / chord.length_squared();
    let inside = along > lo && along < hi;
    let slope = |t: f64| {
        let [p, d, dd] = segment.jet(t);
        ((p - point).dot(d), d.length_squared() + (p - point).dot(dd))
    };
    safeguarded_root(slope, if inside { along } else { 0.5 * (lo + hi) }, lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_pieces_take_the_shortcut_to_the_same_nearest_point() {
        use rand::{RngExt, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(7);
        let mut shortcuts = 0;
        for case in 0..2000 {
            // Collinear Bézier points in order along a random line, unevenly spaced (doubled
            // ends, as at a rounded polygon's corners, in some cases).
            let origin = DVec2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
            let direction = DVec2::from_angle(rng.random_range(0.0..std::f64::consts::TAU));
            let length = rng.random_range(0.01..3.0);
            let mut c = [0.0, rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), 1.0];
            c[1..3].sort_by(f64::total_cmp);
            if case % 5 == 0 {
                c[1] = 0.0;
            }
            let piece = CubicSegment { bezier: c.map(|ci| origin + direction * (length * ci)) };
            let point = origin
                + direction * (length * rng.random_range(-0.5..1.5))
                + direction.perp() * (length * rng.random_range(-1.0..1.0));
            shortcuts += usize::from(piece.straight().is_some());
            let (t, distance) = piece.nearest_parameter(point);
            let (t_ref, distance_ref) = piece.nearest_by_isolation(point);
            assert!(
                (distance - distance_ref).abs() <= 1e-13 * length,
                "case {case}: {distance} against {distance_ref}"
            );
            // The distance pins the parameter only where the piece moves along it.
            let moved = piece.position(t).distance(piece.position(t_ref));
            assert!(moved <= 1e-7 * length, "case {case}: t {t} against {t_ref}");
        }
        assert_eq!(shortcuts, 2000, "every straight piece takes the shortcut");
        // A bent piece does not.
        let bent =
            CubicSegment { bezier: [DVec2::ZERO, DVec2::new(1.0, 1e-9), DVec2::new(2.0, 0.0), DVec2::new(3.0, 0.0)] };
        assert!(bent.straight().is_none());
        // Nor a straight one that folds back along its chord.
        let folded =
            CubicSegment { bezier: [DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(3.0, 0.0)] };
        assert!(folded.straight().is_none());
    }

    fn sample() -> CubicSegment {
        CubicSegment {
            bezier: [DVec2::new(0.0, 0.0), DVec2::new(1.0, 2.0), DVec2::new(3.0, -1.0), DVec2::new(4.0, 1.0)],
        }
    }

    #[test]
    fn split_halves_agree_with_the_whole() {
        let s = sample();
        let (l, r) = s.split(0.3);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            assert!((l.position(t) - s.position(0.3 * t)).length() < 1e-14);
            assert!((r.position(t) - s.position(0.3 + 0.7 * t)).length() < 1e-14);
        }
    }

    #[test]
    fn bounds_contain_dense_samples_and_are_tight() {
        let s = sample();
        let (low, high) = s.bounds();
        let mut seen_low = DVec2::splat(f64::INFINITY);
        let mut seen_high = DVec2::splat(f64::NEG_INFINITY);
        for k in 0..=100_000 {
            let p = s.position(k as f64 / 100_000.0);
            seen_low = seen_low.min(p);
            seen_high = seen_high.max(p);
        }
        assert!(low.cmple(seen_low + 1e-15).all() && high.cmpge(seen_high - 1e-15).all());
        assert!((low - seen_low).abs().max_element() < 1e-9);
        assert!((high - seen_high).abs().max_element() < 1e-9);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let s = sample();
        let h = 1e-6;
        for k in 1..10 {
            let t = k as f64 / 10.0;
            let fd = (s.position(t + h) - s.position(t - h)) / (2.0 * h);
            assert!((fd - s.derivative(t)).length() < 1e-7);
            let fd2 = (s.derivative(t + h) - s.derivative(t - h)) / (2.0 * h);
            assert!((fd2 - s.second_derivative(t)).length() < 1e-6);
        }
    }

    #[test]
    fn straight_segment_arc_length_is_exact() {
        let s =
            CubicSegment { bezier: [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, 2.0), DVec2::new(3.0, 3.0)] };
        assert!((s.arc_length() - 18f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn slope_coefficients_are_the_bernstein_form_of_the_slope() {
        let s = sample();
        let point = DVec2::new(0.7, -0.4);
        let c = s.slope_coefficients(point);
        const QUINTIC: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let bernstein: f64 =
                (0..6).map(|i| QUINTIC[i] * c[i] * t.powi(i as i32) * (1.0 - t).powi(5 - i as i32)).sum();
            let [p, d, _] = s.jet(t);
            assert!((bernstein - (p - point).dot(d)).abs() < 1e-12 * (1.0 + bernstein.abs()), "t = {t}");
        }
    }

    #[test]
    fn nearest_parameter_is_global_on_random_pieces() {
        use rand::{RngExt, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(7);
        let mut random_point = |r: f64| DVec2::new(rng.random_range(-r..r), rng.random_range(-r..r));
        for case in 0..500 {
            let piece = CubicSegment { bezier: [0, 1, 2, 3].map(|_| random_point(1.0)) };
            let point = random_point(1.5);
            let (t, distance) = piece.nearest_parameter(point);
            assert!((piece.position(t).distance(point) - distance).abs() < 1e-15);
            let sampled =
                (0..=20_000).map(|k| piece.position(k as f64 / 2e4).distance(point)).fold(f64::INFINITY, f64::min);
            // Sampling at spacing h misses the minimum by at most ½ max|p'| h² / d-ish; 1e-6
            // is far above that for these unit pieces and far below any wrong local minimum.
            assert!(distance <= sampled + 1e-12, "case {case}: {distance} > sampled {sampled}");
            assert!(sampled - distance < 1e-6, "case {case}");
        }
    }

    #[test]
    fn nearest_parameter_beats_dense_sampling() {
        let s = sample();
        let point = DVec2::new(2.0, 3.0);
        let (_, distance) = s.nearest_parameter(point);
        let sampled = (0..=100_000).map(|k| s.position(k as f64 / 1e5).distance(point)).fold(f64::INFINITY, f64::min);
        assert!(distance <= sampled + 1e-12);
        assert!(sampled - distance < 1e-8);
    }
}
