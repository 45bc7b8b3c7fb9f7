//! Small numerical kernels: Gauss–Legendre rules and polynomial roots on the unit interval.

/// Nodes and weights of the 6-point Gauss–Legendre rule on `[-1, 1]`; exact for degree ≤ 11.
pub const GAUSS_LEGENDRE_6: [(f64, f64); 6] = [
    (-0.932_469_514_203_152, 0.171_324_492_379_170_35),
    (-0.661_209_386_466_264_5, 0.360_761_573_048_138_6),
    (-0.238_619_186_083_196_9, 0.467_913_934_572_691_04),
    (0.238_619_186_083_196_9, 0.467_913_934_572_691_04),
    (0.661_209_386_466_264_5, 0.360_761_573_048_138_6),
    (0.932_469_514_203_152, 0.171_324_492_379_170_35),
];

/// Nodes (positive half) and weights of the 16-point Gauss–Legendre rule on `[-1, 1]`.
const GAUSS_LEGENDRE_16_HALF: [(f64, f64); 8] = [
    (0.095_012_509_837_637_44, 0.189_450_610_455_068_5),
    (0.281_603_550_779_258_9, 0.182_603_415_044_923_6),
    (0.458_016_777_657_227_4, 0.169_156_519_395_002_5),
    (0.617_876_244_402_643_7, 0.149_595_988_816_576_7),
    (0.755_404_408_355_003, 0.124_628_971_255_533_9),
    (0.865_631_202_387_831_7, 0.095_158_511_682_492_78),
    (0.944_575_023_073_232_6, 0.062_253_523_938_647_89),
    (0.989_400_934_991_649_9, 0.027_152_459_411_754_1),
];

/// Integrates `f` over `[a, b]` with the 6-point rule (exact for polynomials of degree ≤ 11).
pub fn gauss_legendre_6(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    GAUSS_LEGENDRE_6.iter().map(|&(x, w)| w * f(mid + half * x)).sum::<f64>() * half
}

/// Integrates `f` over `[a, b]` with the 16-point rule.
pub fn gauss_legendre_16(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    GAUSS_LEGENDRE_16_HALF.iter().map(|&(x, w)| w * (f(mid - half * x) + f(mid + half * x))).sum::<f64>() * half
}

/// Real roots of `a t² + b t + c` that lie strictly inside `(0, 1)`, computed stably.
#[must_use]
pub fn unit_roots_of_quadratic(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    let inside = |t: f64| (t > 0.0 && t < 1.0).then_some(t);
    let scale = a.abs().max(b.abs()).max(c.abs());
    if scale == 0.0 {
        return [None, None];
    }
    if a.abs() <= 1e-14 * scale {
        return if b != 0.0 { [inside(-c / b), None] } else { [None, None] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return [None, None];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q == 0.0 {
        return [inside(0.0), None];
    }
    [inside(q / a), inside(c / q)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_point_rule_is_exact_to_degree_eleven() {
        let exact = 1.0 / 12.0; // ∫₀¹ t^11 dt
        assert!((gauss_legendre_6(0.0, 1.0, |t| t.powi(11)) - exact).abs() < 1e-15);
    }

    #[test]
    fn sixteen_point_rule_integrates_cosine() {
        let value = gauss_legendre_16(0.0, 1.0, f64::cos);
        assert!((value - 1f64.sin()).abs() < 1e-15);
    }

    #[test]
    fn quadratic_roots_inside_unit_interval() {
        let roots = unit_roots_of_quadratic(1.0, -1.0, 0.21); // roots 0.3 and 0.7
        let mut found: Vec<f64> = roots.into_iter().flatten().collect();
        found.sort_by(f64::total_cmp);
        assert_eq!(found.len(), 2);
        assert!((found[0] - 0.3).abs() < 1e-15 && (found[1] - 0.7).abs() < 1e-15);
        assert_eq!(unit_roots_of_quadratic(0.0, 2.0, -1.0)[0], Some(0.5));
        assert_eq!(unit_roots_of_quadratic(1.0, 0.0, 1.0), [None, None]);
    }
}
