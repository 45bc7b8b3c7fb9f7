//! Exact mass properties of a spline body by Green's theorem (MODEL §1).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::quadrature::gauss_legendre_6;
use crate::geometry::spline::Spline;

/// Geometric moments of the region a closed curve encloses.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AreaMoments {
    /// Enclosed area `A`.
    pub area: f64,
    /// Centroid `c`.
    pub centroid: DVec2,
    /// Polar second moment of area about the centroid, `J0 − A|c|²`.
    pub polar_moment: f64,
}

/// Mass properties of a body of uniform density.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MassProperties {
    /// Mass `m = ρA`.
    pub mass: f64,
    /// Moment of inertia about the centre of mass, `I_c = ρ(J0 − A|c|²)`.
    pub inertia: f64,
    /// Centre of mass in the frame of the curve it was computed from.
    pub centre_of_mass: DVec2,
}

impl MassProperties {
    /// Infinite mass and inertia: a static body.
    pub const STATIC: Self = Self { mass: f64::INFINITY, inertia: f64::INFINITY, centre_of_mass: DVec2::ZERO };

    /// `1/m`, zero for a static body.
    #[must_use]
    pub fn inverse_mass(&self) -> f64 {
        if self.mass.is_finite() { 1.0 / self.mass } else { 0.0 }
    }

    /// `1/I`, zero for a static body.
    #[must_use]
    pub fn inverse_inertia(&self) -> f64 {
        if self.inertia.is_finite() { 1.0 / self.inertia } else { 0.0 }
    }
}

/// Area, centroid and polar second moment of the region enclosed by `spline`.
///
/// Each integrand is a polynomial of degree ≤ 11 in the local parameter, so the 6-point
/// Gauss–Legendre rule per segment is exact up to rounding.
#[must_use]
pub fn area_moments(spline: &Spline) -> AreaMoments {
    let mut area = 0.0;
    let mut first = DVec2::ZERO; // (∮ x² dy / 2, −∮ y² dx / 2)
    let mut polar = 0.0; // J0 about the origin
    for segment in spline.segments() {
        area += gauss_legendre_6(0.0, 1.0, |t| {
            let [p, d, _] = segment.jet(t);
            p.perp_dot(d)
        });
        first.x += gauss_legendre_6(0.0, 1.0, |t| {
            let [p, d, _] = segment.jet(t);
            p.x * p.x * d.y
        });
        first.y -= gauss_legendre_6(0.0, 1.0, |t| {
            let [p, d, _] = segment.jet(t);
            p.y * p.y * d.x
        });
        polar += gauss_legendre_6(0.0, 1.0, |t| {
            let [p, d, _] = segment.jet(t);
            p.x * p.x * p.x * d.y - p.y * p.y * p.y * d.x
        });
    }
    let area = 0.5 * area;
    let centroid = 0.5 * first / area;
    let polar_about_origin = polar / 3.0;
    AreaMoments { area, centroid, polar_moment: polar_about_origin - area * centroid.length_squared() }
}

/// Mass, inertia about the centre of mass, and centre of mass for uniform `density`.
#[must_use]
pub fn mass_properties(spline: &Spline, density: f64) -> MassProperties {
    let moments = area_moments(spline);
    MassProperties {
        mass: density * moments.area,
        inertia: density * moments.polar_moment,
        centre_of_mass: moments.centroid,
    }
}

/// The curve moved so its centroid is the origin, and the centroid it had.
#[must_use]
pub fn recentre(spline: &Spline) -> (Spline, DVec2) {
    let centroid = area_moments(spline).centroid;
    (spline.translated(-centroid), centroid)
}
