//! Rays against the exact curves. Along a cubic piece `c(s)` the signed distance to the ray's
//! line, `(c(s) − o) × d`, is itself a cubic whose Bernstein coefficients are those of the
//! control points, `(P_k − o) × d`; its roots in `[0, 1]` are isolated by Descartes' rule of
//! signs on the Bernstein coefficients (subdividing where there are several sign changes) and
//! refined by bisection to the last bit. Where the ray crosses a root, `τ = (c(s) − o) · d`.

use arrayvec::ArrayVec;
use glam::DVec2;

use crate::geometry::segment::CubicSegment;

/// A ray `origin + τ direction` for `0 ≤ τ ≤ max_distance`, `direction` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where it starts.
    pub origin: DVec2,
    /// Unit direction.
    pub direction: DVec2,
    /// Farthest `τ` (m).
    pub max_distance: f64,
}

impl Ray {
    /// A ray from `origin` along `direction` (normalised; `None` for a zero or non-finite one, or
    /// a negative or NaN `max_distance`).
    #[must_use]
    pub fn new(origin: DVec2, direction: DVec2, max_distance: f64) -> Option<Self> {
        let direction = direction.try_normalize()?;
        (origin.is_finite() && max_distance >= 0.0).then_some(Self { origin, direction, max_distance })
    }

    /// The point at `τ`.
    #[must_use]
    pub fn at(&self, distance: f64) -> DVec2 {
        self.origin + distance * self.direction
    }

    /// The part of `[0, max_distance]` inside the box `{centre + a·axis + b·axis⊥ : |a| ≤ h.x,
    /// |b| ≤ h.y}` (slab test in the box's frame), `None` if the ray misses it.
    #[must_use]
    pub fn box_interval(&self, centre: DVec2, axis: DVec2, half_extents: DVec2) -> Option<(f64, f64)> {
        let offset = self.origin - centre;
        let local_origin = DVec2::new(offset.dot(axis), offset.dot(axis.perp()));
        let local_direction = DVec2::new(self.direction.dot(axis), self.direction.dot(axis.perp()));
        let (mut low, mut high) = (0.0f64, self.max_distance);
        for k in 0..2 {
            let (o, d, h) = (local_origin[k], local_direction[k], half_extents[k]);
            if d == 0.0 {
                if o.abs() > h {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((-h - o) / d, (h - o) / d);
            low = low.max(t0.min(t1));
            high = high.min(t0.max(t1));
        }
        (low <= high).then_some((low, high))
    }
}

/// Where a ray crosses a piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayCrossing {
    /// Distance along the ray.
    pub distance: f64,
    /// Parameter on the piece.
    pub s: f64,
    /// Sign of `d × c'(s)`, i.e. of `d · n` for the outward normal `n` of a counter-clockwise
    /// boundary: −1 where the ray enters the body, +1 where it leaves, 0 at a tangency. Summed
    /// over every crossing of a ray from a point, it is the winding number around the point.
    pub side: f64,
}

/// Subdivision depth at which an interval still holding several sign changes is taken as one
/// (multiple or clustered) root: 2⁻⁴⁰ of the parameter range.
const MAX_DEPTH: u32 = 40;

/// Every crossing of `ray` with `piece` within `[0, max_distance]`, in order of `s`. A root at
/// the piece's end `s = 1` is reported, one at its start `s = 0` is not: along a closed curve
/// every joint is the end of one piece, so it is reported once.
#[must_use]
pub fn ray_crossings(ray: &Ray, piece: &CubicSegment) -> ArrayVec<RayCrossing, 3> {
    let weights = piece.bezier.map(|p| (p - ray.origin).perp_dot(ray.direction));
    let mut roots = ArrayVec::<f64, 3>::new();
    isolate(weights, 0.0, 1.0, 0, &mut roots);
    let mut out = ArrayVec::new();
    for s in roots {
        let distance = (piece.position(s) - ray.origin).dot(ray.direction);
        if (0.0..=ray.max_distance).contains(&distance) {
            let side = ray.direction.perp_dot(piece.derivative(s));
            out.push(RayCrossing { distance, s, side: if side == 0.0 { 0.0 } else { side.signum() } });
        }
    }
    out
}

/// Roots in `(low, high]` of the cubic with Bernstein coefficients `w` over `[low, high]`,
/// appended in order (a zero at `low` belongs to the interval before).
fn isolate(w: [f64; 4], low: f64, high: f64, depth: u32, roots: &mut ArrayVec<f64, 3>) {
    if w == [0.0; 4] {
        return; // the piece lies on the ray's line: no crossing to report
    }
    // Zeros at the ends take the sign the polynomial has just inside, for counting.
    let inner = |values: &[f64]| values.iter().copied().find(|v| *v != 0.0).unwrap_or(0.0);
    let start = if w[0] == 0.0 { f64::MIN_POSITIVE.copysign(inner(&w[1..])) } else { w[0] };
    let end = if w[3] == 0.0 { f64::MIN_POSITIVE.copysign(inner(&[w[2], w[1], w[0]])) } else { w[3] };
    let signs = [start, w[1], w[2], end];
    let nonzero: ArrayVec<bool, 4> = signs.iter().filter(|v| **v != 0.0).map(|v| *v < 0.0).collect();
    let changes = nonzero.windows(2).filter(|p| p[0] != p[1]).count();
    if changes == 1 {
        push(roots, bisect(w, start < 0.0, low, high));
    } else if changes > 1 {
        if depth >= MAX_DEPTH {
            push(roots, 0.5 * (low + high)); // a multiple root, or roots closer than 2⁻⁴⁰
        } else {
            let (left, right) = split(w);
            let middle = 0.5 * (low + high);
            isolate(left, low, middle, depth + 1, roots);
            isolate(right, middle, high, depth + 1, roots);
        }
    }
    if w[3] == 0.0 && roots.last() != Some(&high) {
        push(roots, high);
    }
}

fn push(roots: &mut ArrayVec<f64, 3>, root: f64) {
    if !roots.is_full() {
        roots.push(root);
    }
}

/// The single root in `(low, high)` of the Bernstein cubic `w` (one sign change), by bisection
/// to the last bit of the parameter.
fn bisect(w: [f64; 4], negative_at_start: bool, low: f64, high: f64) -> f64 {
    let (mut a, mut b) = (0.0f64, 1.0f64);
    for _ in 0..80 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let value = evaluate(w, m);
        if value == 0.0 {
            return low + (high - low) * m;
        }
        if (value < 0.0) == negative_at_start {
            a = m;
        } else {
            b = m;
        }
    }
    low + (high - low) * 0.5 * (a + b)
}

