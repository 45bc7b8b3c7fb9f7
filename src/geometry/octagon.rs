//! A body's bounding octagon: the cheap, tight bound of its whole boundary and band that the
//! broad phase sweeps (docs/model.md §3).
//!
//! The tree's root box (MODEL §3) encloses its children's boxes, whose axes differ from level
//! to level, so it grows with every level: about 2.7 times the area of the boundary's own box
//! for a blob of the landing pile and 3.5 times for a rounded box of the pyramid, whose world
//! box at a turn of 15° is then 2.75 m wide for a 1 m box. Swept as the body's world box, it made
//! four times the candidate pairs a 1 m box's neighbours give. The octagon is fitted to the curve
//! itself instead: the eight lines that support the boundary in directions 45° apart, in the body
//! frame, with the band added around it at the pose.

use glam::DVec2;

use crate::geometry::obb::FIT_RELATIVE_PAD;
use crate::geometry::pose::Pose;
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;

/// The supporting lines' directions: `(cos kπ/4, sin kπ/4)`, `k = 0..8`.
const DIRECTIONS: usize = 8;

/// The octagon of the lines supporting a boundary in eight directions 45° apart (body frame),
/// and the band around it. It holds the boundary and every point within `band` of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Octagon {
    /// Vertex `k` is where the supporting lines of directions `k` and `k + 1` meet.
    vertices: [DVec2; DIRECTIONS],
    /// Added on every side at the pose (the body's largest tolerance, floored).
    band: f64,
}

impl Octagon {
    /// The octagon around `spline`'s boundary (each support the largest projection of its
    /// pieces on that direction), with `band` around it.
    #[must_use]
    pub fn around(spline: &Spline, band: f64) -> Self {
        let directions: [DVec2; DIRECTIONS] = std::array::from_fn(direction);
        let mut supports = [f64::NEG_INFINITY; DIRECTIONS];
        let mut reach = 0.0f64;
        for segment in spline.segments() {
            for (support, axis) in supports.iter_mut().zip(&directions) {
                *support = support.max(segment.projection_range(*axis).1);
            }
            reach = segment.bezier.iter().fold(reach, |reach, p| reach.max(p.abs().max_element()));
        }
        // Padded so that the vertices' rounding cannot leave a point of the boundary outside.
        let pad = 4.0 * FIT_RELATIVE_PAD * reach;
        let vertices = std::array::from_fn(|k| {
            let next = (k + 1) % DIRECTIONS;
            meet((directions[k], supports[k] + pad), (directions[next], supports[next] + pad))
        });
        Self { vertices, band }
    }

    /// A body's octagon: around its boundary, with its largest tolerance (floored at
    /// `min_band`, as its tree's) around that. Kept with the body as a component, worked out
    /// once when it is added.
    #[must_use]
    pub fn of_body(spline: &Spline, rugosity: &Rugosity, min_band: f64) -> Self {
        Self::around(spline, rugosity.body_band(min_band))
    }

    /// The world's axis-aligned bounds `(min, max)` of the octagon and its band at `pose`.
    #[must_use]
    pub fn world_bounds(&self, pose: &Pose) -> (DVec2, DVec2) {
        // The vertices turned about the origin, their extents by plain comparisons (no NaN
        // handling: a pose that is not finite gives bounds that are not, which the broad phase
        // sweeps as they are), then moved.
        let first = pose.rotate(self.vertices[0]);
        let (mut low, mut high) = (first, first);
        for vertex in &self.vertices[1..] {
            let point = pose.rotate(*vertex);
            low.x = if point.x < low.x { point.x } else { low.x };
            low.y = if point.y < low.y { point.y } else { low.y };
            high.x = if point.x > high.x { point.x } else { high.x };
            high.y = if point.y > high.y { point.y } else { high.y };
        }
        let grow = DVec2::splat(self.band);
        (pose.position + low - grow, pose.position + high + grow)
    }
}

/// Direction `k` of the supporting lines.
fn direction(k: usize) -> DVec2 {
    let angle = std::f64::consts::FRAC_PI_4 * k as f64;
    DVec2::new(angle.cos(), angle.sin())
}

/// Where the lines `a·x = h_a` and `b·x = h_b` meet (`a`, `b` 45° apart).
fn meet((a, h_a): (DVec2, f64), (b, h_b): (DVec2, f64)) -> DVec2 {
    let det = a.perp_dot(b);
    DVec2::new(h_a * b.y - a.y * h_b, a.x * h_b - h_a * b.x) / det
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::Octagon;
    use crate::geometry::aobb_tree::AobbTree;
    use crate::geometry::construct::Generator;
    use crate::geometry::pose::Pose;
    use crate::geometry::rugosity::Rugosity;

    /// Every point of the boundary (4,000 of them), grown by the band in any direction, lies
    /// within the world bounds at 40 turns of three shapes. Each support is at most the boundary's radius `R` about the body's
    /// origin, so the octagon lies in the regular one of supports `R`, within `R / cos 22.5°` of
    /// the origin; and on these shapes the bounds are smaller than the tree's root box's.
    #[test]
    fn the_world_bounds_hold_the_band_and_are_tight() {
        let shapes = [
            Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.1 }.build(24).unwrap(),
            Generator::Blob { radius: 0.1, roughness: 0.5, seed: 3 }.build(16).unwrap(),
            Generator::Blob { radius: 2.0, roughness: 0.9, seed: 8 }.build(32).unwrap(),
        ];
        for spline in &shapes {
            let band = 0.003;
            let octagon = Octagon::around(spline, band);
            let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
            let tree = AobbTree::build(spline, &rugosity, 0.0);
            let radius = spline.radius_about(DVec2::ZERO) + band;
            for turn in 0..40 {
                let pose = Pose::new(DVec2::new(3.0, -7.0), 0.157 * f64::from(turn));
                let (low, high) = octagon.world_bounds(&pose);
                let (mut min, mut max) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
                for k in 0..4000 {
                    let u = spline.segment_count() as f64 * f64::from(k) / 4000.0;
                    let point = pose.transform_point(spline.position(u));
                    (min, max) = (min.min(point), max.max(point));
                }
                let (min, max) = (min - DVec2::splat(band), max + DVec2::splat(band));
                assert!(low.cmple(min).all() && high.cmpge(max).all(), "{low} {high} against {min} {max}");
                let reach = (pose.position - low).max_element().max((high - pose.position).max_element());
                let limit = (radius - band) / std::f64::consts::FRAC_PI_8.cos() + band;
                assert!(reach <= limit * (1.0 + 1e-12), "bounds reach {reach}, beyond {limit}");
                let (root_low, root_high) = tree.root().obb.transformed(&pose).world_aabb();
                let area = |(low, high): (DVec2, DVec2)| (high - low).element_product();
                assert!(area((low, high)) < area((root_low, root_high)), "looser than the root box");
            }
        }
    }
}
