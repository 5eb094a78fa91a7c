//! The per-pass photon map: a uniform hash grid built by a stable counting sort, so that every
//! bucket lists its photons in ascending index and gathers sum them in a fixed order.

use glam::Vec3;
use ppm_core::grid::{bucket_of, cell_of, grid_params};
use ppm_core::layout::{GridParams, Photon};
use rayon::prelude::*;

/// Photons filed by bucket.
#[derive(Clone, Debug, Default)]
pub struct PhotonGrid {
    /// Cell and bucket mapping.
    pub params: GridParams,
    /// `bucket_start[b] .. bucket_start[b + 1]` is bucket `b`'s range in `order`.
    pub bucket_start: Vec<u32>,
    /// Photon indices grouped by bucket, ascending within each.
    pub order: Vec<u32>,
}

/// Builds the grid over `photons` for gather radii up to `sqrt(max_r2)`.
pub fn build_photon_grid(photons: &[Photon], max_r2: f32) -> PhotonGrid {
    let (lo, hi) = photons
        .par_iter()
        .map(|p| (Vec3::from(p.position), Vec3::from(p.position)))
        .reduce(
            || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let (lo, hi) = if photons.is_empty() {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (lo, hi)
    };
    let params = grid_params(lo, hi, max_r2, photons.len() as u32);
    let buckets: Vec<u32> = photons
        .par_iter()
        .with_min_len(4096)
        .map(|p| bucket_of(cell_of(Vec3::from(p.position), &params), &params))
        .collect();
    let mut bucket_start = vec![0u32; params.bucket_count as usize + 1];
    for &b in &buckets {
        bucket_start[b as usize + 1] += 1;
    }
    for i in 1..bucket_start.len() {
        bucket_start[i] += bucket_start[i - 1];
    }
    let mut next = bucket_start.clone();
    let mut order = vec![0u32; photons.len()];
    for (i, &b) in buckets.iter().enumerate() {
        order[next[b as usize] as usize] = i as u32;
        next[b as usize] += 1;
    }
    PhotonGrid {
        params,
        bucket_start,
        order,
    }
}

impl PhotonGrid {
    /// Photon indices in bucket `b`.
    #[inline]
    pub fn bucket(&self, b: u32) -> &[u32] {
        &self.order
            [self.bucket_start[b as usize] as usize..self.bucket_start[b as usize + 1] as usize]
    }
}
