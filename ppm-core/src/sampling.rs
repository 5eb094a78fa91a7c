//! Warps from uniform numbers to the distributions the passes sample.

use glam::Vec3;
use std::f32::consts::PI;

/// Cosine-weighted direction about +z of a local frame (Malley's method).
#[inline]
pub fn cosine_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// Barycentric weights `(b1, b2)` of a point uniform on a triangle: `v0 + b1*e1 + b2*e2`.
#[inline]
pub fn uniform_triangle(u1: f32, u2: f32) -> (f32, f32) {
    let s = u1.sqrt();
    (s * (1.0 - u2), s * u2)
}

/// Direction uniform inside the cone of half-angle `cos_max` about +z of a local frame.
#[inline]
pub fn uniform_cone(u1: f32, u2: f32, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u1 * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Solid-angle density of choosing a point on a light whose selection probability is `pdf`
/// and area `area` (uniform on it), seen at squared distance `dist2` under cosine `cos_l`.
#[inline]
pub fn light_pdf(pdf: f32, area: f32, dist2: f32, cos_l: f32) -> f32 {
    pdf / area * dist2 / cos_l
}

/// Power-heuristic (beta = 2) weight of a sampling strategy with density `a` against one with
/// density `b` (Veach 1997): the two weights of a sample sum to one.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Index of the first entry of a cumulative distribution that exceeds `u` (the last entry is 1).
#[inline]
pub fn sample_cdf(cdf: impl Fn(usize) -> f32, len: usize, u: f32) -> usize {
    let (mut lo, mut hi) = (0usize, len - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < cdf(mid) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::bits_to_unit;
    use crate::rng::random_bits;

    fn u(i: u32, d: u32) -> f32 {
        bits_to_unit(random_bits(9, 1, 0, i, d))
    }

    /// E[cos] under the cosine density is 2/3; a uniform hemisphere would give 1/2.
    #[test]
    fn cosine_hemisphere_has_the_cosine_mean() {
        let n = 200_000;
        let mean: f64 = (0..n)
            .map(|i| cosine_hemisphere(u(i, 0), u(i, 1)).z as f64)
            .sum::<f64>()
            / n as f64;
        assert!((mean - 2.0 / 3.0).abs() < 3e-3, "mean cos = {mean}");
    }

    #[test]
    fn uniform_triangle_stays_inside_with_centroid_mean() {
        let n = 100_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let (b1, b2) = uniform_triangle(u(i, 0), u(i, 1));
            assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6);
            s1 += b1 as f64;
            s2 += b2 as f64;
        }
        assert!((s1 / n as f64 - 1.0 / 3.0).abs() < 3e-3);
        assert!((s2 / n as f64 - 1.0 / 3.0).abs() < 3e-3);
    }

    #[test]
    fn cone_directions_stay_in_the_cone() {
        let cos_max = 10f32.to_radians().cos();
        for i in 0..10_000 {
            let d = uniform_cone(u(i, 0), u(i, 1), cos_max);
            assert!(d.z >= cos_max - 1e-6);
            assert!((d.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn cdf_sampling_picks_the_bracketing_entry() {
        let cdf = [0.25f32, 0.5, 1.0];
        assert_eq!(sample_cdf(|i| cdf[i], 3, 0.0), 0);
        assert_eq!(sample_cdf(|i| cdf[i], 3, 0.25), 1);
        assert_eq!(sample_cdf(|i| cdf[i], 3, 0.49), 1);
        assert_eq!(sample_cdf(|i| cdf[i], 3, 0.99), 2);
    }
}
