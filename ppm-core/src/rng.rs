//! Counter-based random generator (docs/algorithm.md section 5).
//!
//! A number is a pure function of (seed, pass kind, pass index, path index, dimension): no state
//! is carried between draws, so any thread (or GPU invocation) can draw any number, and the
//! result never depends on scheduling. The mixer is `pcg4d` (Jarzynski and Olano, "Hash
//! Functions for GPU Rendering", JCGT 2020), applied twice; it needs only 32-bit integer
//! multiply, add, xor and shift, which WGSL has, so the WGSL twin gives identical bits.
//!
//! # How each pass keys its numbers (part of the contract)
//!
//! A backend that keys its numbers as below traces the CPU backend's paths with the same
//! seed, which the conformance suite's same-seed checks require (`examples/minimal-backend`
//! follows it line by line). `p` is the pass's parameter struct, `slot` the slot index.
//!
//! - **Eye pass** ([`PassKind::Eye`]). The point in the pixel is
//!   `stratified_pair(p.seed, Eye, pixel, 0, start * p.spp + slot % p.spp)`, where `start`
//!   is the slot's `iterations` when it keeps its statistics, `iterations - 1` for a
//!   re-trace, and `p.iteration` otherwise: a slot continues its own sequence. The pixel
//!   centre instead when `p.spp == 1` without `JITTER`. The bounce at depth `d` draws from
//!   `StreamKey { seed: p.seed, kind: Eye, pass_index: p.iteration, path: slot }`
//!   ([`StreamKey::eye_bounce`]): at glass it reflects when dimension `2 + d` is below the
//!   Fresnel reflectance, at a coated surface it takes the coat's reflection when that
//!   dimension is below its chance (`ppm_core::bsdf::specular_probability`) and stops at the
//!   base otherwise; at a rough conductor or coat dimensions `EYE_GLOSSY_DIM + 2 d` and the next
//!   draw the direction, and dimensions `EYE_LIGHT_DIM + 3 d` to `+ 2` the light sample taken
//!   there ([`StreamKey::eye_light`]).
//! - **Direct light** ([`PassKind::DirectLight`]). Sample `s` of the pass is point `start *
//!   p.samples + s` of the stream `StratifiedStream::new(p.seed, DirectLight, slot)`, with
//!   `start` the slot's `iterations` when the pass adds to its sum and `p.iteration`
//!   otherwise; pair 2 picks the light (its first number, by power), pair 0 the point on it,
//!   pair 1 the cosine-sampled direction.
//! - **Photon passes** ([`PassKind::Photon`] for ordinary and testing photons,
//!   [`PassKind::Region`] for compensation and region photons, [`PassKind::Guided`]). Path
//!   `p.first_path + i` draws from `StreamKey { seed: p.seed, kind, pass_index:
//!   p.pass_index, path }`: dimensions `0..EMISSION_DIMS` for its emission
//!   ([`crate::emission`]), then three per bounce `b` from `EMISSION_DIMS + 3 b`: the first
//!   decides Russian roulette at a diffuse surface (survive below the largest albedo
//!   channel) or reflection at glass; at a coated surface it picks the coat's reflection
//!   below its chance and otherwise, rescaled to `[0, 1)`, decides the roulette; the next two the cosine-weighted or glossy direction. A
//!   negative pass and its positive twin use the same indices, so their unchanged paths
//!   cancel; difference passes start at [`DIFFERENCE_PASS_BASE`], except a local move's
//!   one-pass correction right after an ordinary pass, which draws that pass's numbers (its
//!   paths in pose A are then the ones that pass traced).

/// Which pass draws the number: keeps the streams of different passes apart.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    /// Eye rays and their specular chains.
    Eye = 1,
    /// Shadow rays towards the lights.
    DirectLight = 2,
    /// Ordinary and testing photons.
    Photon = 3,
    /// Compensation and region photons (a negative pass and its positive twin share indices).
    Region = 4,
    /// Guided photons.
    Guided = 5,
}

/// First pass index of difference photons (ordinary photons traced in both poses of a move):
/// far above any ordinary pass count, so they share no numbers with ordinary or testing passes.
pub const DIFFERENCE_PASS_BASE: u32 = 1 << 31;

