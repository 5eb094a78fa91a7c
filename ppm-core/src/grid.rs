//! The photon map's hash grid, the same on every backend.
//!
//! Cells are cubes anchored at the world origin whose edge follows the gather radii in use: the
//! radius that [`CELL_QUANTILE`] of the visible points have at most, read from a histogram of
//! their squared radii. A disc of that radius visits at most three cells per axis, which reads
//! a third fewer photons than cells twice as wide (at most two per axis); a larger disc visits
//! more cells, and a disc that would visit more cells than there are photons scans the photons
//! instead, so no spread of radii or of deposits makes a gather blow up. The cells do not
//! depend on where the deposits lie, so a far-flung deposit starves no one.
//!
//! A cell's coordinates hash to a 32-bit key and the key to a bucket; photons are stored in
//! bucket order (ascending index within a bucket), each with its cell's key, so a gather reads
//! them contiguously and skips those of another cell that shares the bucket. Visiting cells in
//! z, y, x order and photons in bucket order fixes the order of every sum, whatever the
//! threads. A backend may scale the cells to suit its search (the CPU backend's are twice as
//! wide), or read the quantile from a sample of the visible points (the CPU backend's, from
//! 65,536 slots on): that changes the order of additions between backends, not what a disc
//! holds.
//!
//! Why this and not pbrt's grid over the visible points (each photon splatting into the
//! points around it): splatting adds into a point's sums from many photons at once, which
//! needs atomic float additions (not in baseline WebGPU) and an order fixed after the fact to
//! stay deterministic; gathering from photons stored in bucket order needs neither.

use glam::Vec3;

/// Bins of the squared-radius histogram: the top bits of a positive f32 (exponent and two
/// mantissa bits), so bins grow by a factor `2^(1/4)` in `r2`.
pub const RADIUS_BINS: u32 = 1024;
const BIN_SHIFT: u32 = 21;

/// The share of visible points whose radius is at most a cell's edge, as a fraction
/// (integers, so every backend computes the same bin).
pub const CELL_QUANTILE: (u32, u32) = (3, 4);

/// Histogram bin of a squared radius.
#[inline]
pub fn radius_bin(r2: f32) -> u32 {
    (r2.max(0.0).to_bits() >> BIN_SHIFT).min(RADIUS_BINS - 1)
}

/// Cell edge from a histogram of the visible points' squared radii ([`radius_bin`]): the
/// radius at the top of the bin holding the [`CELL_QUANTILE`] quantile. 1 when the histogram
/// is empty (no visible point: nothing gathers).
pub fn cell_size(histogram: &[u32]) -> f32 {
    let total: u64 = histogram.iter().map(|&c| u64::from(c)).sum();
    if total == 0 {
        return 1.0;
    }
    let (num, den) = (u64::from(CELL_QUANTILE.0), u64::from(CELL_QUANTILE.1));
    let target = (total * num).div_ceil(den).max(1);
    let mut cumulative = 0u64;
    let bin = histogram
        .iter()
        .position(|&c| {
            cumulative += u64::from(c);
            cumulative >= target
        })
        .unwrap_or(histogram.len() - 1) as u32;
    let r2 = f32::from_bits((bin + 1) << BIN_SHIFT).min(f32::MAX);
    let cell = r2.sqrt();
    if cell > 0.0 && cell.is_finite() {
        cell.max(f32::MIN_POSITIVE)
    } else {
        1.0
    }
}

/// Hash buckets for `photon_count` photons: two per photon (at least 1024), a power of two,
/// so that few occupied cells share a bucket and a gather reads few photons of another cell.
/// The wgpu accumulation reads every photon of a bucket, so fewer buckets cost it most (one
/// per four photons nearly doubled it); more than two per photon only lengthen the grid
/// build, which counts and scans every bucket. The CPU gather, whose cells are twice as wide,
/// does not notice either way.
pub fn bucket_count(photon_count: u32) -> u32 {
    photon_count
        .saturating_mul(2)
        .max(1024)
        .next_power_of_two()
        .min(1 << 26)
}

/// Integer cell coordinates of a point: `floor(p / cell)`, clamped into i32.
#[inline]
pub fn cell_of(p: Vec3, cell: f32) -> [i32; 3] {
    [
        cell_coord(p.x, cell),
        cell_coord(p.y, cell),
        cell_coord(p.z, cell),
    ]
}

/// One coordinate of [`cell_of`]: `floor(v / cell)`, clamped into i32.
#[inline]
pub fn cell_coord(v: f32, cell: f32) -> i32 {
    floor_i32(v / cell)
}

/// The largest f32 below 2^31.
const I32_MAX_F32: f32 = 2_147_483_520.0;

/// `floor(v)` clamped into i32 (NaN gives 0). By truncation and a correction rather than a
/// call to `floor`, which x86-64's baseline has no instruction for: the grid floors three
/// coordinates per photon and six per gather disc.
#[inline]
fn floor_i32(v: f32) -> i32 {
    let v = v.clamp(-2_147_483_648.0, I32_MAX_F32);
    let t = v as i32;
    t - i32::from(t as f32 > v)
}

