//! Building boundary curves: interpolation through points and the shape generators.

use std::f64::consts::TAU;

use glam::DVec2;
use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::error::ShapeError;
use crate::geometry::rounded_polygon::{ControlPointBudget, DEVIATION_SAMPLES, ShapeFit, rounded_polygon};
use crate::geometry::spline::Spline;

/// Control points whose periodic cubic B-spline passes through `points[i]` at `u = i`.
///
/// Solves the cyclic tridiagonal system `(c_{i-1} + 4c_i + c_{i+1})/6 = p_i`, which is
/// strictly diagonally dominant, by the Sherman–Morrison form of the Thomas algorithm.
///
/// # Errors
/// [`ShapeError::TooFewControlPoints`] for fewer than 4 points, [`ShapeError::NonFiniteControlPoint`]
/// for a non-finite point.
pub fn interpolating_control_points(points: &[DVec2]) -> Result<Vec<DVec2>, ShapeError> {
    let n = points.len();
    if n < 4 {
        return Err(ShapeError::TooFewControlPoints { count: n });
    }
    if let Some((index, p)) = points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(ShapeError::NonFiniteControlPoint { index, x: p.x, y: p.y });
    }
    // Matrix (times 6): 4 on the diagonal, 1 off it and in the corners.
    // Sherman–Morrison: A = T + u vᵀ with u = (γ, 0, …, 0, 1), v = (1, 0, …, 0, 1/γ).
    let gamma = -4.0;
    let mut diagonal = vec![4.0; n];
    diagonal[0] -= gamma;
    diagonal[n - 1] -= 1.0 / gamma;
    let rhs: Vec<DVec2> = points.iter().map(|&p| 6.0 * p).collect();
    let y = solve_tridiagonal(&diagonal, &rhs);
    let mut u = vec![DVec2::ZERO; n];
    u[0] = DVec2::splat(gamma);
    u[n - 1] = DVec2::ONE;
    let z = solve_tridiagonal(&diagonal, &u);
    let factor = (y[0] + y[n - 1] / gamma) / (DVec2::ONE + z[0] + z[n - 1] / gamma);
    Ok(y.iter().zip(&z).map(|(&yi, &zi)| yi - factor * zi).collect())
}

/// Thomas algorithm for a symmetric tridiagonal matrix with unit off-diagonals.
fn solve_tridiagonal(diagonal: &[f64], rhs: &[DVec2]) -> Vec<DVec2> {
    let n = diagonal.len();
    let mut c_prime = vec![0.0; n];
    let mut d_prime = vec![DVec2::ZERO; n];
    c_prime[0] = 1.0 / diagonal[0];
    d_prime[0] = rhs[0] / diagonal[0];
    for i in 1..n {
        let m = diagonal[i] - c_prime[i - 1];
        c_prime[i] = 1.0 / m;
        d_prime[i] = (rhs[i] - d_prime[i - 1]) / m;
    }
    let mut x = vec![DVec2::ZERO; n];
    x[n - 1] = d_prime[n - 1];
    for i in (0..n - 1).rev() {
        x[i] = d_prime[i] - c_prime[i] * x[i + 1];
    }
    x
}

impl Spline {
    /// The curve that passes through `points[i]` at `u = i` (a closed interpolating spline).
    ///
    /// # Errors
    /// As [`interpolating_control_points`] and [`Spline::from_control_points`].
    pub fn interpolating(points: &[DVec2]) -> Result<Self, ShapeError> {
        Self::from_control_points(interpolating_control_points(points)?)
    }
}

