//! One cubic piece of a boundary in Bézier form, with exact evaluation, bounds and splitting.

use glam::DVec2;

use crate::geometry::quadrature::{gauss_legendre_16, unit_roots_of_quadratic};

/// A cubic Bézier piece `p(t)`, `t ∈ [0, 1]`, given by its four Bézier points.
///
/// The piece lies in the convex hull of its Bézier points, a tighter bound than the
/// B-spline control points it was made from.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// The stationary points of `|p(t) − x|²` are bracketed on a 32-interval grid and refined by
    /// safeguarded Newton; end points are always candidates, so the global minimum is found.
    #[must_use]
    pub fn nearest_parameter(&self, point: DVec2) -> (f64, f64) {
        const GRID: usize = 32;
        let slope = |t: f64| {
            let [p, d, _] = self.jet(t);
            (p - point).dot(d)
        };
        let mut best = (0.0, self.position(0.0).distance(point));
        let end = self.position(1.0).distance(point);
        if end < best.1 {
            best = (1.0, end);
        }
        let mut t_prev = 0.0;
        let mut f_prev = slope(0.0);
        for k in 1..=GRID {
            let t = k as f64 / GRID as f64;
            let f = slope(t);
            if f_prev < 0.0 && f >= 0.0 {
                let root = refine_minimum(self, point, t_prev, t);
                let distance = self.position(root).distance(point);
                if distance < best.1 {
                    best = (root, distance);
                }
            }
            t_prev = t;
            f_prev = f;
        }
        best
    }
}

/// Finds the root of `(p(t) − x)·p'(t)` in a bracket `[lo, hi]` where it goes from − to +.
fn refine_minimum(segment: &CubicSegment, point: DVec2, mut lo: f64, mut hi: f64) -> f64 {
    let mut t = 0.5 * (lo + hi);
    for _ in 0..64 {
        let [p, d, dd] = segment.jet(t);
        let f = (p - point).dot(d);
        if f == 0.0 {
            return t;
        }
        if f < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let fp = d.length_squared() + (p - point).dot(dd);
        let newton = if fp > 0.0 { t - f / fp } else { f64::NAN };
        t = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        if hi - lo <= 4.0 * f64::EPSILON {
            break;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn nearest_parameter_beats_dense_sampling() {
        let s = sample();
        let point = DVec2::new(2.0, 3.0);
        let (_, distance) = s.nearest_parameter(point);
        let sampled = (0..=100_000).map(|k| s.position(k as f64 / 1e5).distance(point)).fold(f64::INFINITY, f64::min);
        assert!(distance <= sampled + 1e-12);
        assert!(sampled - distance < 1e-8);
    }
}
