//! Direct light (docs/algorithm.md 1.2) at one slot: emission seen at its visible point plus
//! light reflected from the area lights, plus what its eye path's glossy bounces found. Each
//! sample is a shadow ray to a point on a light and a ray drawn from the BSDF
//! ([`crate::bsdf`]) that may meet a light, weighted by the power heuristic: light sampling
//! alone has unbounded variance next to an emitter (a corner of the furnace's glowing walls),
//! where the BSDF's ray takes over.
//!
//! One slot, one function, for every caller: a backend's direct-light pass
//! ([`slot_direct_light`], the twin of direct_light.wgsl) and a local move's paired samples
//! ([`slot_direct`]).

use crate::bsdf;
use crate::layout::{
    ChainLight, DirectLightParams, GpuMaterial, HitPoint, NO_MATERIAL, direct_accumulate, hit_flags,
};
use crate::rng::{PassKind, StratifiedStream};
use crate::sampling::{light_pdf, power_heuristic, sample_cdf, uniform_triangle};
use crate::trace::PoseQueries;
use glam::Vec3;

/// A direct-light sample's stratified pairs: the point on the light, the cosine direction,
/// and (first number) the light's choice. Sample `s` of the slot's iteration `k` is point
/// `k * samples + s` of the slot's sequences, so a slot's samples over all its iterations are
/// stratified together, whichever iterations it sat out or started over at
/// ([`sequence_start`]). direct_light.wgsl's `PAIR_*` are the same.
pub const PAIR_LIGHT_POINT: u32 = 0;
/// See [`PAIR_LIGHT_POINT`].
pub const PAIR_DIRECTION: u32 = 1;
/// See [`PAIR_LIGHT_POINT`].
pub const PAIR_LIGHT_CHOICE: u32 = 2;

/// Rays per sample: the shadow ray and the cosine ray.
pub const RAYS_PER_SAMPLE: u32 = 2;

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

/// The direct-light pass at slot `slot`: adds one iteration's estimate ([`slot_direct`]) to
/// its direct sum, or replaces the sum with it (`params.accumulate`); a resting slot sits it
/// out. `chain` is what its eye path's glossy bounces found. Returns the rays traced.
pub fn slot_direct_light<P: PoseQueries>(
    params: &DirectLightParams,
    pose: &P,
    hp: &mut HitPoint,
    chain: &ChainLight,
    slot: u32,
) -> u64 {
    if hp.flags & hit_flags::RESTING != 0 {
        return 0;
    }
    let (estimate, rays) = slot_direct(params, pose, hp, chain, slot);
    if params.accumulate == direct_accumulate::ADD {
        hp.direct = (Vec3::from(hp.direct) + estimate).into();
        hp.iterations += 1;
    } else {
        hp.direct = estimate.into();
        hp.iterations = 1;
    }
    rays
}

/// One eye path's direct radiance towards the eye, throughput included: what its glossy
/// bounces found (`chain`) and, where it has a visible point, the light seen there; and the
/// rays traced for it. `slot` keys its random numbers.
pub fn slot_direct<P: PoseQueries>(
    params: &DirectLightParams,
    pose: &P,
    hp: &HitPoint,
    chain: &ChainLight,
    slot: u32,
) -> (Vec3, u64) {
    let found = Vec3::from(chain.radiance);
    if !hp.is_valid() {
        return (found, 0);
    }
    let material = &pose.materials()[hp.material as usize];
    let mut direct = if hp.flags & hit_flags::FRONT != 0 {
        Vec3::from(material.emission) * chain.emission_weight
    } else {
        Vec3::ZERO
    };
    let mut rays = 0;
    if params.samples > 0
        && bsdf::visible_point_f(material).max_element() > 0.0
        && !pose.lights().is_empty()
    {
        direct += estimate_reflected(params, pose, material, hp, slot);
        rays = u64::from(params.samples * RAYS_PER_SAMPLE);
    }
    (Vec3::from(hp.throughput) * direct + found, rays)
}

/// Light from the lights reflected towards the eye, `integral of f Le cos_x`: per sample,
/// light sampling (`f Le cos_x / p_light`, `p_light` the solid-angle density of a point
/// chosen by power then by area) and BSDF sampling (`weight Le` where the ray meets a light's
/// front), each weighted by the power heuristic against the other.
fn estimate_reflected<P: PoseQueries>(
    params: &DirectLightParams,
    pose: &P,
    material: &GpuMaterial,
    hp: &HitPoint,
    slot: u32,
) -> Vec3 {
    let (lights, materials) = (pose.lights(), pose.materials());
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
        let light = &lights[sample_cdf(|i| lights[i].cdf, lights.len(), choice)];
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
                && !pose.occluded(origin, w, dist - 2.0 * params.ray_epsilon)
            {
                let le = Vec3::from(materials[light.material as usize].emission);
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
        if let Some(hit) = pose.closest_hit_if_emitter(origin, w) {
            let tri = &pose.triangles()[hit.triangle as usize];
            let cos_l = -Vec3::from(tri.normal).dot(w);
            if tri.light != NO_MATERIAL && cos_l > 0.0 {
                let light = &lights[tri.light as usize];
                let le = Vec3::from(materials[light.material as usize].emission);
                let pl = light_pdf(light.pdf, light.area, hit.t * hit.t, cos_l);
                sum += scattered.weight * le * power_heuristic(scattered.pdf, pl);
            }
        }
    }
    sum / params.samples as f32
}
