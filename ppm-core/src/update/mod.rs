//! The progressive update of a hit point's statistics (docs/algorithm.md 1.4, thesis eqs 1 to 4),
//! written in the forms that stay accurate in f32.

use std::f32::consts::PI;

pub mod gather;
pub mod pairing;

/// A hit point's running statistics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Statistics {
    /// Accumulated photon count `n`.
    pub n: f32,
    /// Squared radius `r2`.
    pub r2: f32,
    /// Accumulated flux `tau`, per channel.
    pub tau: [f32; 3],
}

/// The shrink factor `(n + alpha*M) / (n + M)`, written as `1 - (1 - alpha) * M / (n + M)`.
///
/// The naive quotient divides two large, nearly equal numbers once `n` dwarfs `M`, and its
/// numerator stops growing once `n` passes 2^24; this form computes the small departure from 1
/// directly, so it stays in (alpha, 1] and never rounds above 1. Callers ensure `n + M > 0`.
#[inline]
pub fn shrink_ratio(n: f32, m: f32, alpha: f32) -> f32 {
    1.0 - (1.0 - alpha) * (m / (n + m))
}

/// Folds one gather pass into the statistics (thesis eqs 1 to 3).
///
/// `m` photons were found within the radius, carrying `dtau` (power times BRDF). When no photon
/// has ever arrived (`n + m == 0`) nothing changes.
#[inline]
pub fn ppm_update(s: Statistics, m: f32, dtau: [f32; 3], alpha: f32) -> Statistics {
    if s.n + m <= 0.0 {
        return s;
    }
    let ratio = shrink_ratio(s.n, m, alpha);
    Statistics {
        n: s.n + alpha * m,
        r2: s.r2 * ratio,
        tau: [
            (s.tau[0] + dtau[0]) * ratio,
            (s.tau[1] + dtau[1]) * ratio,
            (s.tau[2] + dtau[2]) * ratio,
        ],
    }
}

/// Folds one gather of compensation (negative) photons into the statistics (thesis eqs 5 to
/// 7, docs/algorithm.md 3, "Counts that go negative").
///
/// `m` counts the negative photons found (in ordinary-photon units), `dtau` is their
/// (negative) flux. The count falls by `alpha * m` and radius and flux grow by the ratio
/// `(n - alpha*m) / (n - m)`, written `1 + (1 - alpha) * m / (n - m)` so the departure from 1
/// is computed directly. Clamps: once the negative photons reach the count (`m >= n`, which
/// includes `n - alpha*m <= 0`) the hit point is emptied (`n = 0`, `tau = 0`,
/// `r2 = r2_initial`) rather than divided by zero or a negative number; `r2` never exceeds
/// `r2_initial`, and `tau` grows by the same factor as `r2`, so the flux density never
/// rises by removing photons; every `tau` channel is clamped at zero.
#[inline]
pub fn compensation_update(
    s: Statistics,
    m: f32,
    dtau: [f32; 3],
    alpha: f32,
    r2_initial: f32,
) -> Statistics {
    if m <= 0.0 {
        return s;
    }
    if m >= s.n {
        return Statistics {
            n: 0.0,
            r2: r2_initial,
            tau: [0.0; 3],
        };
    }
    let ratio = 1.0 + (1.0 - alpha) * (m / (s.n - m));
    // The flux grows with the disc it now stands for: where the cap stops the disc, the flux
    // stops with it, so the density `tau / r2` never grows by what the cap cut off (with `m`
    // near `n` the ratio is unbounded, and a flux scaled by it alone blew kept slots up).
    let r2 = (s.r2 * ratio).min(r2_initial);
    let grown = if s.r2 > 0.0 { r2 / s.r2 } else { ratio };
    Statistics {
        n: s.n - alpha * m,
        r2,
        tau: [
            ((s.tau[0] + dtau[0]) * grown).max(0.0),
            ((s.tau[1] + dtau[1]) * grown).max(0.0),
            ((s.tau[2] + dtau[2]) * grown).max(0.0),
        ],
    }
}