/// A parametric shape generator; every generator produces a CCW curve centred near the origin.
///
/// `Circle`, `Ellipse`, `Superellipse`, `Gear` and `Blob` interpolate points sampled on the exact
/// shape. `RoundedRectangle` and `RoundedPolygon` place their control points on the sides
/// ([`rounded_polygon`]), so their straight sides are exactly straight and a rectangle has
/// exactly its nominal width and height; only the corners deviate from the nominal arcs, at a
/// right angle by at most 0.22 % of the corner radius (1.26 % when the radius takes a whole
/// side), see [`rounded_polygon`] and [`Generator::max_deviation`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Generator {
    /// Circle of `radius`.
    Circle {
        /// Radius (m).
        radius: f64,
    },
    /// Ellipse with semi-axes `a` (along x) and `b` (along y).
    Ellipse {
        /// Semi-axis along x (m).
        a: f64,
        /// Semi-axis along y (m).
        b: f64,
    },
    /// Rectangle `width × height` with corners rounded at `corner_radius`; the sides are exactly
    /// straight (a [`Generator::RoundedPolygon`] of the four corners).
    RoundedRectangle {
        /// Full width (m).
        width: f64,
        /// Full height (m).
        height: f64,
        /// Corner radius (m), at most half the smaller side; 0 rounds the corners minimally
        /// (see [`rounded_polygon`]).
        corner_radius: f64,
    },
    /// Closed polygon with every corner rounded at `corner_radius`; the sides are exactly straight.
    RoundedPolygon {
        /// Corners in order, clockwise or counter-clockwise (m); at least 3, no crossing sides.
        corners: Vec<DVec2>,
        /// Corner radius (m), ≥ 0 and small enough that the two roundings of every side fit on
        /// it; 0 rounds the corners minimally (see [`rounded_polygon`]).
        corner_radius: f64,
    },
    /// Superellipse `|x/a|^p + |y/b|^p = 1`.
    Superellipse {
        /// Semi-axis along x (m).
        a: f64,
        /// Semi-axis along y (m).
        b: f64,
        /// Exponent `p > 0` (2 is an ellipse, large values approach a rectangle).
        exponent: f64,
    },
    /// Gear or star: radius `r(θ) = radius (1 + depth·cos(teeth θ))`.
    Gear {
        /// Mean radius (m).
        radius: f64,
        /// Number of teeth (≥ 1).
        teeth: u32,
        /// Relative tooth depth in `[0, 1)`.
        depth: f64,
    },
    /// Seeded random smooth blob: `r(θ) = radius (1 + Σ_k a_k cos(kθ + φ_k))`, harmonics 2..=6
    /// with amplitudes drawn uniformly in `[0, roughness / k]` and scaled so `r > radius/3`.
    Blob {
        /// Mean radius (m).
        radius: f64,
        /// Overall relative amplitude of the harmonics, in `[0, 1)`.
        roughness: f64,
        /// Seed of the random harmonics.
        seed: u64,
    },
}

impl Generator {
    /// The curve with `segments` segments.
    ///
    /// For `RoundedRectangle` and `RoundedPolygon`, `segments` is the exact segment count: six
    /// control points per corner, the rest spread over the straight parts in proportion to their
    /// lengths.
    ///
    /// # Errors
    /// [`ShapeError::InvalidParameter`] naming the generator field for a parameter out of its
    /// domain, or `segments` when a rounded polygon needs more (the message names the minimum,
    /// 6 per corner) or its sides have no room for more; [`ShapeError::TooFewControlPoints`] for
    /// fewer than 4 segments.
    pub fn build(&self, segments: usize) -> Result<Spline, ShapeError> {
        if segments < 4 {
            return Err(ShapeError::TooFewControlPoints { count: segments });
        }
        self.check()?;
        match self.rounded_polygon() {
            Some((corners, radius)) => Ok(rounded_polygon(&corners, radius, ControlPointBudget::Segments(segments))?.0),
            None => Spline::interpolating(&self.sample(segments)),
        }
    }

    /// The curve with `segments` segments and how closely it follows the exact shape.
    ///
    /// [`ShapeFit::max_deviation`] is the largest distance from the curve (64 samples per
    /// segment) to the exact shape: for rounded rectangles and polygons the distance to the
    /// nearest side or arc; for a circle the exact distance `| |p| − r |`; for the ellipse,
    /// superellipse, gear and blob the *radial* distance `| |p| − R(φ) |` to the shape's point at
    /// the same polar angle `φ` about the origin, an upper bound of the distance to the nearest point.
    ///
    /// # Errors
    /// As [`Generator::build`].
    pub fn build_with_fit(&self, segments: usize) -> Result<(Spline, ShapeFit), ShapeError> {
        if let Some((corners, radius)) = self.rounded_polygon() {
            if segments < 4 {
                return Err(ShapeError::TooFewControlPoints { count: segments });
            }
            self.check()?;
            return rounded_polygon(&corners, radius, ControlPointBudget::Segments(segments));
        }
        let spline = self.build(segments)?;
        let fit = ShapeFit { max_deviation: self.radial_deviation(&spline), segments };
        Ok((spline, fit))
    }

    /// Largest deviation (m) of the `segments`-segment curve from the exact shape (see
    /// [`Generator::build_with_fit`] for the measure of each generator).
    ///
    /// # Errors
    /// As [`Generator::build`].
    pub fn max_deviation(&self, segments: usize) -> Result<f64, ShapeError> {
        Ok(self.build_with_fit(segments)?.1.max_deviation)
    }

