//! Pearson's chi-square test of a direction sampler against a density over [`SphereGrid`]'s
//! bins, its p-value, and the random numbers that drive the samplers.
//!
//! The sampler and the density come in as closures, so that a deliberately wrong sampler can
//! be scored against a right density (the suite's `wrong_samplers_are_rejected`). Samples the
//! sampler does not count (a direction below the surface that ends the path, a delta lobe's)
//! fall in one more bin, whose expected count is what the density leaves of one: the counts
//! are then one multinomial draw, and the statistic follows chi-square with one degree of
//! freedom less than the bins kept.

use super::sphere_grid::SphereGrid;
use glam::Vec3;
use ppm_core::stats::chi_square_p;

/// Bins whose expected count is below this are pooled into one, so that Pearson's statistic
/// follows the chi-square distribution closely (the usual rule; pbrt-v4 and Mitsuba 3 use it).
const MIN_EXPECTED: f64 = 5.0;

/// SplitMix64 (Steele et al. 2014): a generator that shares nothing with the renderer's
/// `pcg4d` streams, so that the test does not inherit their flaws.
pub struct Rng(u64);

impl Rng {
    /// The stream of `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A float in `[0, 1)` from the top 24 bits: every value exactly representable, as the
    /// renderer's own numbers are.
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two of [`Self::uniform`].
    pub fn pair(&mut self) -> (f32, f32) {
        (self.uniform(), self.uniform())
    }
}

/// What one chi-square test found.
#[derive(Clone, Copy, Debug)]
pub struct Outcome {
    /// Pearson's statistic.
    pub statistic: f64,
    /// Its degrees of freedom: the bins kept after pooling, less one.
    pub dof: usize,
    /// The chance of a statistic at least this large if the sampler draws the density.
    pub p_value: f64,
    /// The density's integral over the sphere.
    pub integral: f64,
    /// The samples the sampler counted.
    pub valid: usize,
    /// The samples drawn.
    pub n: usize,
    /// Counted samples in bins where the density's integral is zero: a sampler that draws
    /// where its density says it cannot.
    pub stray: usize,
    /// The three bins that add most to the statistic, as `(bin, observed, expected)`; the
    /// bin past the grid's is the samples not counted.
    pub worst: [(usize, f64, f64); 3],
}

impl Outcome {
    /// The share of samples counted.
    pub fn valid_share(&self) -> f64 {
        self.valid as f64 / self.n as f64
    }
}

/// Draws `n` samples (`draw` gives a direction to count, or `None`) and scores their bins
/// against `n` times the integrals of `density` over them.
pub fn test(
    grid: &SphereGrid,
    n: usize,
    rng: &mut Rng,
    draw: impl FnMut(&mut Rng) -> Option<Vec3>,
    density: impl Fn(Vec3) -> f64,
) -> Outcome {
    let integrals: Vec<f64> = grid
        .integrate(|d| [density(d)])
        .iter()
        .map(|[p]| *p)
        .collect();
    test_integrals(grid, n, rng, draw, &integrals)
}

/// [`test`] against the density's integrals over the bins, computed beforehand (with the
/// lobe's value in the same pass).
pub fn test_integrals(
    grid: &SphereGrid,
    n: usize,
    rng: &mut Rng,
    mut draw: impl FnMut(&mut Rng) -> Option<Vec3>,
    integrals: &[f64],
) -> Outcome {
    let mut observed = vec![0.0f64; grid.cells() + 1];
    let lost = grid.cells();
    for _ in 0..n {
        let cell = draw(rng).map_or(lost, |dir| grid.cell_of(dir));
        observed[cell] += 1.0;
    }
    let integral: f64 = integrals.iter().sum();
    let mut expected: Vec<f64> = integrals.iter().map(|p| p * n as f64).collect();
    expected.push((1.0 - integral).max(0.0) * n as f64);
    let stray = integrals
        .iter()
        .zip(&observed)
        .filter(|&(&p, _)| p == 0.0)
        .map(|(_, &o)| o as usize)
        .sum();
    let (statistic, dof) = pearson(&observed, &expected);
    let mut worst: Vec<(usize, f64, f64)> = (0..observed.len())
        .filter(|&i| expected[i] >= MIN_EXPECTED)
        .map(|i| (i, observed[i], expected[i]))
        .collect();
    let excess = |&(_, o, e): &(usize, f64, f64)| (o - e) * (o - e) / e;
    worst.sort_by(|a, b| excess(b).total_cmp(&excess(a)));
    worst.resize(3, (lost, 0.0, 0.0));
    Outcome {
        statistic,
        dof,
        p_value: chi_square_p(statistic, dof),
        integral,
        valid: n - observed[lost] as usize,
        n,
        stray,
        worst: [worst[0], worst[1], worst[2]],
    }
}

/// Pearson's statistic over the bins, those expecting fewer than [`MIN_EXPECTED`] pooled
/// into one (itself folded into the smallest other bin when it still expects fewer), and
/// its degrees of freedom.
fn pearson(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let mut kept: Vec<(f64, f64)> = Vec::new();
    let mut pooled = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < MIN_EXPECTED {
            pooled = (pooled.0 + o, pooled.1 + e);
        } else {
            kept.push((o, e));
        }
    }
    if pooled.1 >= MIN_EXPECTED || kept.is_empty() {
        kept.push(pooled);
    } else if let Some(smallest) = kept.iter_mut().min_by(|a, b| a.1.total_cmp(&b.1)) {
        *smallest = (smallest.0 + pooled.0, smallest.1 + pooled.1);
    }
    let statistic = kept
        .iter()
        .map(|&(o, e)| {
            if e > 0.0 {
                (o - e) * (o - e) / e
            } else if o > 0.0 {
                f64::INFINITY
            } else {
                0.0
            }
        })
        .sum();
    (statistic, kept.len().saturating_sub(1).max(1))
}

#[test]
fn pooling_keeps_the_counts_and_the_expectations() {
    // Two small bins pool into one that expects enough; the statistic is the pooled bin's
    // and the others', with one degree of freedom less than the three bins kept.
    let (statistic, dof) = pearson(&[10.0, 2.0, 4.0, 12.0], &[10.0, 3.0, 3.0, 14.0]);
    assert_eq!(dof, 2);
    assert!(
        (statistic - (0.0 + 4.0 / 14.0 + 0.0)).abs() < 1e-12,
        "{statistic}"
    );
    // A lone small bin folds into the smallest kept one.
    let (statistic, dof) = pearson(&[9.0, 1.0, 20.0], &[8.0, 1.0, 21.0]);
    assert_eq!(dof, 1);
    assert!(
        (statistic - (1.0 / 9.0 + 1.0 / 21.0)).abs() < 1e-12,
        "{statistic}"
    );
}
