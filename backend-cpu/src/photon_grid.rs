//! The per-pass photon map (ppm_core::grid): cells sized to the radii in use, photons copied
//! into bucket order by a stable counting sort, so a gather reads them contiguously and sums
//! them in a fixed order (pairs that cancel left out). Each photon's normal is decoded once
//! here, not once per visible point that tests it.

use glam::Vec3;
use ppm_core::geometry::oct_unfold;
use ppm_core::grid::{RADIUS_BINS, bucket_count, cell_coord, cell_key, cell_size, radius_bin};
use ppm_core::layout::{GridParams, HitPoint, Photon};
use ppm_core::update::gather::search_r2;
use rayon::prelude::*;

/// Cells are this many times as wide as [`ppm_core::grid`]'s. A gather looks each cell up once
/// for a run of neighbouring slots ([`crate::photon_search`]), so looking up fewer, fuller cells
/// pays where one slot at a time would read too many photons; past twice the width the extra
/// photons each disc tests cost more than the lookups saved (`cargo bench -p harness --bench
/// throughput` at 768x768 shows it in the gather column). The cells fix which photons a slot
/// tests, not which it finds, so sums differ from the wgpu backend's only by the order of their
/// additions.
const CELL_SCALE: f32 = 2.0;

/// The same for a pass every slot gathers within a floor disc (`r2_floor > 0`: local mode's
/// corrections). Those discs are wide and find many photons in each cell, so reading fewer
/// photons pays more than looking up fewer cells, and ppm-core's own width gathers a large
/// correction fastest (narrower cells gain nothing more).
const FLOOR_CELL_SCALE: f32 = 1.0;

/// A photon as the gather reads it: [`ppm_core::layout::GridPhoton`] with its normal decoded.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellPhoton {
    /// Where the photon landed.
    pub position: Vec3,
    /// Key of its cell.
    pub cell: u32,
    /// [`oct_unfold`] of its normal: a visible point gathers it if this dotted with the point's
    /// normal is positive (the test of [`ppm_core::geometry::oct_faces`]).
    pub facing: Vec3,
    /// Power carried.
    pub power: Vec3,
}

/// Photons filed by bucket.
#[derive(Clone, Debug, Default)]
pub struct PhotonGrid {
    /// Cell size and bucket count.
    pub params: GridParams,
    /// `bucket_start[b] .. bucket_start[b + 1]` is bucket `b`'s range in `sorted`.
    pub bucket_start: Vec<u32>,
    /// The photons in bucket order, ascending index within each bucket.
    pub sorted: Vec<CellPhoton>,
    /// Index in the pass's deposits of each photon of `sorted`.
    pub order: Vec<u32>,
    /// Each photon's pose-A partner (position, luminance; zero for none) in the order of
    /// `sorted`, where its pass paired them ([`ppm_core::update::pairing`]); empty otherwise.
    /// In bucket order, so a gather reads it alongside the photons.
    pub partners: Vec<[f32; 4]>,
}

/// What a grid files: a map's deposits, their pose-A partners where a pass paired them
/// ([`ppm_core::update::pairing`]), and the deposits it leaves out (indices; pairs that
/// cancel, which add nothing to a gather).
#[derive(Clone, Copy)]
pub struct MapContents<'a> {
    /// The deposits.
    pub photons: &'a [Photon],
    /// Each deposit's partner (position, luminance; zero for none), where a pass paired them.
    pub partners: Option<&'a [[f32; 4]]>,
    /// Deposits left out of the grid.
    pub left_out: &'a [u32],
}

/// Builds the grid over `contents` for the gather radii of `hit_points`' visible points (at
/// least `sqrt(r2_floor)`).
pub fn build_photon_grid(
    contents: MapContents,
    hit_points: &[HitPoint],
    r2_floor: f32,
) -> PhotonGrid {
    let MapContents {
        photons,
        partners,
        left_out,
    } = contents;
    let histogram = radius_histogram(hit_points, r2_floor);
    let scale = if r2_floor > 0.0 {
        FLOOR_CELL_SCALE
    } else {
        CELL_SCALE
    };
    let mut filed = vec![true; photons.len()];
    for &i in left_out {
        filed[i as usize] = false;
    }
    let count = filed.iter().filter(|f| **f).count();
    let params = GridParams {
        cell_size: cell_size(&histogram) * scale,
        bucket_count: bucket_count(count as u32),
        photon_count: count as u32,
        _pad0: 0,
    };
    let keys = cell_keys(photons, params.cell_size);
    let mask = params.bucket_count - 1;
    let filed_keys = || keys.iter().enumerate().filter(|(i, _)| filed[*i]);
    let mut bucket_start = vec![0u32; params.bucket_count as usize + 1];
    for (_, &k) in filed_keys() {
        bucket_start[(k & mask) as usize + 1] += 1;
    }
    for i in 1..bucket_start.len() {
        bucket_start[i] += bucket_start[i - 1];
    }
    let mut next = bucket_start.clone();
    let mut order = vec![0u32; count];
    for (i, &k) in filed_keys() {
        let slot = &mut next[(k & mask) as usize];
        order[*slot as usize] = i as u32;
        *slot += 1;
    }
    let sorted = order
        .par_iter()
        .with_min_len(4096)
        .map(|&i| {
            let p = &photons[i as usize];
            CellPhoton {
                position: Vec3::from(p.position),
                cell: keys[i as usize],
                facing: oct_unfold(p.normal_oct),
                power: Vec3::from(p.power),
            }
        })
        .collect();
    let partners = partners.map_or_else(Vec::new, |all| {
        order
            .par_iter()
            .with_min_len(4096)
            .map(|&i| all[i as usize])
            .collect()
    });
    PhotonGrid {
        params,
        bucket_start,
        sorted,
        order,
        partners,
    }
}

