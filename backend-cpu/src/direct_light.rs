//! Direct light (docs/algorithm.md 1.2): emission seen at each hit point plus light reflected from
//! the area lights. Each sample is a shadow ray to a point on a light and a ray drawn from the
//! BSDF ([`ppm_core::bsdf`]) that may meet a light, weighted by the power heuristic: light
//! sampling alone has unbounded variance next to an emitter (a corner of the furnace's
//! glowing walls), where the BSDF's ray takes over.

use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::layout::{
    ChainLight, DirectLightParams, GpuMaterial, HitPoint, NO_MATERIAL, direct_accumulate, hit_flags,
};
use ppm_core::passes::DirectStats;
use ppm_core::rng::{PassKind, StratifiedStream};
use ppm_core::sampling::{light_pdf, power_heuristic, sample_cdf, uniform_triangle};
use rayon::prelude::*;

/// Stratified pairs of each sample: the point on the light, the cosine direction, and the
/// light's choice (first number). Sample `s` of the slot's iteration `k` is point
/// `k * samples + s` of the slot's sequences, so a slot's samples over all its iterations
/// are stratified together, whichever iterations it sat out or started over at ([`sequence_start`]).
const PAIR_LIGHT_POINT: u32 = 0;
const PAIR_DIRECTION: u32 = 1;
const PAIR_LIGHT_CHOICE: u32 = 2;

/// Where this pass's samples start in the slot's sequences: at the slot's own iteration count
/// when the pass adds to its sum (a slot that rested or was reset continues its own sequence
/// without gaps, which would clump its samples), at the pass's key otherwise.
pub fn sequence_start(params: &DirectLightParams, hp: &HitPoint) -> u32 {
    if params.accumulate == direct_accumulate::ADD {
        hp.iterations
    } else {
        params.iteration
    }
}

/// Emitting triangles up to which a cosine ray tests them one by one, then casts one shadow ray to the nearest, instead of finding its nearest hit in the BVH:
/// most cosine rays meet no emitter and skip the BVH (cornell-box's direct light at 768x768, two
/// runs side by side: 97 and 99 ms before, 88 and 89 after). The wgpu backend keeps the
/// closest-hit query: where SIMD lanes split between the two paths the vector runs both (its
/// direct light took 4.5 times as long on lavapipe).
const FEW_EMITTERS: usize = 16;

/// Rays per sample: the shadow ray and the cosine ray.
pub const RAYS_PER_SAMPLE: u32 = 2;

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
            if hp.flags & hit_flags::RESTING != 0 {
                return 0;
            }
            let chain = chain.get(slot).unwrap_or(&ChainLight::NONE);
            let (estimate, rays) = slot_direct(params, scene, hp, chain, slot as u32);
            if params.accumulate == direct_accumulate::ADD {
                hp.direct = (Vec3::from(hp.direct) + estimate).into();
                hp.iterations += 1;
            } else {
                hp.direct = estimate.into();
                hp.iterations = 1;
            }
            rays
        })
        .sum();
    DirectStats { rays }
}

/// One eye path's direct radiance towards the eye, throughput included: what its glossy
/// bounces found (`chain`) and, where it has a visible point, the light seen there; and the
/// rays traced for it; `slot` keys its random numbers. Local mode's direct-light correction
/// calls it on the host for eye paths of its own.
pub fn slot_direct(
    params: &DirectLightParams,
    scene: &SceneData,
    hp: &HitPoint,
    chain: &ChainLight,
    slot: u32,
) -> (Vec3, u64) {
    let found = Vec3::from(chain.radiance);
    if !hp.is_valid() {
        return (found, 0);
    }
    let material = &scene.materials[hp.material as usize];
    let mut direct = if hp.flags & hit_flags::FRONT != 0 {
        Vec3::from(material.emission) * chain.emission_weight
    } else {
        Vec3::ZERO
    };
    let mut rays = 0;
    if params.samples > 0
        && bsdf::visible_point_f(material).max_element() > 0.0
        && !scene.lights.is_empty()
    {
        direct += estimate_reflected(params, scene, material, hp, slot);
        rays = u64::from(params.samples * RAYS_PER_SAMPLE);
    }
    (Vec3::from(hp.throughput) * direct + found, rays)
}

/// Light from the lights reflected towards the eye, `integral of f Le cos_x`: per sample,
/// light sampling (`f Le cos_x / p_light`, `p_light` the solid-angle density of a point
/// chosen by power then by area) and BSDF sampling (`weight Le` where the ray meets a light's
/// front), each weighted by the power heuristic against the other.
fn estimate_reflected(
    params: &DirectLightParams,
    scene: &SceneData,
    material: &GpuMaterial,
    hp: &HitPoint,
    slot: u32,
) -> Vec3 {
    let x = Vec3::from(hp.position);
    let n = Vec3::from(hp.normal);
    let f = bsdf::visible_point_f(material);
    let origin = x + n * params.ray_epsilon;
    let mut sum = Vec3::ZERO;
    let start = sequence_start(params, hp) * params.samples;
    let stream = StratifiedStream::new(params.seed, PassKind::DirectLight, slot);
    for s in 0..params.samples {
        let index = start + s;
        let pair = |p| stream.pair(p, index);
        let (choice, _) = pair(PAIR_LIGHT_CHOICE);
        let li = sample_cdf(|i| scene.lights[i].cdf, scene.lights.len(), choice);
        let light = &scene.lights[li];
        let (u1, u2) = pair(PAIR_LIGHT_POINT);
        let (b1, b2) = uniform_triangle(u1, u2);
        let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
        let to_light = y - origin;
        let dist2 = to_light.length_squared();
        if dist2 > 0.0 {
            let dist = dist2.sqrt();
            let w = to_light / dist;
            let cos_x = n.dot(w);
            let cos_l = -Vec3::from(light.normal).dot(w);
            if cos_x > 0.0
                && cos_l > 0.0
                && !scene.occluded(origin, w, dist - 2.0 * params.ray_epsilon)
            {
                let le = Vec3::from(scene.materials[light.material as usize].emission);
                let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
                let pb = bsdf::visible_point_pdf(n, w);
                // A coat lets through a share of the light (one on a bare surface).
                let cos_through = cos_x * bsdf::arrival(material, cos_x);
                sum += f * le * (cos_through / pl * power_heuristic(pl, pb));
            }
        }
        let scattered = bsdf::sample_visible(material, n, pair(PAIR_DIRECTION));
        let w = scattered.dir;
        // Only an emitter met first adds light.
        let hit = if scene.emitters.len() <= FEW_EMITTERS {
            scene.closest_hit_if_emitter(origin, w)
        } else {
            scene.closest_hit(origin, w, f32::INFINITY)
        };
        if let Some(hit) = hit {
            let tri = &scene.triangles[hit.triangle as usize];
            let cos_l = -Vec3::from(tri.normal).dot(w);
            if tri.light != NO_MATERIAL && cos_l > 0.0 {
                let light = &scene.lights[tri.light as usize];
                let le = Vec3::from(scene.materials[light.material as usize].emission);
                let pl = light_pdf(light.pdf, light.area, hit.t * hit.t, cos_l);
                sum += scattered.weight * le * power_heuristic(scattered.pdf, pl);
            }
        }
    }
    sum / params.samples as f32
}
