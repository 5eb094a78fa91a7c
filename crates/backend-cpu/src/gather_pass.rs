//! Gather pass (ALGORITHM.md 1.4, and 3 "Who gathers what"): each hit point that gathers this
//! kind of pass sums the photons within its radius and folds them into its statistics with
//! ppm-core's stable updates.

use crate::photon_grid::PhotonGrid;
use glam::Vec3;
use ppm_core::geometry::oct_faces;
use ppm_core::grid::{cell_key, cell_range, scan_instead};
use ppm_core::layout::{GatherParams, GpuMaterial, GridPhoton, HitPoint, gather_kind, hit_flags};
use ppm_core::passes::GatherStats;
use ppm_core::update::{Statistics, compensation_update, ppm_update};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// The current photon map: its grid, and (region passes) each deposit's weight.
pub struct PhotonMap<'a> {
    /// The deposits in bucket order.
    pub grid: &'a PhotonGrid,
    /// Path weights per deposit, when the pass kept them.
    pub weights: Option<&'a [f32]>,
    /// The pass's [`gather_r2_floor`](ppm_core::layout::PhotonPassParams::gather_r2_floor).
    pub r2_floor: f32,
}

/// Whether a slot belongs to the set a pass of `kind` serves (ALGORITHM.md 3, "Who gathers
/// what"), visible point or not: such a slot counts the pass's photons in `emitted`.
pub fn serves(hp: &HitPoint, kind: u32) -> bool {
    let updated = hp.flags & hit_flags::UPDATED != 0;
    match kind & gather_kind::KIND_MASK {
        gather_kind::REGION_NEGATIVE | gather_kind::REGION_POSITIVE => !updated,
        gather_kind::GUIDED => updated,
        _ => true,
    }
}

/// Whether a slot gathers a pass of `kind`: it is served and has a visible point.
pub fn gathers(hp: &HitPoint, kind: u32) -> bool {
    hp.is_valid() && serves(hp, kind)
}

/// Region photons gathered but not yet applied: signed count and flux (times BRDF) per hit
/// point (area mode's deferred compensation).
pub type Pending = [f32; 4];