/// Reflected radiance estimate `tau / (pi * r2 * emitted)` (thesis eq 4, docs/algorithm.md 1.5).
///
/// Divides in two steps so the product `pi * r2 * emitted` is never formed: it overflows at
/// huge scales or photon counts, and underflows at tiny ones. Zero while nothing was emitted;
/// a density beyond f32's range (a radius shrunk towards underflow) saturates at `f32::MAX`
/// instead of becoming infinite.
#[inline]
pub fn radiance(tau: [f32; 3], r2: f32, emitted: f32) -> [f32; 3] {
    if emitted <= 0.0 || r2 <= 0.0 {
        return [0.0; 3];
    }
    let area = PI * r2;
    tau.map(|t| ((t / emitted) / area).min(f32::MAX))
}

/// Rec. 709 luminance of a linear RGB value: how the corrections below weigh channels.
#[inline]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// How much of a slot's history to keep after a correction of variance `variance` (in squared
/// luminance of flux) was added to statistics `n`, `tau` (the corrected flux);
/// docs/algorithm.md 3c.
///
/// A slot's flux sum built from `n` photons has relative variance about `1 / n`; the
/// correction adds `variance / lum(tau)^2`. The corrected statistics are then worth as much as
/// `1 / (1/n + variance / lum(tau)^2)` photons of their own, a fraction
/// `f = 1 / (1 + n * variance / lum(tau)^2)` of `n`: scaling `tau` and `emitted` by `f` keeps
/// the estimate and lets the photons that follow weigh what they are worth against it, so the
/// correction's noise fades at the rate of a consistent estimator instead of freezing in
/// statistics built from many more samples. No variance keeps everything; a correction that
/// leaves no flux (or noise of any size against zero) keeps nothing. After an earlier
/// correction `n` is what that one kept (`n - HitPoint::discounted`): two corrections then
/// keep what one of their summed variance would, where weighing each against the whole
/// count would discount the history again at every move of a drag.
#[inline]
pub fn history_kept(n: f32, tau: [f32; 3], variance: f32) -> f32 {
    // NaN counts as no variance, as in the WGSL twin.
    if variance.is_nan() || variance <= 0.0 {
        return 1.0;
    }
    let lum = luminance(tau);
    let relative = variance / (lum * lum);
    if !relative.is_finite() {
        return 0.0;
    }
    (1.0 / (1.0 + n * relative)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn stats(n: f32, r2: f32, tau: f32) -> Statistics {
        Statistics {
            n,
            r2,
            tau: [tau; 3],
        }
    }

    /// Negative photons nearly as many as the count, on a converged disc: the ratio is huge,
    /// the radius stops at its initial value, and the radiance must not rise (the photons
    /// removed carried flux); scaling the flux by the ratio alone made it 300 times brighter.
    #[test]
    fn removing_photons_never_raises_the_radiance() {
        let s = stats(100.0, 1.0, 50.0);
        let before = radiance(s.tau, s.r2, 1e4)[0];
        for (m, removed) in [(99.9, -0.5), (50.0, -20.0), (1.0, -0.4), (99.999, 0.0)] {
            let after = compensation_update(s, m, [removed; 3], 0.7, 4.0);
            assert!(after.r2 <= 4.0 && after.r2 >= s.r2, "{after:?}");
            let r = radiance(after.tau, after.r2, 1e4)[0];
            assert!(
                r <= before * (1.0 + 1e-5),
                "m {m}: radiance {before} -> {r}"
            );
        }
    }

    /// A correction as noisy as the slot's own statistics halves what it keeps; none keeps
    /// everything; one against no flux keeps nothing; the weight falls as the noise grows.
    #[test]
    fn history_kept_weighs_the_correction_against_the_slot() {
        let tau = [10.0; 3];
        // Relative variance 1/n from n = 100 photons; the same again from the correction.
        let own = 100.0 / 100.0;
        assert_relative_eq!(history_kept(100.0, tau, own), 0.5, epsilon = 1e-6);
        assert_eq!(history_kept(100.0, tau, 0.0), 1.0);
        assert_eq!(history_kept(100.0, [0.0; 3], 1.0), 0.0);
        let (small, large) = (
            history_kept(100.0, tau, 0.1),
            history_kept(100.0, tau, 10.0),
        );
        assert!(1.0 > small && small > 0.5 && 0.5 > large && large > 0.0);
        assert_eq!(history_kept(1e30, tau, 1e30), 0.0);
    }

    #[test]
    fn count_grows_by_alpha_m_and_radius_shrinks_monotonically() {
        let alpha = 0.7;
        let mut s = stats(0.0, 400.0, 0.0);
        for pass in 0..200 {
            let m = (pass % 7) as f32;
            let next = ppm_update(s, m, [1.0 * m; 3], alpha);
            assert_relative_eq!(next.n, s.n + alpha * m, max_relative = 1e-6);
            assert!(next.r2 <= s.r2, "radius grew at pass {pass}");
            if m > 0.0 {
                assert!(next.r2 < s.r2, "radius did not shrink at pass {pass}");
            }
            s = next;
        }
    }

    #[test]
    fn empty_gather_on_empty_point_changes_nothing() {
        let s = stats(0.0, 4.0, 0.0);
        assert_eq!(ppm_update(s, 0.0, [0.0; 3], 0.5), s);
    }

    /// With a constant photon density the estimate keeps its value while the radius shrinks:
    /// after `k` passes of `density * r2` unit-power photons each, `tau / (r2 * k)` is the
    /// density again, because the flux is rescaled by exactly the factor that shrinks the disc.
    #[test]
    fn gather_keeps_density_when_radius_shrinks() {
        let alpha = 0.6;
        let density = 3.0; // photons per pass per unit r2 (the disc area over pi)
        let mut s = stats(0.0, 100.0, 0.0);
        for k in 1..=50 {
            let m = density * s.r2;
            s = ppm_update(s, m, [m; 3], alpha);
            assert_relative_eq!(s.tau[0] / (s.r2 * k as f32), density, max_relative = 1e-4);
        }
        assert!(s.r2 < 20.0, "radius barely shrank: r2 = {}", s.r2);
    }

    #[test]
    fn ratio_matches_the_quotient_where_both_are_exact() {
        for (n, m, alpha) in [(10.0, 5.0, 0.7), (0.0, 3.0, 0.5), (1000.0, 1.0, 0.9)] {
            let quotient = (n + alpha * m) / (n + m);
            assert_relative_eq!(shrink_ratio(n, m, alpha), quotient, max_relative = 1e-6);
        }
    }

    /// Eqs 5-7 reverse eqs 1-3 in the count: removing the M photons just added restores `n`,
    /// and the radius grows back (not exactly to where it was: the thesis's ratio is taken at
    /// the new count) while the flux falls.
    #[test]
    fn compensation_reverses_the_count_and_grows_the_radius() {
        let before = stats(40.0, 300.0, 12.0);
        let added = ppm_update(before, 10.0, [5.0; 3], 0.7);
        let removed = compensation_update(added, 10.0, [-5.0; 3], 0.7, 400.0);
        assert_relative_eq!(removed.n, before.n, max_relative = 1e-6);
        assert!(removed.r2 > added.r2 && removed.r2 <= 400.0, "{removed:?}");
        assert!(
            removed.tau[0] < added.tau[0] && removed.tau[0] >= 0.0,
            "{removed:?}"
        );
    }

    #[test]
    fn negative_photons_outnumbering_the_count_empty_the_hit_point() {
        let s = stats(5.0, 100.0, 3.0);
        for m in [5.0, 6.0, 1e6] {
            let e = compensation_update(s, m, [-1.0; 3], 0.7, 400.0);
            assert_eq!((e.n, e.r2, e.tau), (0.0, 400.0, [0.0; 3]), "m = {m}");
        }
    }

    #[test]
    fn compensation_clamps_radius_and_flux() {
        // Nearly all photons removed: the ratio is huge, r2 stops at r2_initial.
        let s = compensation_update(stats(10.0, 350.0, 1.0), 9.99, [-50.0; 3], 0.7, 400.0);
        assert!(s.n > 0.0 && s.r2 == 400.0 && s.tau == [0.0; 3], "{s:?}");
        for m in [0.1f32, 1.0, 4.0, 9.0] {
            let s = compensation_update(stats(10.0, 100.0, 2.0), m, [-3.0; 3], 0.5, 400.0);
            assert!(
                s.n.is_finite() && s.r2 <= 400.0 && s.r2 >= 100.0 && s.tau[0] >= 0.0,
                "{s:?}"
            );
        }
    }

    #[test]
    fn radiance_divides_by_disc_area_and_emitted() {
        let l = radiance([2.0 * PI, 0.0, 4.0 * PI], 2.0, 0.5);
        assert_relative_eq!(l[0], 2.0);
        assert_relative_eq!(l[2], 4.0);
        assert_eq!(radiance([1.0; 3], 1.0, 0.0), [0.0; 3]);
        // The product pi * r2 * emitted overflows f32 here; the two-step form does not.
        let big = radiance([1e30; 3], 1e20, 1e20);
        assert!(big[0].is_finite() && big[0] > 0.0);
    }
}

/// The stable forms matter: the naive formulas, kept here in the tests only, fail on states
/// the stress family reaches (`count-past-2^24`, `negative-outnumbers-n`, `r2-underflow`,
/// `scale-1e4` with many photons), where the forms above stay finite and in range. The stress
/// family runs those states on both backends (tests/tests/stress.rs).
#[cfg(test)]
mod naive_forms {
    use super::*;

    fn naive_compensation(s: Statistics, m: f32, dtau: f32, alpha: f32) -> Statistics {
        let ratio = (s.n - alpha * m) / (s.n - m);
        Statistics {
            n: s.n - alpha * m,
            r2: s.r2 * ratio,
            tau: s.tau.map(|t| (t + dtau) * ratio),
        }
    }

    #[test]
    fn naive_eqs_5_to_7_break_when_negative_photons_outnumber_n_and_the_clamped_form_does_not() {
        let s = Statistics {
            n: 5.0,
            r2: 100.0,
            tau: [3.0; 3],
        };
        let naive = naive_compensation(s, 6.0, -4.0, 0.7);
        assert!(naive.r2 < 0.0 && naive.tau[0] > 0.0, "naive: {naive:?}");
        let at_n = naive_compensation(s, 5.0, -4.0, 0.7);
        assert!(
            !at_n.r2.is_finite(),
            "naive at m = n divides by zero: {at_n:?}"
        );
        let stable = compensation_update(s, 6.0, [-4.0; 3], 0.7, 400.0);
        assert_eq!((stable.n, stable.r2, stable.tau), (0.0, 400.0, [0.0; 3]));
    }

    #[test]
    fn naive_radiance_overflows_where_the_two_step_form_does_not() {
        // A huge radius (r2 = 1e24) after 2.1e15 photons: pi * r2 * emitted = 6.6e39 overflows
        // f32 to infinity in the product, although the estimate itself is ordinary.
        let (tau, r2, emitted) = (1e20f32, 1e24f32, 2.1e15f32);
        let naive = tau / (std::f32::consts::PI * r2 * emitted);
        assert_eq!(
            naive, 0.0,
            "the product overflowed to infinity and the quotient vanished"
        );
        let stable = radiance([tau; 3], r2, emitted)[0];
        assert!(stable > 0.0 && stable.is_finite(), "{stable}");
    }

    #[test]
    fn naive_ratio_is_less_accurate_past_2_24() {
        // Past 2^24 the naive quotient's numerator stops growing: (n + alpha*M) rounds to n
        // while the denominator grows, so the ratio mixes two roundings; the stable form
        // computes the departure from 1 directly and stays in (alpha, 1].
        let (n, m, alpha) = (3.4e7f32, 3.0f32, 0.7f32);
        let naive = (n + alpha * m) / (n + m);
        let stable = shrink_ratio(n, m, alpha);
        let exact = 1.0 - (1.0 - f64::from(alpha)) * f64::from(m) / (f64::from(n) + f64::from(m));
        assert!(
            (f64::from(stable) - exact).abs() <= (f64::from(naive) - exact).abs(),
            "naive {naive}, stable {stable}, exact {exact}"
        );
        assert!(stable <= 1.0 && stable > alpha);
    }
}