    /// The corners (CCW for the rectangle) and corner radius of a rounded rectangle or polygon.
    fn rounded_polygon(&self) -> Option<(Vec<DVec2>, f64)> {
        match self {
            Self::RoundedRectangle { width, height, corner_radius } => {
                let half = 0.5 * DVec2::new(*width, *height);
                let corners = [DVec2::new(-1.0, -1.0), DVec2::new(1.0, -1.0), DVec2::ONE, DVec2::new(-1.0, 1.0)];
                Some((corners.iter().map(|&c| c * half).collect(), *corner_radius))
            }
            Self::RoundedPolygon { corners, corner_radius } => Some((corners.clone(), *corner_radius)),
            _ => None,
        }
    }

    /// Largest radial distance `| |p| − R(φ) |` of the curve from the exact shape.
    fn radial_deviation(&self, spline: &Spline) -> f64 {
        let harmonics = match *self {
            Self::Blob { roughness, seed, .. } => blob_harmonics(roughness, seed),
            _ => Vec::new(),
        };
        spline
            .segments()
            .flat_map(|segment| {
                (0..DEVIATION_SAMPLES).map(move |k| segment.position(k as f64 / DEVIATION_SAMPLES as f64))
            })
            .map(|p| (p.length() - self.polar_radius(p.y.atan2(p.x), &harmonics)).abs())
            .fold(0.0, f64::max)
    }

    /// Distance from the origin to the exact shape at polar angle `angle` (star-shaped generators).
    fn polar_radius(&self, angle: f64, harmonics: &[(f64, f64, f64)]) -> f64 {
        let (s, c) = angle.sin_cos();
        match *self {
            Self::Circle { radius } => radius,
            Self::Ellipse { a, b } => a * b / (b * c).hypot(a * s),
            Self::Superellipse { a, b, exponent } => {
                ((c / a).abs().powf(exponent) + (s / b).abs().powf(exponent)).powf(-1.0 / exponent)
            }
            Self::Gear { radius, teeth, depth } => radius * (1.0 + depth * (teeth as f64 * angle).cos()),
            Self::Blob { radius, .. } => radius * blob_radius(harmonics, angle),
            Self::RoundedRectangle { .. } | Self::RoundedPolygon { .. } => {
                unreachable!("rounded polygons measure their deviation against their sides and arcs")
            }
        }
    }

    fn check(&self) -> Result<(), ShapeError> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ShapeError::parameter(what, format!("must be finite and > 0, got {v}")))
            }
        };
        let in_unit = |what: &str, v: f64| {
            if (0.0..1.0).contains(&v) {
                Ok(())
            } else {
                Err(ShapeError::parameter(what, format!("must lie in [0, 1), got {v}")))
            }
        };
        match *self {
            // The polygon path checks its own corners, radius and budget.
            Self::RoundedPolygon { .. } => Ok(()),
            Self::Circle { radius } => positive("circle.radius", radius),
            Self::Ellipse { a, b } => positive("ellipse.a", a).and(positive("ellipse.b", b)),
            Self::RoundedRectangle { width, height, corner_radius } => {
                positive("rounded_rectangle.width", width)?;
                positive("rounded_rectangle.height", height)?;
                if !(corner_radius.is_finite() && corner_radius >= 0.0 && corner_radius <= 0.5 * width.min(height)) {
                    return Err(ShapeError::parameter(
                        "rounded_rectangle.corner_radius",
                        format!(
                            "must lie in [0, half the smaller side = {}], got {corner_radius}",
                            0.5 * width.min(height)
                        ),
                    ));
                }
                Ok(())
            }
            Self::Superellipse { a, b, exponent } => {
                positive("superellipse.a", a)?;
                positive("superellipse.b", b)?;
                positive("superellipse.exponent", exponent)
            }
            Self::Gear { radius, teeth, depth } => {
                positive("gear.radius", radius)?;
                if teeth == 0 {
                    return Err(ShapeError::parameter("gear.teeth", "must be at least 1"));
                }
                in_unit("gear.depth", depth)
            }
            Self::Blob { radius, roughness, .. } => {
                positive("blob.radius", radius).and(in_unit("blob.roughness", roughness))
            }
        }
    }

    /// `count` points on the exact shape, in CCW order, to be interpolated (not for rounded polygons).
    fn sample(&self, count: usize) -> Vec<DVec2> {
        let angle = |k: usize| TAU * k as f64 / count as f64;
        match *self {
            Self::Circle { radius } => (0..count).map(|k| radius * DVec2::from_angle(angle(k))).collect(),
            Self::Ellipse { a, b } => (0..count).map(|k| DVec2::new(a, b) * DVec2::from_angle(angle(k))).collect(),
            Self::RoundedRectangle { .. } | Self::RoundedPolygon { .. } => {
                unreachable!("rounded polygons place their control points on their sides")
            }
            Self::Superellipse { a, b, exponent } => (0..count)
                .map(|k| {
                    let (s, c) = angle(k).sin_cos();
                    let power = |v: f64| v.signum() * v.abs().powf(2.0 / exponent);
                    DVec2::new(a * power(c), b * power(s))
                })
                .collect(),
            Self::Gear { radius, teeth, depth } => (0..count)
                .map(|k| radius * (1.0 + depth * (teeth as f64 * angle(k)).cos()) * DVec2::from_angle(angle(k)))
                .collect(),
            Self::Blob { radius, roughness, seed } => {
                let harmonics = blob_harmonics(roughness, seed);
                (0..count).map(|k| radius * blob_radius(&harmonics, angle(k)) * DVec2::from_angle(angle(k))).collect()
            }
        }
    }
}

