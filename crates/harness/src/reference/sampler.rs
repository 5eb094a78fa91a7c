//! The reference's random numbers: randomised quasi-Monte Carlo, so the truth converges
//! faster than independent samples would, with its error still measurable.
//!
//! Every pair of dimensions (the point in the pixel, the point on a light, a bounce direction,
//! ...) takes its values from the first two dimensions of the Sobol sequence, a (0, 2)-sequence
//! whose every prefix is well stratified in 2-D, randomised by nested uniform (Owen)
//! scrambling computed with a hash (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020)
//! and with the sample order shuffled per pair, so that pairs do not correlate.
//!
//! A pixel's samples fall into [`BATCHES`] batches with independent scrambles: each batch is
//! an unbiased estimate on its own, and the spread of the batch means measures the error of
//! their average honestly, which the sample variance of scrambled points would not (it
//! ignores the stratification and overstates the error).

/// Independent randomisations per pixel.
pub const BATCHES: u32 = 8;

/// The random numbers of one sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    /// Index of the sample within its batch.
    index: u32,
    /// Hash of the seed, the pixel and the batch.
    stream: u32,
}

impl Sampler {
    /// Sample `sample` (counting all batches) of `pixel` in run `seed`.
    pub fn new(seed: u32, pixel: u32, sample: u32) -> Self {
        let batch = sample % BATCHES;
        Self {
            index: sample / BATCHES,
            stream: hash(hash(hash(seed) ^ pixel) ^ batch.wrapping_mul(0x9e37_79b9)),
        }
    }

    /// The point of dimension pair `pair` in `[0, 1)^2`.
    pub fn pair(&self, pair: u32) -> (f32, f32) {
        let seed = hash(self.stream ^ pair.wrapping_mul(0x85eb_ca6b));
        let index = owen_scramble(self.index, seed);
        let x = owen_scramble(index.reverse_bits(), hash(seed ^ 1));
        let y = owen_scramble(sobol_second(index), hash(seed ^ 2));
        (to_unit(x), to_unit(y))
    }
}

/// The second dimension of the Sobol sequence: direction numbers `v_{k+1} = v_k ^ (v_k >> 1)`
/// from `v_0 = 2^31` (the first dimension is the bit-reversed index).
fn sobol_second(mut index: u32) -> u32 {
    let (mut v, mut out) = (1u32 << 31, 0u32);
    while index != 0 {
        if index & 1 != 0 {
            out ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    out
}

/// Nested uniform scrambling of the bits of `x` (most significant first): a random
/// permutation of the binary tree of intervals, keyed by `seed`. The hash below maps each bit
/// only to bits above it, so applied to the reversed bits it flips each bit depending on the
/// bits above it alone, as Owen scrambling requires.
fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut v = x.reverse_bits();
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^= v.wrapping_mul(0x8d22_f6e6);
    v.reverse_bits()
}

/// A 32-bit integer hash with good avalanche (the "lowbias32" mixer).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// The top 24 bits as a float in `[0, 1)`.
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A (0, 2)-sequence puts exactly one of its first 2^k points in each of the 2^k
    /// elementary intervals of every shape; scrambling keeps that.
    #[test]
    fn every_elementary_interval_holds_one_point() {
        for (pixel, pair) in [(0, 0), (17, 3), (1234, 9)] {
            let points: Vec<(f32, f32)> = (0..16)
                .map(|i| Sampler::new(5, pixel, i * BATCHES).pair(pair))
                .collect();
            for (cols, rows) in [(16, 1), (8, 2), (4, 4), (2, 8), (1, 16)] {
                let mut seen = vec![0; 16];
                for (x, y) in &points {
                    let cell = (y * rows as f32) as usize * cols + (x * cols as f32) as usize;
                    seen[cell] += 1;
                }
                assert!(seen.iter().all(|&c| c == 1), "{cols}x{rows}: {seen:?}");
            }
        }
    }

    /// Scrambled points are uniform on average: the mean over many pixels of the first
    /// point is 1/2 in each coordinate.
    #[test]
    fn scrambled_points_average_to_the_centre() {
        let n = 20_000;
        let (mut sx, mut sy) = (0.0f64, 0.0f64);
        for pixel in 0..n {
            let (x, y) = Sampler::new(1, pixel, 0).pair(2);
            sx += f64::from(x);
            sy += f64::from(y);
        }
        let (mx, my) = (sx / f64::from(n), sy / f64::from(n));
        // Standard error of a uniform mean over 20,000 draws: 0.002.
        assert!(
            (mx - 0.5).abs() < 0.01 && (my - 0.5).abs() < 0.01,
            "{mx} {my}"
        );
    }

    #[test]
    fn batches_and_pairs_differ() {
        let a = Sampler::new(0, 7, 0).pair(0);
        assert_ne!(a, Sampler::new(0, 7, 1).pair(0), "batches");
        assert_ne!(a, Sampler::new(0, 7, 0).pair(1), "pairs");
        assert_ne!(a, Sampler::new(0, 8, 0).pair(0), "pixels");
    }
}