/// Pass index that keys the scrambles of stratified sequences ([`stratified_pair`]): no
/// iteration, frame or photon pass reaches it.
pub const STRATIFIED_PASS: u32 = u32::MAX;

/// Point `index` of the stratified pair sequence `pair` of the stream `(seed, kind, path)`:
/// each stream and pair has its own Owen-scrambled Sobol sequence ([`crate::qmc`]), so the
/// samples a path takes over successive iterations cover their square evenly.
#[inline]
pub fn stratified_pair(seed: u32, kind: PassKind, path: u32, pair: u32, index: u32) -> (f32, f32) {
    StratifiedStream::new(seed, kind, path).pair(pair, index)
}

/// The stratified pair sequences of one stream `(seed, kind, path)`, its key hashed once for
/// all of them: a path that takes several pairs at one index (direct light takes three) pays
/// for the key once.
#[derive(Clone, Copy, Debug)]
pub struct StratifiedStream {
    key: [u32; 4],
}

impl StratifiedStream {
    /// The stream's sequences.
    #[inline]
    pub fn new(seed: u32, kind: PassKind, path: u32) -> Self {
        Self {
            key: pcg4d([seed, kind as u32, STRATIFIED_PASS, path]),
        }
    }

    /// Point `index` of sequence `pair`: [`stratified_pair`].
    #[inline]
    pub fn pair(&self, pair: u32, index: u32) -> (f32, f32) {
        crate::qmc::sobol_pair(key_bits(self.key, pair), index)
    }
}

/// The key of one random stream: everything but the dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamKey {
    /// Run seed.
    pub seed: u32,
    /// Pass kind.
    pub kind: PassKind,
    /// Index of the pass (photon pass number, or frame for eye and direct passes).
    pub pass_index: u32,
    /// Index of the path (pixel slot or photon) within the pass.
    pub path: u32,
}

/// An eye path's first glass dimension: depth `d` picks at glass with dimension `2 + d`.
pub const EYE_GLASS_DIM: u32 = 2;

/// An eye path's first glossy dimension: depth `d` draws a glossy direction from dimensions
/// `EYE_GLOSSY_DIM + 2 d` and the next, apart from the glass numbers at any depth.
pub const EYE_GLOSSY_DIM: u32 = 1 << 16;

/// An eye path's first light-sample dimension: at a glossy bounce at depth `d`, dimension
/// `EYE_LIGHT_DIM + 3 d` picks the light and the next two the point on it
/// ([`StreamKey::eye_light`]).
pub const EYE_LIGHT_DIM: u32 = 1 << 17;

impl StreamKey {
    /// The number that picks a lobe at an eye path's bounce at `depth` (at glass, or between
    /// a coat's reflection and its base), alone: what decides whether the path stops there.
    #[inline]
    pub fn eye_lobe(&self, depth: u32) -> f32 {
        self.uniform(EYE_GLASS_DIM + depth)
    }

    /// The numbers of an eye path's bounce at `depth`: [`Self::eye_lobe`], and the pair that
    /// draws a glossy direction ([`crate::bsdf::sample`]'s `u`).
    #[inline]
    pub fn eye_bounce(&self, depth: u32) -> (f32, (f32, f32)) {
        let glossy = EYE_GLOSSY_DIM + 2 * depth;
        (
            self.eye_lobe(depth),
            (self.uniform(glossy), self.uniform(glossy + 1)),
        )
    }

    /// The numbers of the light sample at an eye path's glossy bounce at `depth`: the one
    /// that picks the light, and the pair that picks the point on it.
    #[inline]
    pub fn eye_light(&self, depth: u32) -> (f32, (f32, f32)) {
        let first = EYE_LIGHT_DIM + 3 * depth;
        (
            self.uniform(first),
            (self.uniform(first + 1), self.uniform(first + 2)),
        )
    }

    /// The 32 random bits for `dimension` of this stream.
    #[inline]
    pub fn bits(&self, dimension: u32) -> u32 {
        random_bits(
            self.seed,
            self.kind as u32,
            self.pass_index,
            self.path,
            dimension,
        )
    }

