//! Gather pass (ALGORITHM.md 1.4): each hit point sums this pass's photons within its radius
//! and folds them into its statistics with the stable update of ppm-core.

use crate::photon_grid::PhotonGrid;
use glam::Vec3;
use ppm_core::geometry::oct_decode;
use ppm_core::grid::buckets_around;
use ppm_core::layout::{GatherParams, GpuMaterial, HitPoint, Photon};
use ppm_core::passes::GatherStats;
use ppm_core::update::{Statistics, ppm_update};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// Updates every valid hit point from `photons` (indexed by `grid`).
pub fn gather_pass_main(
    params: &GatherParams,
    materials: &[GpuMaterial],
    photons: &[Photon],
    grid: &PhotonGrid,
    hit_points: &mut [HitPoint],
) -> GatherStats {
    let (reached, gathered) = hit_points
        .par_iter_mut()
        .with_min_len(256)
        .map(|hp| {
            if !hp.is_valid() {
                return (0, 0);
            }
            let (m, flux) = photons_in_disc(hp, photons, grid);
            let brdf = Vec3::from(materials[hp.material as usize].albedo) * FRAC_1_PI;
            let dtau = flux * brdf;
            let s = ppm_update(
                Statistics {
                    n: hp.n,
                    r2: hp.r2,
                    tau: hp.tau,
                },
                m as f32,
                dtau.into(),
                params.alpha,
            );
            hp.n = s.n;
            hp.r2 = s.r2;
            hp.tau = s.tau;
            hp.emitted += params.emitted_increment;
            (u64::from(m > 0), u64::from(m))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    GatherStats {
        hit_points_reached: reached,
        photons_gathered: gathered,
    }
}

/// Count and summed power of the photons within `sqrt(r2)` of the hit point whose surface
/// faces the same way; summed in bucket order, then ascending photon index.
#[inline]
fn photons_in_disc(hp: &HitPoint, photons: &[Photon], grid: &PhotonGrid) -> (u32, Vec3) {
    let x = Vec3::from(hp.position);
    let n = Vec3::from(hp.normal);
    let (buckets, count) = buckets_around(x, hp.r2.sqrt(), &grid.params);
    let mut m = 0u32;
    let mut flux = Vec3::ZERO;
    for &b in &buckets[..count] {
        for &i in grid.bucket(b) {
            let p = &photons[i as usize];
            let d = Vec3::from(p.position) - x;
            if d.length_squared() < hp.r2 && oct_decode(p.normal_oct).dot(n) > 0.0 {
                m += 1;
                flux += Vec3::from(p.power);
            }
        }
    }
    (m, flux)
}