/// Slots the cell size is read from, at least: every `k`-th slot, `k` as large as still reads
/// this many (every slot where a quarter of them are not valid). The quantile of a few tens
/// of thousands of radii lands in the bin of the quantile of all of them, bar rounding at a
/// bin's edge, and reading every slot cost a tenth of the gather at 768x768 (62 MB of slots
/// for a few bytes each).
const RADIUS_SAMPLES: usize = 1 << 15;

/// Histogram of the search radii ([`radius_bin`]) of the valid slots among a fixed stride of
/// `hit_points` (every slot where the stride's sample holds too few valid ones), the same
/// whatever the threads.
fn radius_histogram(hit_points: &[HitPoint], r2_floor: f32) -> Vec<u32> {
    let histogram = |stride: usize| {
        hit_points
            .par_iter()
            .step_by(stride)
            .with_min_len(1024)
            .filter(|h| h.is_valid())
            .fold(
                || vec![0u32; RADIUS_BINS as usize],
                |mut h, hp| {
                    h[radius_bin(search_r2(hp, r2_floor)) as usize] += 1;
                    h
                },
            )
            .reduce(
                || vec![0u32; RADIUS_BINS as usize],
                |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
            )
    };
    let stride = (hit_points.len() / RADIUS_SAMPLES).max(1);
    let sample = histogram(stride);
    let valid: u32 = sample.iter().sum();
    match stride > 1 && (valid as usize) < RADIUS_SAMPLES / 4 {
        true => histogram(1),
        false => sample,
    }
}

/// Photons keyed together, one per lane.
const KEY_LANES: usize = 8;

/// Each photon's [`cell_key`], [`KEY_LANES`] photons at a time. The compiler packs a single
/// photon's three divisions into one four-lane division whose fourth lane is the word after
/// the position in memory, the photon's path index: a subnormal float, which the CPU divides
/// in microcode (keying took five times as long). Dividing the same coordinate of several
/// photons fills every lane with a coordinate (padding with zero), and gives the same
/// quotients as [`ppm_core::grid::cell_of`].
fn cell_keys(photons: &[Photon], cell: f32) -> Vec<u32> {
    let mut keys = vec![0u32; photons.len()];
    keys.par_chunks_mut(4096)
        .zip(photons.par_chunks(4096))
        .for_each(|(keys, photons)| {
            for (keys, photons) in keys.chunks_mut(KEY_LANES).zip(photons.chunks(KEY_LANES)) {
                let mut lanes = [[0.0f32; KEY_LANES]; 3];
                for (l, p) in photons.iter().enumerate() {
                    for (axis, lane) in lanes.iter_mut().enumerate() {
                        lane[l] = p.position[axis];
                    }
                }
                let coords = lanes.map(|axis| axis.map(|v| cell_coord(v, cell)));
                for (l, key) in keys.iter_mut().enumerate() {
                    *key = cell_key([coords[0][l], coords[1][l], coords[2][l]]);
                }
            }
        });
    keys
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_core::grid::cell_of;
    use ppm_core::layout::hit_flags;

    /// Keys made in lanes are ppm-core's keys of each photon's cell, for a count of photons
    /// that leaves a short last group, at coordinates of either sign, tiny ones included.
    #[test]
    fn keys_in_lanes_are_the_keys_of_cell_of() {
        let photons: Vec<Photon> = (0..1037u32)
            .map(|i| {
                let f = |k: u32| ((i * 7919 + k * 104_729) % 2001) as f32 * 0.37 - 370.0;
                let sign = if i % 2 == 0 { -1.0 } else { 1.0 };
                Photon {
                    position: [f(1), f(2), f32::from_bits(i) * sign],
                    path: i,
                    ..Photon::default()
                }
            })
            .collect();
        for cell in [0.013, 1.0, 7.5] {
            let keys = cell_keys(&photons, cell);
            assert_eq!(keys.len(), photons.len());
            for (p, key) in photons.iter().zip(&keys) {
                let expected = cell_key(cell_of(Vec3::from(p.position), cell));
                assert_eq!(*key, expected, "cell {cell}, {p:?}");
            }
        }
    }

    /// `count` slots with radii spread log-uniformly over three orders of magnitude, valid
    /// where `valid(index)` says so.
    fn slots(count: u32, valid: impl Fn(u32) -> bool) -> Vec<HitPoint> {
        (0..count)
            .map(|i| {
                let u = ((i.wrapping_mul(2_654_435_761) >> 8) as f32) / (1u32 << 24) as f32;
                let r = 1e-3 * 1e3f32.powf(u);
                HitPoint {
                    r2: r * r,
                    flags: if valid(i) { hit_flags::VALID } else { 0 },
                    ..HitPoint::empty(i)
                }
            })
            .collect()
    }

    /// Every valid slot's bin, counted one by one.
    fn every_radius(hit_points: &[HitPoint]) -> Vec<u32> {
        let mut histogram = vec![0u32; RADIUS_BINS as usize];
        for hp in hit_points.iter().filter(|hp| hp.is_valid()) {
            histogram[radius_bin(hp.r2) as usize] += 1;
        }
        histogram
    }

    /// The cell size read from a stride of many slots is the one read from all of them; where
    /// the stride finds too few valid slots, every slot is read.
    #[test]
    fn a_sample_of_the_radii_sizes_the_cells_as_all_of_them() {
        let many = slots(600_000, |i| i % 5 != 0);
        assert_eq!(
            cell_size(&radius_histogram(&many, 0.0)),
            cell_size(&every_radius(&many))
        );
        let sparse = slots(600_000, |i| i % 97 == 3);
        assert_eq!(radius_histogram(&sparse, 0.0), every_radius(&sparse));
    }
}
