//! The statistics behind the independent-seed comparison: Welch's two-sample t-test and
//! Holm's correction across many tests, so the whole comparison has a stated false-alarm rate.

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
}
