//! Gather pass (docs/algorithm.md 1.4, and 3 "Who gathers what"): each slot that gathers this
//! kind of pass sums the photons within its radius, and ppm-core's gather rule
//! ([`ppm_core::update::gather`]) folds them into its statistics.

use crate::photon_search::{Found, PhotonMap, RUN, photons_in_discs};
use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::layout::{GatherParams, GpuMaterial, HitPoint, gather_kind};
use ppm_core::passes::GatherStats;
use ppm_core::update::gather::{self, SlotState, disc_shrink, gather_rule, gathers, search_r2};
use rayon::prelude::*;

/// Region photons gathered but not yet applied, per slot: flux (times BRDF and scale) and
/// signed count, or a correction's variance ([`SlotState::pending`]).
pub type Pending = [f32; 4];

/// Runs the gather rule over every slot with what it found in `map`.
pub fn gather_pass_main(
    params: &GatherParams,
    materials: &[GpuMaterial],
    map: &PhotonMap,
    r2_initial: f32,
    hit_points: &mut [HitPoint],
    pending: &mut [Pending],
) -> GatherStats {
    let apply = params.kind & gather_kind::KIND_MASK == gather_kind::REGION_APPLY;
    let squares = params.kind & gather_kind::ADD_FLUX != 0;
    let (reached, gathered) = hit_points
        .par_chunks_mut(RUN)
        .zip(pending.par_chunks_mut(RUN))
        .with_min_len(32)
        .map(|(slots, pending)| {
            let found = match apply {
                true => [Found::default(); RUN],
                false => photons_in_discs(slots, |hp| gathers(hp.flags, params.kind), map, squares),
            };
            let mut stats = (0, 0);
            for ((hp, pending), found) in slots.iter_mut().zip(pending).zip(found) {
                // Only a gathering slot reads its BRDF (as the WGSL twin).
                let reflectance = match gathers(hp.flags, params.kind) {
                    true => {
                        stats.0 += u64::from(found.count > 0);
                        stats.1 += u64::from(found.count);
                        Vec3::from(hp.throughput)
                            * bsdf::visible_point_f(&materials[hp.material as usize])
                    }
                    false => Vec3::ZERO,
                };
                let before = SlotState::of(hp, *pending);
                let after = gather_rule(
                    params,
                    r2_initial,
                    reflectance.into(),
                    before,
                    &scaled(found, search_r2(hp, map.r2_floor), hp.r2),
                );
                after.store(hp);
                *pending = after.pending;
            }
            stats
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    GatherStats {
        hit_points_reached: reached,
        photons_gathered: gathered,
    }
}

/// What a slot found within a disc of squared radius `searched`, scaled to its own disc of
/// `r2` ([`disc_shrink`]; a slot's own disc, even of radius 0, scales nothing).
fn scaled(found: Found, searched: f32, r2: f32) -> gather::Found {
    let shrink = disc_shrink(r2, searched);
    gather::Found {
        flux: (found.flux * shrink).into(),
        count: found.count as f32,
        weight: found.weight * shrink,
        power_sq: found.power_sq * shrink * shrink,
        _pad: [0.0; 2],
    }
}