/// De Casteljau evaluation of the Bernstein cubic `w` at `x`.
fn evaluate(w: [f64; 4], x: f64) -> f64 {
    let lerp = |p: f64, q: f64| p + (q - p) * x;
    let (a, b, c) = (lerp(w[0], w[1]), lerp(w[1], w[2]), lerp(w[2], w[3]));
    let (d, e) = (lerp(a, b), lerp(b, c));
    lerp(d, e)
}

/// The Bernstein coefficients of the two halves of `w`.
fn split(w: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    let mid = |p: f64, q: f64| 0.5 * (p + q);
    let (a, b, c) = (mid(w[0], w[1]), mid(w[1], w[2]), mid(w[2], w[3]));
    let (d, e) = (mid(a, b), mid(b, c));
    let f = mid(d, e);
    ([w[0], a, d, f], [f, e, c, w[3]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_across_a_straight_piece_meets_it_once_where_it_should() {
        let from = DVec2::new(0.0, -1.0);
        let to = DVec2::new(0.0, 1.0);
        let piece = CubicSegment { bezier: [from, from.lerp(to, 1.0 / 3.0), from.lerp(to, 2.0 / 3.0), to] };
        let ray = Ray::new(DVec2::new(-2.0, 0.5), DVec2::X, 10.0).unwrap();
        let hits = ray_crossings(&ray, &piece);
        assert_eq!(hits.len(), 1);
        assert!((hits[0].distance - 2.0).abs() < 1e-15 && (hits[0].s - 0.75).abs() < 1e-15, "{hits:?}");
        assert!(Ray::new(DVec2::ZERO, DVec2::ZERO, 1.0).is_none());
    }

    #[test]
    fn a_ray_through_an_s_curve_meets_it_three_times() {
        // c(s) = (s, (2s − 1)³ − 0.25 (2s − 1)): crosses y = 0 at 2s − 1 ∈ {−½, 0, ½}.
        let [y0, y1, y2, y3] = [-0.75, 13.0 / 12.0, -13.0 / 12.0, 0.75]; // its Bernstein form
        let x = |k: f64| k / 3.0;
        let piece = CubicSegment {
            bezier: [DVec2::new(x(0.0), y0), DVec2::new(x(1.0), y1), DVec2::new(x(2.0), y2), DVec2::new(x(3.0), y3)],
        };
        let ray = Ray::new(DVec2::new(-1.0, 0.0), DVec2::X, 10.0).unwrap();
        let hits = ray_crossings(&ray, &piece);
        let s: Vec<f64> = hits.iter().map(|h| h.s).collect();
        assert_eq!(s.len(), 3, "{hits:?}");
        for (got, want) in s.iter().zip([0.25, 0.5, 0.75]) {
            assert!((got - want).abs() < 1e-14, "{s:?}");
        }
    }
}
