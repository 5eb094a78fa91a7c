//! The per-pass photon map (ppm_core::grid): cells sized to the radii in use, photons copied
//! into bucket order by a stable counting sort, so a gather reads them contiguously and sums
//! them in a fixed order (pairs that cancel left out). Each photon's normal is decoded once
//! here, not once per visible point that tests it.

use glam::Vec3;
use ppm_core::geometry::oct_unfold;
use ppm_core::grid::{RADIUS_BINS, bucket_count, cell_key, cell_of, cell_size, radius_bin};
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
    let histogram = hit_points
        .par_iter()
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
        );
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
    let keys: Vec<u32> = photons
        .par_iter()
        .with_min_len(4096)
        .map(|p| cell_key(cell_of(Vec3::from(p.position), params.cell_size)))
        .collect();
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
