//! The statistics behind the project's tests of agreement: Welch's two-sample t-test and
//! Holm's correction across many tests, so that a comparison of backends with independent
//! seeds has a stated false-alarm rate; Pearson's chi-square tail and Sidak's correction, for
//! the goodness-of-fit tests of the BSDF samplers (`ppm-core/tests/bsdf_sampling`).

/// Mean and unbiased variance of a sample.
pub fn mean_variance(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var)
}

/// Welch's t statistic and its Welch-Satterthwaite degrees of freedom, each sample's
/// variance taken at least `min_variance` (a floor against samples that happen to be nearly
/// constant, whose spread would otherwise be underestimated).
pub fn welch_t(a: &[f64], b: &[f64], min_variance: f64) -> (f64, f64) {
    let (ma, va) = mean_variance(a);
    let (mb, vb) = mean_variance(b);
    let (va, vb) = (va.max(min_variance), vb.max(min_variance));
    let (sa, sb) = (va / a.len() as f64, vb / b.len() as f64);
    let se2 = sa + sb;
    if se2 <= 0.0 {
        // Both samples constant: equal means agree exactly, different ones infinitely not.
        let t = if ma == mb { 0.0 } else { f64::INFINITY };
        return (t, (a.len() + b.len() - 2) as f64);
    }
    let df = se2 * se2
        / (sa * sa / (a.len() as f64 - 1.0) + sb * sb / (b.len() as f64 - 1.0))
            .max(f64::MIN_POSITIVE);
    ((ma - mb) / se2.sqrt(), df)
}

/// Two-sided p-value of Student's t with `df` degrees of freedom: `I_{df/(df+t^2)}(df/2, 1/2)`.
pub fn t_two_sided_p(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    regularized_incomplete_beta(df / (df + t * t), 0.5 * df, 0.5)
}

/// `I_x(a, b)` by the continued fraction of Numerical Recipes (Lentz's method).
pub fn regularized_incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    // The fraction converges fast for x < (a+1)/(a+b+2); use the symmetry otherwise.
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_fraction(x, a, b) / a
    } else {
        1.0 - ln_front.exp() * beta_fraction(1.0 - x, b, a) / b
    }
}

fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    d = 1.0 / if d.abs() < TINY { TINY } else { d };
    let mut h = d;
    for m in 1..300 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        for aa in [
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ] {
            d = 1.0 + aa * d;
            d = 1.0 / if d.abs() < TINY { TINY } else { d };
            c = 1.0 + aa / c;
            c = if c.abs() < TINY { TINY } else { c };
            h *= d * c;
        }
        if (d * c - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// `ln Gamma(x)` for x > 0 (Lanczos, g = 7, n = 9), accurate to ~1e-15.
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
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
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let sum = G[1..]
        .iter()
        .enumerate()
        .fold(G[0], |s, (i, g)| s + g / (x + i as f64 + 1.0));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

/// The chance that a chi-square variable with `dof` degrees of freedom exceeds `statistic`:
/// the regularised upper incomplete gamma function `Q(dof / 2, statistic / 2)`, by a series
/// below `a + 1` and a continued fraction above (Press et al., "Numerical Recipes", 6.2).
pub fn chi_square_p(statistic: f64, dof: usize) -> f64 {
    let (a, x) = (dof as f64 / 2.0, statistic / 2.0);
    if x.is_nan() || x == f64::INFINITY {
        return 0.0;
    }
    if x <= 0.0 {
        return 1.0;
    }
    // ln(x^a e^-x / Gamma(a)), the factor both expansions share.
    let front = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = x^a e^-x / Gamma(a + 1) * sum x^k / ((a + 1) ... (a + k)).
        let (mut term, mut sum, mut denominator) = (1.0 / a, 1.0 / a, a);
        for _ in 0..100_000 {
            denominator += 1.0;
            term *= x / denominator;
            sum += term;
            if term < sum * 1e-16 {
                break;
            }
        }
        return (1.0 - sum * front.exp()).max(0.0);
    }
    // Q(a, x) = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - ...)), by the
    // modified Lentz method.
    let tiny = 1e-300;
    let mut b = x + 1.0 - a;
    let (mut c, mut d) = (1.0 / tiny, 1.0 / b);
    let mut fraction = d;
    for i in 1..100_000 {
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
        let step = d * c;
        fraction *= step;
        if (step - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (front.exp() * fraction).clamp(0.0, 1.0)
}

/// The level each of `tests` independent tests must meet for all of them together to reject
/// a right sampler with chance `alpha` (Sidak's correction).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

/// Holm's step-down correction: which of `p_values` are rejected at family-wise rate `alpha`.
pub fn holm_rejections(p_values: &[f64], alpha: f64) -> Vec<bool> {
    let mut order: Vec<usize> = (0..p_values.len()).collect();
    order.sort_by(|&i, &j| p_values[i].total_cmp(&p_values[j]));
    let m = p_values.len();
    let mut rejected = vec![false; m];
    for (rank, &i) in order.iter().enumerate() {
        if p_values[i] <= alpha / (m - rank) as f64 {
            rejected[i] = true;
        } else {
            break;
        }
    }
    rejected
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() < tol, "{a} vs {b}");
    }

    #[test]
    fn ln_gamma_matches_factorials() {
        close(ln_gamma(1.0), 0.0, 1e-12);
        close(ln_gamma(5.0), 24f64.ln(), 1e-12);
        close(ln_gamma(0.5), std::f64::consts::PI.sqrt().ln(), 1e-12);
    }

    /// Reference values from Student's t tables: P(|T| > 2.447) = 0.05 at 6 df,
    /// P(|T| > 1.96) = 0.05 as df grows, P(|T| > 0) = 1.
    #[test]
    fn t_p_values_match_tables() {
        close(t_two_sided_p(2.447, 6.0), 0.05, 1e-3);
        close(t_two_sided_p(1.96, 1e6), 0.05, 1e-4);
        close(t_two_sided_p(0.0, 3.0), 1.0, 1e-12);
        close(t_two_sided_p(12.706, 1.0), 0.05, 1e-3);
    }

    #[test]
    fn welch_separates_shifted_samples_and_not_equal_ones() {
        let a = [1.0, 1.1, 0.9, 1.05, 0.95];
        let b = [2.0, 2.1, 1.9, 2.05, 1.95];
        let (t, df) = welch_t(&a, &b, 0.0);
        assert!(t_two_sided_p(t, df) < 1e-6);
        let (t, df) = welch_t(&a, &a, 0.0);
        close(t_two_sided_p(t, df), 1.0, 1e-12);
    }

    #[test]
    fn holm_rejects_only_what_survives_the_step_down() {
        let r = holm_rejections(&[0.001, 0.04, 0.03, 0.5], 0.05);
        assert_eq!(r, vec![true, false, false, false]);
        let r = holm_rejections(&[0.001, 0.012, 0.02], 0.05);
        assert_eq!(r, vec![true, true, true]);
    }

    #[test]
    fn the_chi_square_tail_meets_known_quantiles() {
        // Even degrees of freedom have a closed form: Q(k, y) = e^-y sum_{j < k} y^j / j!.
        for (dof, statistic) in [
            (2usize, 9.21),
            (4, 3.0),
            (10, 23.2),
            (100, 135.8),
            (1000, 1107.0),
        ] {
            let y = statistic / 2.0;
            let (mut term, mut sum) = (1.0f64, 1.0f64);
            for j in 1..dof / 2 {
                term *= y / j as f64;
                sum += term;
            }
            let closed = (sum.ln() - y).exp();
            let p = chi_square_p(statistic, dof);
            assert!(
                (p - closed).abs() <= 1e-10 * closed.max(1e-3),
                "{dof}: {p} {closed}"
            );
        }
        // Upper 5% and 1% quantiles of odd degrees of freedom (R's `qchisq`).
        for (dof, statistic, p) in [
            (1usize, 3.841_458_820_694_124, 0.05),
            (1, 6.634_896_601_021_214, 0.01),
            (3, 11.344_866_730_144_37, 0.01),
            (25, 44.314_104_896_219_16, 0.01),
        ] {
            let got = chi_square_p(statistic, dof);
            assert!((got - p).abs() < 1e-9, "{dof}: {got} against {p}");
        }
        assert_eq!(chi_square_p(0.0, 5), 1.0);
        assert_eq!(chi_square_p(f64::INFINITY, 5), 0.0);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-14);
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-15);
    }
}