/// The 32-bit key of a cell: a sum of its coordinates times large odd constants (two cells
/// share it only if their differences weigh to a multiple of 2^32, which no neighbours do),
/// mixed so that its low bits (the bucket) depend on every coordinate bit. (Teschner et al.'s
/// xor of the products does collide between neighbours.)
#[inline]
pub fn cell_key(c: [i32; 3]) -> u32 {
    crate::qmc::hash(
        (c[0] as u32)
            .wrapping_mul(73_856_093)
            .wrapping_add((c[1] as u32).wrapping_mul(19_349_663))
            .wrapping_add((c[2] as u32).wrapping_mul(83_492_791)),
    )
}

/// The cells a disc of radius `r` about `p` may touch: lowest and highest coordinates per
/// axis, inclusive.
#[inline]
pub fn cell_range(p: Vec3, r: f32, cell: f32) -> ([i32; 3], [i32; 3]) {
    (
        cell_of(p - Vec3::splat(r), cell),
        cell_of(p + Vec3::splat(r), cell),
    )
}

/// Whether visiting the cells of `range` costs more than scanning all `photon_count`
/// photons; the gather then scans them all. (f32 arithmetic, as the WGSL twin's.)
#[inline]
pub fn scan_instead(range: ([i32; 3], [i32; 3]), photon_count: u32) -> bool {
    cells_in(range) > photon_count as f32
}

/// Cells in a range (lowest and highest coordinates per axis, inclusive), in f32 so that no
/// range overflows.
#[inline]
pub fn cells_in(range: ([i32; 3], [i32; 3])) -> f32 {
    let extent = |a: usize| range.1[a] as f32 - range.0[a] as f32 + 1.0;
    extent(0) * extent(1) * extent(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The truncating floor agrees with `floor` then a clamp, across signs, integers, halves,
    /// values beyond i32 and NaN.
    #[test]
    fn floor_i32_is_floor_clamped() {
        let values = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999,
            -2.999,
            1e-30,
            -1e-30,
            8388607.5,
            -8388607.5,
            1.6777217e7,
            3e9,
            -3e9,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            f32::MIN,
        ];
        for v in values {
            let expected = v.floor().clamp(-2_147_483_648.0, I32_MAX_F32) as i32;
            assert_eq!(floor_i32(v), expected, "{v}");
        }
        assert_eq!(floor_i32(f32::NAN), 0);
    }

    fn histogram_of(r2: &[f32]) -> Vec<u32> {
        let mut h = vec![0u32; RADIUS_BINS as usize];
        for &v in r2 {
            h[radius_bin(v) as usize] += 1;
        }
        h
    }

    /// Three quarters of the points at radius 1 and the rest at 100: the cells follow the
    /// many small discs, not the few large ones, and a small disc spans at most three cells
    /// per axis.
    #[test]
    fn cells_follow_the_radii_most_points_have() {
        let mut r2 = vec![1.0f32; 750];
        r2.extend(vec![1e4f32; 250]);
        let cell = cell_size(&histogram_of(&r2));
        assert!((1.0..1.25).contains(&cell), "{cell}");
        for p in [Vec3::splat(0.3), Vec3::new(-7.9, 3.2, 1e3)] {
            let (lo, hi) = cell_range(p, 1.0, cell);
            assert!((0..3).all(|a| hi[a] - lo[a] <= 2), "{lo:?} {hi:?}");
        }
    }

    #[test]
    fn an_empty_histogram_gives_a_usable_cell() {
        assert_eq!(cell_size(&[0; RADIUS_BINS as usize]), 1.0);
        let huge = cell_size(&histogram_of(&[f32::MAX]));
        assert!(huge.is_finite() && huge > 0.0);
        let tiny = cell_size(&histogram_of(&[1e-44]));
        assert!(tiny > 0.0);
    }

    /// Points far apart or at the f32 limit get valid cells, and a disc spanning more cells
    /// than there are photons is scanned instead.
    #[test]
    fn any_spread_of_points_keeps_cells_bounded() {
        assert_eq!(cell_of(Vec3::splat(1e38), 1e-3), [i32::MAX - 127; 3]);
        assert_eq!(cell_of(Vec3::splat(-1e38), 1e-3), [i32::MIN; 3]);
        let range = cell_range(Vec3::ZERO, 1e30, 1.0);
        assert!(scan_instead(range, 1_000_000));
        assert!(!scan_instead(cell_range(Vec3::ZERO, 0.5, 1.0), 8));
    }

    #[test]
    fn neighbouring_cells_have_distinct_keys() {
        let mut keys = std::collections::HashSet::new();
        for x in -16..16 {
            for y in -16..16 {
                for z in -16..16 {
                    assert!(keys.insert(cell_key([x, y, z])), "{x} {y} {z}");
                }
            }
        }
    }
}
