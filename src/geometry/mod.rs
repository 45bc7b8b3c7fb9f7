//! Curves, tolerances, bounding boxes and the curve-pair solver.

pub mod aobb_tree;
pub mod construct;
pub mod curve_pair;
pub mod multiresolution;
pub mod obb;
pub mod octagon;
pub mod overlap;
pub mod patterns;
pub mod pose;
pub mod quadrature;
pub mod query;
pub mod ray;
pub mod rounded_polygon;
pub mod rugosity;
pub mod segment;
pub mod self_intersection;
pub mod spline;

/// The lesser of two distances, NaN if either is (a NaN refuses what it would prove).
pub(crate) fn least(x: f64, y: f64) -> f64 {
    if x.is_nan() || x <= y { x } else { y }
}
