//! Stratified sample sequences: the first two dimensions of the Sobol sequence, randomised by
//! nested uniform (Owen) scrambling computed with a hash (Burley, "Practical Hash-based Owen
//! Scrambling", JCGT 2020), with the order of the points shuffled the same way.
//!
//! The Sobol pair is a (0, 2)-sequence: every prefix of 2^k points puts one point in each of
//! the 2^k elementary intervals of every shape, so a pixel whose iterations take successive
//! points covers its area (or a light, or the hemisphere) evenly, and an edge or a penumbra
//! converges faster than with independent points. Scrambling keeps that and makes each point
//! uniform, so estimates stay unbiased; a different scramble key gives an independent
//! sequence. Only 32-bit integer multiplies, adds, xors, shifts and bit reversal: the WGSL
//! twin (`qmc.wgsl`) gives the same bits.

/// Point `index` of the scrambled, shuffled Sobol pair keyed by `scramble`, as 32-bit
/// fractions (the value is the bits over 2^32).
#[inline]
pub fn sobol_pair_bits(scramble: u32, index: u32) -> [u32; 2] {
    let seed = hash(scramble);
    let index = owen_scramble(index, seed);
    [
        // Both dimensions come bit-reversed, which scrambling reverses again.
        laine_karras(index, hash(seed ^ 1)).reverse_bits(),
        laine_karras(sobol_second_reversed(index), hash(seed ^ 2)).reverse_bits(),
    ]
}

/// [`sobol_pair_bits`] as floats in `[0, 1)` (the top 24 bits, exact in f32).
#[inline]
pub fn sobol_pair(scramble: u32, index: u32) -> (f32, f32) {
    let [x, y] = sobol_pair_bits(scramble, index);
    (to_unit(x), to_unit(y))
}

/// The second dimension of the Sobol sequence, bit-reversed (the first dimension is the
/// bit-reversed index). Its direction numbers `v_{k+1} = v_k ^ (v_k >> 1)` from `v_0 = 2^31`
/// are Pascal's triangle mod 2: reversed bit `i` of `v_k` is set when `C(k, i)` is odd, that is
/// (Lucas) when the bits of `i` are a subset of those of `k`. So reversed bit `i` of the point
/// is the xor of the index's bits `k` over the supersets of `i`, five shift-and-xor steps over
/// the 5-bit positions, instead of a loop over all 32 bits of a scrambled index that branched
/// unpredictably on each (a seventh of a CPU iteration's time at 768x768).
#[inline]
fn sobol_second_reversed(index: u32) -> u32 {
    let mut y = index;
    y ^= (y >> 1) & 0x5555_5555;
    y ^= (y >> 2) & 0x3333_3333;
    y ^= (y >> 4) & 0x0f0f_0f0f;
    y ^= (y >> 8) & 0x00ff_00ff;
    y ^= (y >> 16) & 0x0000_ffff;
    y
}

/// Nested uniform scrambling of the bits of `x`, most significant first: a random
/// permutation of the binary tree of intervals, keyed by `seed`. The multiply-xor steps flip
/// each bit depending only on the bits below it, so applied to the reversed bits each bit
/// flips depending on the bits above it alone, as Owen scrambling requires.
#[inline]
fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The multiply-xor steps of [`owen_scramble`], on bits already reversed.
#[inline]
fn laine_karras(mut v: u32, seed: u32) -> u32 {
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^= v.wrapping_mul(0x8d22_f6e6);
    v
}

/// A 32-bit integer hash with good avalanche (the "lowbias32" mixer): turns any key into a
/// scramble seed.
#[inline]
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

#[inline]
fn to_unit(bits: u32) -> f32 {
    crate::rng::bits_to_unit(bits)
}

/// Fixed vectors `((scramble, index), bits)`: every backend's twin of [`sobol_pair_bits`]
/// must reproduce these exactly.
pub const TEST_VECTORS: [([u32; 2], [u32; 2]); 4] = [
    ([0, 0], [0x03a7_f2f4, 0xa788_5697]),
    ([1, 1], [0xf17c_3f25, 0x6bc2_451b]),
    ([0xdead_beef, 12_345], [0xe385_094f, 0x53b8_a594]),
    ([u32::MAX, u32::MAX], [0x7c18_9429, 0x3e56_bd5f]),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sequence_reproduces_the_fixed_vectors() {
        for ([scramble, index], expected) in TEST_VECTORS {
            let got = sobol_pair_bits(scramble, index);
            assert_eq!(got, expected, "({scramble:#x}, {index}): {got:#010x?}");
        }
    }

    /// The shift-and-xor form is the sum of direction numbers that defines the dimension.
    #[test]
    fn the_second_dimension_sums_its_direction_numbers() {
        let by_definition = |index: u32| {
            let (mut v, mut out) = (1u32 << 31, 0u32);
            for k in 0..32 {
                if index >> k & 1 != 0 {
                    out ^= v;
                }
                v ^= v >> 1;
            }
            out
        };
        let spread = (0..4096u32).map(|i| i.wrapping_mul(0x9e37_79b9));
        for index in (0..4096).chain(spread).chain([u32::MAX, 1 << 31]) {
            assert_eq!(
                sobol_second_reversed(index).reverse_bits(),
                by_definition(index),
                "{index:#x}"
            );
        }
    }

    /// A (0, 2)-sequence puts exactly one of its first 2^k points in each of the 2^k
    /// elementary intervals of every shape; scrambling and shuffling keep that.
    #[test]
    fn every_elementary_interval_holds_one_point() {
        for scramble in [0u32, 17, 0x1234_5678] {
            let points: Vec<(f32, f32)> = (0..16).map(|i| sobol_pair(scramble, i)).collect();
            for (cols, rows) in [(16, 1), (8, 2), (4, 4), (2, 8), (1, 16)] {
                let mut seen = [0; 16];
                for (x, y) in &points {
                    let cell = (y * rows as f32) as usize * cols + (x * cols as f32) as usize;
                    seen[cell] += 1;
                }
                assert!(seen.iter().all(|&c| c == 1), "{cols}x{rows}: {seen:?}");
            }
        }
    }

    /// Scrambled points are uniform on average: the first point over many keys averages 1/2
    /// in each coordinate.
    #[test]
    fn scrambled_points_average_to_the_centre() {
        let n = 20_000;
        let (mut sx, mut sy) = (0.0f64, 0.0f64);
        for key in 0..n {
            let (x, y) = sobol_pair(key, 0);
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
}
