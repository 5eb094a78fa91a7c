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

/// Runs the gather rule over every slot with what it found in `map`. Returns whether every
/// slot came out finite ([`SlotState::is_finite`], screened as each is stored: a sweep over
/// every slot after the pass cost about 4% of the gather at 768x768).
pub fn gather_pass_main(
    params: &GatherParams,
    materials: &[GpuMaterial],
    map: &PhotonMap,
    r2_initial: f32,
    hit_points: &mut [HitPoint],
    pending: &mut [Pending],
) -> (GatherStats, bool) {
    let apply = params.kind & gather_kind::KIND_MASK == gather_kind::REGION_APPLY;
    let squares = params.kind & gather_kind::ADD_FLUX != 0;
    let (reached, gathered, finite) = hit_points
        .par_chunks_mut(RUN)
        .zip(pending.par_chunks_mut(RUN))
        .with_min_len(32)
        .map(|(slots, pending)| {
            let found = match apply {
                true => [Found::default(); RUN],
                false => photons_in_discs(slots, |hp| gathers(hp.flags, params.kind), map, squares),
            };
            let mut stats = (0, 0, true);
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
                // Most passes leave the pending sum as it was (zero): a write of the same
                // bits would still send its line back to memory, 9 MB a pass at 768x768.
                if pending.map(f32::to_bits) != after.pending.map(f32::to_bits) {
                    *pending = after.pending;
                }
                stats.2 &= after.is_finite();
            }
            stats
        })
        .reduce(|| (0, 0, true), |a, b| (a.0 + b.0, a.1 + b.1, a.2 & b.2));
    let stats = GatherStats {
        hit_points_reached: reached,
        photons_gathered: gathered,
    };
    (stats, finite)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon_grid::{MapContents, build_photon_grid};
    use ppm_core::geometry::oct_encode;
    use ppm_core::layout::{Photon, hit_flags, material_kind};

    /// The pass screens each slot as it stores it: a slot that comes out with a field not
    /// finite is reported, and a pass that leaves every slot finite reports none.
    #[test]
    fn a_slot_left_not_finite_is_reported() {
        let photons: Vec<Photon> = (0..50)
            .map(|i| Photon {
                position: [i as f32 * 0.01, 0.0, 0.0],
                path: i,
                power: [1.0; 3],
                normal_oct: oct_encode(Vec3::Y),
            })
            .collect();
        let slots: Vec<HitPoint> = (0..40)
            .map(|i| HitPoint {
                position: [i as f32 * 0.01, 0.0, 0.0],
                normal: [0.0, 1.0, 0.0],
                throughput: [1.0; 3],
                material: 0,
                r2: 1e-3,
                flags: hit_flags::VALID,
                ..HitPoint::empty(i)
            })
            .collect();
        let contents = MapContents {
            photons: &photons,
            partners: None,
            left_out: &[],
        };
        let grid = build_photon_grid(contents, &slots, 0.0);
        let map = PhotonMap {
            grid: &grid,
            weights: None,
            r2_floor: 0.0,
        };
        let white = GpuMaterial {
            albedo: [0.5; 3],
            kind: material_kind::DIFFUSE,
            ..GpuMaterial::default()
        };
        let params = GatherParams {
            alpha: 0.7,
            emitted_increment: 1e4,
            kind: gather_kind::ORDINARY,
            region_photons: 0.0,
        };
        let gather = |mut slots: Vec<HitPoint>| {
            let mut pending = vec![[0.0; 4]; slots.len()];
            let (stats, finite) =
                gather_pass_main(&params, &[white], &map, 1e-3, &mut slots, &mut pending);
            assert!(stats.photons_gathered > 0, "{stats:?}");
            finite
        };
        assert!(gather(slots.clone()));
        let mut broken = slots;
        broken[17].tau[1] = f32::NAN;
        assert!(!gather(broken));
    }
}
