//! The uniform hash grid that indexes one pass's photons: cell and bucket mapping shared by all
//! backends, so that every backend files every photon under the same bucket.

use crate::layout::GridParams;
use glam::Vec3;

/// Cells per axis at most: keeps cell coordinates far from integer overflow.
const MAX_CELLS_PER_AXIS: f32 = (1u32 << 20) as f32;

/// Grid covering the box `lo..hi` of the photons, for gather radii up to `sqrt(max_r2)`.
///
/// Cells are at least twice the largest radius wide, so a gather disc spans at most two cells
/// per axis; they grow further if the box would need more than 2^20 cells per axis. One bucket
/// per photon, rounded up to a power of two, keeps buckets short.
pub fn grid_params(lo: Vec3, hi: Vec3, max_r2: f32, photon_count: u32) -> GridParams {
    let extent = (hi - lo).max(Vec3::ZERO);
    let mut cell = (2.0 * max_r2.max(0.0).sqrt()).max(extent.max_element() / MAX_CELLS_PER_AXIS);
    if !(cell > 0.0 && cell.is_finite()) {
        cell = 1.0;
    }
    let dims = (extent / cell).floor() + Vec3::ONE;
    GridParams {
        origin: lo.into(),
        cell_size: cell,
        dims: [dims.x as u32, dims.y as u32, dims.z as u32],
        bucket_count: photon_count.max(1).next_power_of_two().min(1 << 26),
        photon_count,
        _pad0: 0,
        _pad1: 0,
        _pad2: 0,
    }
}

/// Cell of a point, clamped into the grid (clamping keeps the mapping monotonic per axis).
#[inline]
pub fn cell_of(p: Vec3, g: &GridParams) -> [u32; 3] {
    let rel = (p - Vec3::from(g.origin)) / g.cell_size;
    let axis = |v: f32, dim: u32| (v.floor().max(0.0) as u32).min(dim - 1);
    [
        axis(rel.x, g.dims[0]),
        axis(rel.y, g.dims[1]),
        axis(rel.z, g.dims[2]),
    ]
}

/// Bucket of a cell: the spatial hash of Teschner et al. (2003), masked to the bucket count.
#[inline]
pub fn bucket_of(cell: [u32; 3], g: &GridParams) -> u32 {
    (cell[0].wrapping_mul(73_856_093)
        ^ cell[1].wrapping_mul(19_349_663)
        ^ cell[2].wrapping_mul(83_492_791))
        & (g.bucket_count - 1)
}

/// The distinct buckets a gather disc of radius `r` about `p` must visit (at most eight).
///
/// Distinct, because two neighbouring cells may hash to one bucket: visiting it twice would
/// count its photons twice.
#[inline]
pub fn buckets_around(p: Vec3, r: f32, g: &GridParams) -> ([u32; 8], usize) {
    let lo = cell_of(p - Vec3::splat(r), g);
    let hi = cell_of(p + Vec3::splat(r), g);
    let mut out = [0u32; 8];
    let mut count = 0;
    for z in lo[2]..=hi[2].min(lo[2] + 1) {
        for y in lo[1]..=hi[1].min(lo[1] + 1) {
            for x in lo[0]..=hi[0].min(lo[0] + 1) {
                let b = bucket_of([x, y, z], g);
                if !out[..count].contains(&b) {
                    out[count] = b;
                    count += 1;
                }
            }
        }
    }
    (out, count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_spans_at_most_two_cells_per_axis() {
        let g = grid_params(Vec3::ZERO, Vec3::splat(100.0), 4.0, 1000);
        assert!(g.cell_size >= 4.0);
        for p in [
            Vec3::splat(3.9),
            Vec3::splat(50.0),
            Vec3::new(0.0, 99.9, 12.0),
        ] {
            let lo = cell_of(p - Vec3::splat(2.0), &g);
            let hi = cell_of(p + Vec3::splat(2.0), &g);
            for a in 0..3 {
                assert!(hi[a] - lo[a] <= 1);
            }
        }
    }

    #[test]
    fn huge_extent_with_tiny_radius_keeps_cells_bounded() {
        let g = grid_params(Vec3::ZERO, Vec3::splat(1e9), 1e-12, 10);
        assert!(g.dims.iter().all(|&d| d <= (1 << 20) + 1));
        assert_eq!(cell_of(Vec3::splat(2e9), &g), [g.dims[0] - 1; 3]);
    }

    #[test]
    fn buckets_around_are_distinct() {
        let mut g = grid_params(Vec3::ZERO, Vec3::splat(10.0), 1.0, 1);
        g.bucket_count = 2;
        let (b, n) = buckets_around(Vec3::splat(2.0), 1.0, &g);
        let mut v = b[..n].to_vec();
        v.dedup();
        assert_eq!(v.len(), n);
        assert!(n <= 2);
    }
}
