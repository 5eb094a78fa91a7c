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
        // The first dimension is the bit-reversed index, which scrambling reverses again.
        laine_karras(index, hash(seed ^ 1)).reverse_bits(),
        owen_scramble(sobol_second(index), hash(seed ^ 2)),
    ]
}

/// [`sobol_pair_bits`] as floats in `[0, 1)` (the top 24 bits, exact in f32).
#[inline]
pub fn sobol_pair(scramble: u32, index: u32) -> (f32, f32) {
    let [x, y] = sobol_pair_bits(scramble, index);
    (to_unit(x), to_unit(y))
}

/// The second dimension of the Sobol sequence: the xor of the direction numbers
/// `v_{k+1} = v_k ^ (v_k >> 1)` (from `v_0 = 2^31`) of the index's set bits (the first
/// dimension is the bit-reversed index). Read a byte of the index at a time from
/// [`SECOND_BY_BYTE`]: a scrambled index has all 32 bits in play, and a loop over them
/// branched unpredictably on every bit (a seventh of a CPU iteration's time at 768x768).
#[inline]
fn sobol_second(index: u32) -> u32 {
    (0..4).fold(0, |out, byte| {
        out ^ SECOND_BY_BYTE[byte][(index >> (8 * byte)) as usize & 0xff]
    })
}

/// `SECOND_BY_BYTE[j][b]`: the xor of the direction numbers of the set bits of `b`, taken as
/// byte `j` of an index.
const SECOND_BY_BYTE: [[u32; 256]; 4] = {
    let mut direction = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut k = 0;
    while k < 32 {
        direction[k] = v;
        v ^= v >> 1;
        k += 1;
    }
    let mut table = [[0u32; 256]; 4];
    let mut j = 0;
    while j < 4 {
        let mut b = 0;
        while b < 256 {
            let mut out = 0;
            let mut i = 0;
            while i < 8 {
                if b & (1 << i) != 0 {
                    out ^= direction[8 * j + i];
                }
                i += 1;
            }
            table[j][b] = out;
            b += 1;
        }
        j += 1;
    }
    table
};

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
