//! The reference's random numbers: randomised quasi-Monte Carlo, so the truth converges
//! faster than independent samples would, with its error still measurable.
//!
//! Every pair of dimensions (the point in the pixel, the point on a light, a bounce direction,
//! ...) takes its values from its own scrambled Sobol pair sequence ([`ppm_core::qmc`]). A
//! pixel's samples fall into [`BATCHES`] batches with independent scrambles: each batch is an
//! unbiased estimate on its own, and the spread of the batch means measures the error of
//! their average honestly, which the sample variance of stratified points would not (it
//! ignores the stratification and overstates the error).

use ppm_core::qmc::{hash, sobol_pair};

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
        sobol_pair(self.stream ^ pair.wrapping_mul(0x85eb_ca6b), self.index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each batch follows its own stratified sequence: the first 16 samples of one batch of
    /// one pixel fill the 4x4 cells of the square one each.
    #[test]
    fn a_batch_is_stratified_and_batches_pairs_and_pixels_differ() {
        let mut seen = [0; 16];
        for i in 0..16 {
            let (x, y) = Sampler::new(5, 9, i * BATCHES + 3).pair(4);
            seen[(y * 4.0) as usize * 4 + (x * 4.0) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1), "{seen:?}");
        let a = Sampler::new(0, 7, 0).pair(0);
        assert_ne!(a, Sampler::new(0, 7, 1).pair(0), "batches");
        assert_ne!(a, Sampler::new(0, 7, 0).pair(1), "pairs");
        assert_ne!(a, Sampler::new(0, 8, 0).pair(0), "pixels");
    }
}