/// Updates every slot that gathers this pass (or adds to its pending sum, or applies it).
pub fn gather_pass_main(
    params: &GatherParams,
    materials: &[GpuMaterial],
    map: &PhotonMap,
    r2_initial: f32,
    hit_points: &mut [HitPoint],
    pending: &mut [Pending],
) -> GatherStats {
    let kind = params.kind & gather_kind::KIND_MASK;
    if kind == gather_kind::REGION_APPLY {
        let add = params.kind & gather_kind::ADD_FLUX != 0;
        apply_pending(params.alpha, r2_initial, add, hit_points, pending);
        return GatherStats::default();
    }
    let deferred = params.kind & gather_kind::DEFERRED != 0;
    let region = matches!(
        kind,
        gather_kind::REGION_NEGATIVE | gather_kind::REGION_POSITIVE
    );
    let (reached, gathered) = hit_points
        .par_iter_mut()
        .zip(pending.par_iter_mut())
        .with_min_len(256)
        .map(|(hp, pending)| {
            if !gathers(hp, params.kind) {
                if serves(hp, params.kind) {
                    hp.emitted += params.emitted_increment;
                }
                return (0, 0);
            }
            let (found, weight_sum, flux) = photons_in_disc(hp, map);
            // Photons found in a floor disc wider than the slot's stand for their density
            // over the slot's own disc (a slot's own disc, even of radius 0, scales nothing).
            let shrink = if map.r2_floor > hp.r2 {
                hp.r2 / map.r2_floor
            } else {
                1.0
            };
            let (weight_sum, flux) = (weight_sum * shrink, flux * shrink);
            // Region photons stand for `emitted / N_c` ordinary photons each, times their
            // path weight (ALGORITHM.md 3, "Power of region photons").
            let scale = if region {
                hp.emitted / params.region_photons
            } else {
                1.0
            };
            let m = if region && params.kind & gather_kind::RAW_COUNT == 0 {
                weight_sum * scale
            } else {
                found as f32
            };
            let brdf = Vec3::from(materials[hp.material as usize].albedo) * FRAC_1_PI;
            let dtau: [f32; 3] = (flux * Vec3::from(hp.throughput) * brdf * scale).into();
            if deferred {
                let sign = if kind == gather_kind::REGION_NEGATIVE {
                    -1.0
                } else {
                    1.0
                };
                *pending = [
                    pending[0] + sign * m,
                    pending[1] + dtau[0],
                    pending[2] + dtau[1],
                    pending[3] + dtau[2],
                ];
                return (u64::from(found > 0), u64::from(found));
            }
            let s = Statistics {
                n: hp.n,
                r2: hp.r2,
                tau: hp.tau,
            };
            let s = if kind == gather_kind::REGION_NEGATIVE {
                compensation_update(s, m, dtau, params.alpha, r2_initial)
            } else {
                ppm_update(s, m, dtau, params.alpha)
            };
            hp.n = s.n;
            hp.r2 = s.r2;
            hp.tau = s.tau;
            hp.emitted += params.emitted_increment;
            if kind == gather_kind::REGION_NEGATIVE && m > 0.0 && s.n == 0.0 {
                // Emptied: its statistics start over, so does their normaliser; otherwise the
                // photons it gathers next would be divided by everything emitted before.
                hp.emitted = 0.0;
            }
            (u64::from(found > 0), u64::from(found))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    GatherStats {
        hit_points_reached: reached,
        photons_gathered: gathered,
    }
}

/// The squared radius a slot gathers the map's photons within: its own, or the pass's floor.
#[inline]
pub fn gather_r2(hp: &HitPoint, map: &PhotonMap) -> f32 {
    hp.r2.max(map.r2_floor)
}

/// Count, summed path weight and summed power of the photons within the gather radius of
/// the hit point whose surface faces the same way; summed in the grid's fixed order.
#[inline]
fn photons_in_disc(hp: &HitPoint, map: &PhotonMap) -> (u32, f32, Vec3) {
    let mut found = 0u32;
    let mut weight = 0.0f32;
    let mut flux = Vec3::ZERO;
    for_photons_in_disc(hp, map, |i, p| {
        found += 1;
        weight += map.weights.map_or(1.0, |w| w[i]);
        flux += Vec3::from(p.power);
    });
    (found, weight, flux)
}

/// Calls `visit(index in the pass, photon)` for each photon within the hit point's gather
/// disc, cell by cell in z, y, x order (or over all photons, when the disc spans more cells than there
/// are photons), in bucket order within a cell.
#[inline]
pub fn for_photons_in_disc(
    hp: &HitPoint,
    map: &PhotonMap,
    mut visit: impl FnMut(usize, &GridPhoton),
) {
    let x = Vec3::from(hp.position);
    let n = Vec3::from(hp.normal);
    let grid = map.grid;
    let r2 = gather_r2(hp, map);
    let mut test = |k: usize, p: &GridPhoton| {
        let d = Vec3::from(p.position) - x;
        if d.length_squared() < r2 && oct_faces(p.normal_oct, n) {
            visit(grid.order[k] as usize, p);
        }
    };
    let range = cell_range(x, r2.sqrt(), grid.params.cell_size);
    if scan_instead(range, grid.params.photon_count) {
        grid.sorted.iter().enumerate().for_each(|(k, p)| test(k, p));
        return;
    }
    let (lo, hi) = range;
    let mask = grid.params.bucket_count - 1;
    for cz in lo[2]..=hi[2] {
        for cy in lo[1]..=hi[1] {
            for cx in lo[0]..=hi[0] {
                let key = cell_key([cx, cy, cz]);
                let b = (key & mask) as usize;
                let (start, end) = (
                    grid.bucket_start[b] as usize,
                    grid.bucket_start[b + 1] as usize,
                );
                for (k, p) in grid.sorted[start..end].iter().enumerate() {
                    if p.cell == key {
                        test(start + k, p);
                    }
                }
            }
        }
    }
}

/// Folds each hit point's pending region photons into its statistics as one update: eqs 1-3
/// when the net count grew, eqs 5-7 with their clamps when it fell; flux clamped at zero.
/// With `add`, only the flux is added (clamped at zero).
fn apply_pending(
    alpha: f32,
    r2_initial: f32,
    add: bool,
    hit_points: &mut [HitPoint],
    pending: &mut [Pending],
) {
    hit_points
        .par_iter_mut()
        .zip(pending.par_iter_mut())
        .for_each(|(hp, p)| {
            let [m, t0, t1, t2] = std::mem::take(p);
            if !hp.is_valid() || (m == 0.0 && t0 == 0.0 && t1 == 0.0 && t2 == 0.0) {
                return;
            }
            if add {
                hp.tau = [hp.tau[0] + t0, hp.tau[1] + t1, hp.tau[2] + t2].map(|t| t.max(0.0));
                return;
            }
            let s = Statistics {
                n: hp.n,
                r2: hp.r2,
                tau: hp.tau,
            };
            let s = if m >= 0.0 {
                let s = ppm_update(s, m, [t0, t1, t2], alpha);
                Statistics {
                    tau: s.tau.map(|t| t.max(0.0)),
                    ..s
                }
            } else {
                compensation_update(s, -m, [t0, t1, t2], alpha, r2_initial)
            };
            if m < 0.0 && s.n == 0.0 {
                hp.emitted = 0.0;
            }
            hp.n = s.n;
            hp.r2 = s.r2;
            hp.tau = s.tau;
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon_grid::build_photon_grid;
    use ppm_core::geometry::oct_encode;
    use ppm_core::layout::{Photon, hit_flags};
    use ppm_core::rng::{PassKind, StreamKey};

    /// Photons on a plane and a perpendicular wall at `scale`, a few far away; visible points
    /// with radii spread over two orders of magnitude.
    fn case(scale: f32, far: f32) -> (Vec<Photon>, Vec<HitPoint>) {
        let u = |path: u32, d: u32| {
            StreamKey {
                seed: 9,
                kind: PassKind::Photon,
                pass_index: 0,
                path,
            }
            .uniform(d)
        };
        let mut photons: Vec<Photon> = (0..4000)
            .map(|i| {
                let (a, b) = (u(i, 0) * scale, u(i, 1) * scale);
                let (position, normal) = if i % 3 == 0 {
                    ([a, b, 0.0], Vec3::Z)
                } else {
                    ([a, 0.0, b], Vec3::Y)
                };
                Photon {
                    position,
                    path: i,
                    power: [1.0; 3],
                    normal_oct: oct_encode(normal),
                }
            })
            .collect();
        photons.push(Photon {
            position: [far, -far, far],
            normal_oct: oct_encode(Vec3::Y),
            ..Photon::default()
        });
        let hit_points = (0..300)
            .map(|i| {
                let r = scale * 0.002 * 100f32.powf(u(10_000 + i, 2));
                HitPoint {
                    position: [u(10_000 + i, 0) * scale, 0.0, u(10_000 + i, 1) * scale],
                    normal: [0.0, 1.0, 0.0],
                    r2: r * r,
                    flags: hit_flags::VALID,
                    ..HitPoint::default()
                }
            })
            .collect();
        (photons, hit_points)
    }

    /// The grid finds exactly the photons a scan of all of them finds, at any scale and with a
    /// deposit far from the rest (which must not starve the others' buckets), within each
    /// slot's radius or a pass's wider floor.
    #[test]
    fn the_grid_finds_what_a_brute_force_scan_finds() {
        let cases = [(1.0, 10.0), (1e-4, 1e-3), (1e4, 1e37), (1.0, 1e8)];
        for ((scale, far), floor) in cases.into_iter().flat_map(|c| [(c, 0.0), (c, 0.01)]) {
            let (photons, hit_points) = case(scale, far);
            let r2_floor = floor * scale * scale;
            let grid = build_photon_grid(&photons, &hit_points, r2_floor);
            let map = PhotonMap {
                grid: &grid,
                weights: None,
                r2_floor,
            };
            for hp in &hit_points {
                let mut found = Vec::new();
                for_photons_in_disc(hp, &map, |i, _| found.push(i));
                found.sort_unstable();
                let n = Vec3::from(hp.normal);
                let expected: Vec<usize> = (0..photons.len())
                    .filter(|&i| {
                        let p = &photons[i];
                        (Vec3::from(p.position) - Vec3::from(hp.position)).length_squared()
                            < hp.r2.max(r2_floor)
                            && oct_faces(p.normal_oct, n)
                    })
                    .collect();
                assert_eq!(
                    found, expected,
                    "scale {scale}, far {far}, floor {floor}, {hp:?}"
                );
            }
        }
    }
}
