//! Multiresolution of periodic cubic B-splines: Lane–Riesenfeld synthesis and local
//! reverse-subdivision analysis (Bartels–Samavati), MODEL §2.

use glam::DVec2;

/// Taps of the coarse filter A: `c_i` from fine points `f_{2i-3} .. f_{2i+3}`.
pub const ANALYSIS_COARSE_TAPS: [f64; 7] =
    [23.0 / 196.0, -23.0 / 49.0, 9.0 / 28.0, 52.0 / 49.0, 9.0 / 28.0, -23.0 / 49.0, 23.0 / 196.0];

/// Taps of the detail filter B: `d_i` from fine points `f_{2i-1} .. f_{2i+3}`.
pub const ANALYSIS_DETAIL_TAPS: [f64; 5] =
    [13.0 / 98.0, -4.0 * 13.0 / 98.0, 6.0 * 13.0 / 98.0, -4.0 * 13.0 / 98.0, 13.0 / 98.0];

fn at(points: &[DVec2], i: isize) -> DVec2 {
    points[i.rem_euclid(points.len() as isize) as usize]
}

/// One Lane–Riesenfeld subdivision of a closed control polygon (n → 2n points):
/// `f_{2i} = (c_{i-1} + 6c_i + c_{i+1})/8`, `f_{2i+1} = (c_i + c_{i+1})/2`. Same curve, finer polygon.
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
    if fine.len() % 2 != 0 || fine.len() < 8 {
        return None;
    }
    let n = fine.len() / 2;
    let mut coarse = Vec::with_capacity(n);
    let mut details = Vec::with_capacity(n);
    for i in 0..n as isize {
        let c = ANALYSIS_COARSE_TAPS
            .iter()
            .enumerate()
            .map(|(k, &w)| w * at(fine, 2 * i - 3 + k as isize))
            .fold(DVec2::ZERO, |acc, v| acc + v);
        let d = ANALYSIS_DETAIL_TAPS
            .iter()
            .enumerate()
            .map(|(k, &w)| w * at(fine, 2 * i - 1 + k as isize))
            .fold(DVec2::ZERO, |acc, v| acc + v);
        coarse.push(c);
        details.push(d);
    }
    Some((coarse, details))
}