    /// A uniform float in [0, 1) for `dimension` of this stream.
    #[inline]
    pub fn uniform(&self, dimension: u32) -> f32 {
        bits_to_unit(self.bits(dimension))
    }
}

/// The `pcg4d` permutation of four 32-bit words.
#[inline]
pub fn pcg4d(mut v: [u32; 4]) -> [u32; 4] {
    for x in &mut v {
        *x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    }
    mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    mix(&mut v);
    v
}

#[inline]
fn mix(v: &mut [u32; 4]) {
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
}

/// 32 random bits for one (seed, kind, pass, path, dimension) tuple.
///
/// The first round hashes the stream key; the second folds in the dimension, so consecutive
/// dimensions of one path are as unrelated as different paths.
#[inline]
pub fn random_bits(seed: u32, kind: u32, pass_index: u32, path: u32, dimension: u32) -> u32 {
    key_bits(pcg4d([seed, kind, pass_index, path]), dimension)
}

/// The second round of [`random_bits`]: a hashed stream key and a dimension.
#[inline]
fn key_bits(key: [u32; 4], dimension: u32) -> u32 {
    pcg4d([key[0], key[1] ^ dimension, key[2], key[3]])[0]
}

/// Maps 32 random bits to a float in [0, 1): the top 24 bits, exactly representable in f32.
#[inline]
pub fn bits_to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Fixed vectors `([seed, kind, pass_index, path, dimension], bits)`: every backend's twin of
/// [`random_bits`] must reproduce these bits exactly.
pub const TEST_VECTORS: [([u32; 5], u32); 6] = [
    ([0, 0, 0, 0, 0], 0x2582_1ee0),
    ([1, 1, 0, 0, 0], 0x6a2f_940e),
    ([1, 3, 0, 0, 0], 0x275a_19df),
    ([42, 3, 7, 123_456, 5], 0x7a28_7a63),
    ([u32::MAX, 2, u32::MAX, u32::MAX, u32::MAX], 0x2081_2152),
    ([7, 1, 1, 589_823, 9], 0xe1d0_dda0),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generator_reproduces_the_fixed_vectors() {
        for (k, expected) in TEST_VECTORS {
            let got = random_bits(k[0], k[1], k[2], k[3], k[4]);
            assert_eq!(got, expected, "key {k:?}: got {got:#010x}");
        }
    }

    /// Chi-square of 100,000 draws over 64 equal bins: 99.9% of uniform samples stay below 110.
    #[test]
    fn uniform_draws_fill_equal_bins_evenly() {
        let mut bins = [0u32; 64];
        for path in 0..100_000 {
            let key = StreamKey {
                seed: 3,
                kind: PassKind::Photon,
                pass_index: 1,
                path,
            };
            bins[(key.uniform(0) * 64.0) as usize] += 1;
        }
        let expected = 100_000.0 / 64.0;
        let chi2: f64 = bins
            .iter()
            .map(|&b| (b as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 110.0, "chi2 = {chi2}");
    }

    /// Neighbouring dimensions of one path and neighbouring paths are uncorrelated.
    #[test]
    fn neighbouring_streams_are_uncorrelated() {
        let n = 50_000;
        let (mut sxy, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
        for path in 0..n {
            let key = StreamKey {
                seed: 0,
                kind: PassKind::Eye,
                pass_index: 0,
                path,
            };
            let next = StreamKey {
                path: path + 1,
                ..key
            };
            let (x, y) = (key.uniform(0) as f64, key.uniform(1) as f64);
            sxy += x * y + x * next.uniform(0) as f64;
            sx += x;
            sy += y;
        }
        let cov = sxy / (2 * n) as f64 - (sx / n as f64) * (sy / n as f64);
        assert!(cov.abs() < 2e-3, "covariance {cov}");
    }

    #[test]
    fn unit_floats_stay_below_one() {
        assert_eq!(bits_to_unit(0), 0.0);
        assert!(bits_to_unit(u32::MAX) < 1.0);
    }
}