/// `(order, amplitude, phase)` of the blob harmonics, amplitudes scaled so `Σ a_k ≤ 2/3`.
fn blob_harmonics(roughness: f64, seed: u64) -> Vec<(f64, f64, f64)> {
    let mut rng = crate::random::seeded(seed);
    let mut harmonics: Vec<(f64, f64, f64)> = (2..=6)
        .map(|k| {
            let order = k as f64;
            (order, rng.random_range(0.0..=1.0) * roughness / order, rng.random_range(0.0..TAU))
        })
        .collect();
    let total: f64 = harmonics.iter().map(|h| h.1).sum();
    if total > 2.0 / 3.0 {
        harmonics.iter_mut().for_each(|h| h.1 *= (2.0 / 3.0) / total);
    }
    harmonics
}

/// `r(θ)/radius = 1 + Σ_k a_k cos(kθ + φ_k)` of a blob.
fn blob_radius(harmonics: &[(f64, f64, f64)], theta: f64) -> f64 {
    1.0 + harmonics.iter().map(|&(order, amp, phase)| amp * (order * theta + phase).cos()).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolating_curve_passes_through_its_points() {
        let points: Vec<DVec2> =
            (0..9).map(|k| DVec2::from_angle(TAU * k as f64 / 9.0) * (1.0 + 0.3 * (k % 3) as f64)).collect();
        let spline = Spline::interpolating(&points).unwrap();
        for (i, p) in points.iter().enumerate() {
            assert!((spline.position(i as f64) - *p).length() < 1e-12);
        }
    }

    #[test]
    fn generators_build_valid_ccw_curves() {
        let gens = [
            Generator::Circle { radius: 1.0 },
            Generator::Ellipse { a: 2.0, b: 0.5 },
            Generator::RoundedRectangle { width: 2.0, height: 1.0, corner_radius: 0.2 },
            Generator::Superellipse { a: 1.0, b: 1.0, exponent: 4.0 },
            Generator::Gear { radius: 1.0, teeth: 8, depth: 0.15 },
            Generator::Blob { radius: 1.0, roughness: 0.5, seed: 7 },
            Generator::RoundedPolygon {
                corners: vec![
                    DVec2::ZERO,
                    DVec2::new(2.0, 0.0),
                    DVec2::new(2.0, 1.0),
                    DVec2::new(1.0, 0.4),
                    DVec2::new(0.0, 1.0),
                ],
                corner_radius: 0.1,
            },
        ];
        for g in &gens {
            let spline = g.build(64).unwrap();
            spline.validate().unwrap();
        }
    }

    #[test]
    fn rounded_rectangle_has_exactly_its_width_and_height() {
        let spline = Generator::RoundedRectangle { width: 2.0, height: 1.0, corner_radius: 0.2 }.build(40).unwrap();
        let (lo, hi) = spline.bounds();
        assert!((lo + DVec2::new(1.0, 0.5)).abs().max_element() < 1e-15, "{lo}");
        assert!((hi - DVec2::new(1.0, 0.5)).abs().max_element() < 1e-15, "{hi}");
    }

    #[test]
    fn circle_deviation_is_the_interpolation_error() {
        // Cubic interpolation of 64 points on the unit circle: about (2π/64)⁴/384 ≈ 2.4e-7.
        let deviation = Generator::Circle { radius: 1.0 }.max_deviation(64).unwrap();
        assert!(deviation > 1e-8 && deviation < 5e-7, "{deviation}");
    }
}
