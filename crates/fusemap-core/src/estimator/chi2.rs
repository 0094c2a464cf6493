//! χ² quantiles for the Mahalanobis gate.
//!
//! A measurement with innovation `ν` and innovation covariance `S` is consistent with the
//! filter when its normalised innovation squared `νᵀ S⁻¹ ν` (NIS) is below the χ² quantile
//! for the measurement's degrees of freedom at the chosen probability (Bar-Shalom, Li &
//! Kirubarajan, *Estimation with Applications to Tracking and Navigation*, §5.4). The
//! quantile is computed, not tabulated, so any probability and dimension work: the χ²
//! distribution function with `k` degrees of freedom is the regularised lower incomplete
//! gamma function `P(k/2, x/2)`, evaluated by its series or continued fraction (Press et
//! al., *Numerical Recipes*, §6.2), and inverted by bisection.

/// `ln Γ(x)` for `x > 0` (Lanczos approximation, g = 7, nine coefficients; relative error
/// below 1e-15 in double precision).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised lower incomplete gamma function `P(a, x)`.
fn gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_prefix = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        // Series: P = e^{-x} x^a / Γ(a+1) Σ x^n / ((a+1)…(a+n)).
        let (mut ap, mut sum, mut del) = (a, 1.0 / a, 1.0 / a);
        for _ in 0..1000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        sum * ln_prefix.exp()
    } else {
        // Continued fraction for Q = 1 − P (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - ln_prefix.exp() * h
    }
}

/// The χ² distribution function with `dof` degrees of freedom at `x`.
pub fn chi_square_cdf(dof: u32, x: f64) -> f64 {
    if dof == 0 || !x.is_finite() {
        return if x.is_finite() || x < 0.0 { 0.0 } else { 1.0 };
    }
    gamma_p(dof as f64 / 2.0, x / 2.0)
}

/// The `probability` quantile of the χ² distribution with `dof` degrees of freedom: the
/// Mahalanobis gate for a `dof`-dimensional measurement. `None` unless `dof ≥ 1` and
/// `0 < probability < 1`.
pub fn chi_square_quantile(dof: u32, probability: f64) -> Option<f64> {
    if dof == 0 || !(probability > 0.0 && probability < 1.0) {
        return None;
    }
    let mut hi = dof as f64 + 10.0;
    while chi_square_cdf(dof, hi) < probability {
        hi *= 2.0;
        if hi > 1e12 {
            return None;
        }
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi_square_cdf(dof, mid) < probability {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * hi {
            break;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn quantiles_match_published_tables() {
        // NIST/SEMATECH e-Handbook, table of upper critical values of the χ² distribution.
        for (dof, p, want) in [
            (1, 0.99, 6.635),
            (2, 0.99, 9.210),
            (3, 0.99, 11.345),
            (1, 0.95, 3.841),
            (2, 0.95, 5.991),
            (3, 0.95, 7.815),
            (10, 0.99, 23.209),
            (2, 0.999, 13.816),
        ] {
            let got = chi_square_quantile(dof, p).unwrap();
            assert!((got - want).abs() < 1e-3, "dof {dof} p {p}: {got} vs {want}");
        }
        // Two degrees of freedom have the closed form −2 ln(1 − p).
        let p: f64 = 0.9973;
        assert!((chi_square_quantile(2, p).unwrap() - (-2.0 * (1.0 - p).ln())).abs() < 1e-9);
        assert_eq!(chi_square_quantile(0, 0.5), None);
        assert_eq!(chi_square_quantile(2, 1.0), None);
        assert_eq!(chi_square_quantile(2, f64::NAN), None);
    }

    proptest! {
        #[test]
        fn quantile_inverts_the_distribution(dof in 1u32..8, p in 0.01..0.999f64) {
            let q = chi_square_quantile(dof, p).unwrap();
            prop_assert!((chi_square_cdf(dof, q) - p).abs() < 1e-9);
        }
    }
}
