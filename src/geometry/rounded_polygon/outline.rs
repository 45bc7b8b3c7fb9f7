//! The nominal outline a rounded polygon's curve is measured against: straight sides and
//! circular arcs ([`ShapeFit::max_deviation`](super::ShapeFit::max_deviation)).

use glam::DVec2;

use super::DEVIATION_SAMPLES;
use crate::geometry::spline::Spline;

/// One piece of a nominal outline.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Line {
        from: DVec2,
        to: DVec2,
    },
    /// The arc about `centre` from `from` to `to`, turning by `turn` (signed, |turn| < π).
    Arc {
        centre: DVec2,
        radius: f64,
        from: DVec2,
        to: DVec2,
        turn: f64,
    },
}

impl Piece {
    fn distance(&self, p: DVec2) -> f64 {
        match *self {
            Self::Line { from, to } => {
                let along = to - from;
                let s = ((p - from).dot(along) / along.length_squared()).clamp(0.0, 1.0);
                p.distance(from + s * along)
            }
            Self::Arc { centre, radius, from, to, turn } => {
                let (d, a, b) = (p - centre, from - centre, to - centre);
                let sign = turn.signum();
                if sign * a.perp_dot(d) >= 0.0 && sign * d.perp_dot(b) >= 0.0 {
                    (d.length() - radius).abs()
                } else {
                    p.distance(from).min(p.distance(to))
                }
            }
        }
    }
}

/// A nominal outline: straight sides and circular arcs.
#[derive(Clone, Debug)]
pub(super) struct Outline {
    pieces: Vec<Piece>,
}

impl Outline {
    /// The CCW polygon with corners rounded at `radius` (sharp for 0).
    pub(super) fn rounded_polygon(ccw: &[DVec2], radius: f64) -> Self {
        let n = ccw.len();
        if radius == 0.0 {
            return Self { pieces: (0..n).map(|k| Piece::Line { from: ccw[k], to: ccw[(k + 1) % n] }).collect() };
        }
        let arcs: Vec<Piece> = (0..n).map(|k| corner_arc(ccw, k, radius)).collect();
        let mut pieces = Vec::with_capacity(2 * n);
        for k in 0..n {
            let (Piece::Arc { to: from, .. }, Piece::Arc { from: to, .. }) = (arcs[k], arcs[(k + 1) % n]) else {
                unreachable!("corner_arc returns arcs")
            };
            pieces.extend([arcs[k], Piece::Line { from, to }]);
        }
        Self { pieces }
    }

    /// The canonical corner of [`corner_deviation`](super::corner_deviation): sides 3 tangent lengths long.
    pub(super) fn canonical_corner(turn: f64) -> Self {
        let corners = [DVec2::new(-3.0, 0.0), DVec2::ZERO, 3.0 * DVec2::from_angle(turn)];
        let radius = 1.0 / (0.5 * turn).tan();
        let arc = corner_arc(&corners, 1, radius);
        let Piece::Arc { from, to, .. } = arc else { unreachable!("corner_arc returns arcs") };
        Self { pieces: vec![Piece::Line { from: corners[0], to: from }, arc, Piece::Line { from: to, to: corners[2] }] }
    }

    /// The distance of `p` from the nearest piece.
    pub(super) fn distance(&self, p: DVec2) -> f64 {
        self.pieces.iter().map(|piece| piece.distance(p)).fold(f64::INFINITY, f64::min)
    }

    /// Largest distance of `spline` from the outline, [`DEVIATION_SAMPLES`] samples per segment.
    pub(super) fn max_deviation(&self, spline: &Spline) -> f64 {
        spline
            .segments()
            .flat_map(|segment| {
                (0..DEVIATION_SAMPLES).map(move |k| segment.position(k as f64 / DEVIATION_SAMPLES as f64))
            })
            .map(|p| self.distance(p))
            .fold(0.0, f64::max)
    }
}

/// The arc of `radius` tangent to both sides at corner `k` (centre inside a convex corner,
/// outside a concave one).
fn corner_arc(corners: &[DVec2], k: usize, radius: f64) -> Piece {
    let n = corners.len();
    let vertex = corners[k];
    let incoming = (vertex - corners[(k + n - 1) % n]).normalize();
    let outgoing = (corners[(k + 1) % n] - vertex).normalize();
    let turn = incoming.perp_dot(outgoing).atan2(incoming.dot(outgoing));
    let tangent = radius * (0.5 * turn.abs()).tan();
    let from = vertex - tangent * incoming;
    let centre = from + turn.signum() * radius * incoming.perp();
    Piece::Arc { centre, radius, from, to: vertex + tangent * outgoing, turn }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_distance_inside_and_outside_its_wedge() {
        let corners = [DVec2::new(-2.0, 0.0), DVec2::ZERO, DVec2::new(0.0, 2.0)];
        let arc = corner_arc(&corners, 1, 1.0);
        assert!((arc.distance(DVec2::new(-1.0, 1.0)) - 1.0).abs() < 1e-15); // the centre
        assert!((arc.distance(DVec2::new(1.0, -1.0)) - (2.0 * 2.0_f64.sqrt() - 1.0)).abs() < 1e-15);
        assert!((arc.distance(DVec2::new(-3.0, 0.0)) - 2.0).abs() < 1e-15); // beyond the start
    }
}
