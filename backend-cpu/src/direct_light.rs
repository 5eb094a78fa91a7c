//! Direct light (docs/algorithm.md 1.2): every slot's direct sum grows by one iteration's
//! estimate ([`ppm_core::direct_light::slot_direct_light`]), over the slots in parallel.

use crate::trace::SceneData;
use ppm_core::direct_light::slot_direct_light;
use ppm_core::layout::{ChainLight, DirectLightParams, HitPoint};
use ppm_core::passes::DirectStats;
use rayon::prelude::*;

/// Adds one iteration's direct light to every slot's direct sum (or replaces the sum with it,
/// `params.accumulate == 0`): emission seen plus reflected light from the area lights, times
/// the eye path's throughput, zero where the slot has no visible point this iteration; plus
/// what the eye path's glossy bounces found, where `chain` holds it (a glossy scene).
pub fn direct_light_main(
    params: &DirectLightParams,
    scene: &SceneData,
    hit_points: &mut [HitPoint],
    chain: &[ChainLight],
) -> DirectStats {
    let rays = hit_points
        .par_iter_mut()
        .enumerate()
        .with_min_len(256)
        .map(|(slot, hp)| {
            let chain = chain.get(slot).unwrap_or(&ChainLight::NONE);
            slot_direct_light(params, scene, hp, chain, slot as u32)
        })
        .sum();
    DirectStats { rays }
}
