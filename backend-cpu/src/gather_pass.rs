//! Gather pass (docs/algorithm.md 1.4, and 3 "Who gathers what"): each hit point that gathers this
//! kind of pass sums the photons within its radius and folds them into its statistics with
//! ppm-core's stable updates.

use crate::photon_search::{Found, PhotonMap, RUN, photons_in_discs};
use glam::Vec3;
use ppm_core::layout::{GatherParams, GpuMaterial, HitPoint, gather_kind, hit_flags};
use ppm_core::passes::GatherStats;
use ppm_core::update::{Statistics, compensation_update, history_kept, luminance, ppm_update};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// Whether a slot belongs to the set a pass of `kind` serves (docs/algorithm.md 3, "Who gathers
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
    let (reached, gathered) = hit_points
        .par_chunks_mut(RUN)
        .zip(pending.par_chunks_mut(RUN))
        .with_min_len(32)
        .map(|(slots, pending)| {
            let squares = params.kind & gather_kind::ADD_FLUX != 0;
            let found = photons_in_discs(slots, |hp| gathers(hp, params.kind), map, squares);
            let mut stats = (0, 0);
            for ((hp, pending), found) in slots.iter_mut().zip(pending).zip(found) {
                if !gathers(hp, params.kind) {
                    if serves(hp, params.kind) {
                        hp.emitted += params.emitted_increment;
                    }
                    continue;
                }
                update_slot(
                    params,
                    materials,
                    map.r2_floor,
                    r2_initial,
                    hp,
                    pending,
                    found,
                );
                stats.0 += u64::from(found.count > 0);
                stats.1 += u64::from(found.count);
            }
            stats
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    GatherStats {
        hit_points_reached: reached,
        photons_gathered: gathered,
    }
}

/// Folds what one gathering slot found into its statistics (or its pending sum).
fn update_slot(
    params: &GatherParams,
    materials: &[GpuMaterial],
    r2_floor: f32,
    r2_initial: f32,
    hp: &mut HitPoint,
    pending: &mut Pending,
    found: Found,
) {
    let kind = params.kind & gather_kind::KIND_MASK;
    let deferred = params.kind & gather_kind::DEFERRED != 0;
    let region = matches!(
        kind,
        gather_kind::REGION_NEGATIVE | gather_kind::REGION_POSITIVE
    );
    let Found {
        count: found,
        weight: weight_sum,
        flux,
        power_sq,
    } = found;
    // Photons found in a floor disc wider than the slot's stand for their density
    // over the slot's own disc (a slot's own disc, even of radius 0, scales nothing).
    let shrink = if r2_floor > hp.r2 {
        hp.r2 / r2_floor
    } else {
        1.0
    };
    let (weight_sum, flux) = (weight_sum * shrink, flux * shrink);
    // Region photons stand for `emitted / N_c` ordinary photons each, times their
    // path weight (docs/algorithm.md 3, "Power of region photons").
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
    let factor = Vec3::from(hp.throughput) * brdf * scale;
    let dtau: [f32; 3] = (flux * factor).into();
    if deferred {
        let sign = if kind == gather_kind::REGION_NEGATIVE {
            -1.0
        } else {
            1.0
        };
        // A flux-only correction keeps the variance of its flux where the count would go.
        let count = if params.kind & gather_kind::ADD_FLUX != 0 {
            power_sq * (luminance(factor.into()) * shrink).powi(2)
        } else {
            sign * m
        };
        *pending = [
            pending[0] + count,
            pending[1] + dtau[0],
            pending[2] + dtau[1],
            pending[3] + dtau[2],
        ];
        return;
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
}

/// Folds each hit point's pending region photons into its statistics as one update: eqs 1-3
/// when the net count grew, eqs 5-7 with their clamps when it fell; flux clamped at zero.
/// With `add`, only the flux is added (clamped at zero), and the pending count, which then
/// holds the correction's variance, weighs how much of the slot's history stays
/// ([`history_kept`]).
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
                // `m` holds the correction's variance: the slot keeps the share of its history
                // that is worth keeping against it (docs/algorithm.md 3c).
                let tau = [hp.tau[0] + t0, hp.tau[1] + t1, hp.tau[2] + t2].map(|t| t.max(0.0));
                let kept = history_kept(hp.n, tau, m);
                hp.tau = tau.map(|t| t * kept);
                hp.emitted *= kept;
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
