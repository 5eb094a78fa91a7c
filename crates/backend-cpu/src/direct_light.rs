//! Direct light (ALGORITHM.md 1.2): emission seen at each hit point plus light reflected from
//! the area lights, estimated with seeded shadow rays.

use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::layout::{DirectLightParams, HitPoint, hit_flags};
use ppm_core::passes::DirectStats;
use ppm_core::rng::{PassKind, StreamKey};
use ppm_core::sampling::{sample_cdf, uniform_triangle};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// Random dimensions per shadow ray: light choice, then two for the point on it.
const DIMS_PER_SAMPLE: u32 = 3;

/// Writes `direct` of every valid hit point; idempotent, so a frame can recompute it.
pub fn direct_light_main(
    params: &DirectLightParams,
    scene: &SceneData,
    hit_points: &mut [HitPoint],
) -> DirectStats {
    let rays = hit_points
        .par_iter_mut()
        .enumerate()
        .with_min_len(256)
        .map(|(slot, hp)| {
            if !hp.is_valid() {
                return 0;
            }
            let material = &scene.materials[hp.material as usize];
            let mut direct = if hp.flags & hit_flags::FRONT != 0 {
                Vec3::from(material.emission)
            } else {
                Vec3::ZERO
            };
            let albedo = Vec3::from(material.albedo);
            if params.samples > 0 && albedo.max_element() > 0.0 && !scene.lights.is_empty() {
                let key = StreamKey {
                    seed: params.seed,
                    kind: PassKind::DirectLight,
                    pass_index: params.frame,
                    path: slot as u32,
                };
                let irradiance = estimate_irradiance(params, scene, hp, &key);
                direct += irradiance * albedo * FRAC_1_PI;
            }
            hp.direct = direct.into();
            u64::from(params.samples)
        })
        .sum();
    DirectStats { rays }
}

/// Mean of `Le * cos_x * cos_l / d^2 / pdf(y)` over the shadow rays: the irradiance from the
/// lights, with `pdf(y) = light.pdf / light.area` for a point chosen by power then by area.
fn estimate_irradiance(
    params: &DirectLightParams,
    scene: &SceneData,
    hp: &HitPoint,
    key: &StreamKey,
) -> Vec3 {
    let x = Vec3::from(hp.position);
    let n = Vec3::from(hp.normal);
    let origin = x + n * params.ray_epsilon;
    let mut sum = Vec3::ZERO;
    for s in 0..params.samples {
        let d0 = s * DIMS_PER_SAMPLE;
        let li = sample_cdf(|i| scene.lights[i].cdf, scene.lights.len(), key.uniform(d0));
        let light = &scene.lights[li];
        let (b1, b2) = uniform_triangle(key.uniform(d0 + 1), key.uniform(d0 + 2));
        let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
        let to_light = y - origin;
        let dist2 = to_light.length_squared();
        if dist2 <= 0.0 {
            continue;
        }
        let dist = dist2.sqrt();
        let w = to_light / dist;
        let cos_x = n.dot(w);
        let cos_l = -Vec3::from(light.normal).dot(w);
        if cos_x <= 0.0 || cos_l <= 0.0 {
            continue;
        }
        if scene.occluded(origin, w, dist - 2.0 * params.ray_epsilon) {
            continue;
        }
        let le = Vec3::from(scene.materials[light.material as usize].emission);
        sum += le * (cos_x * cos_l / dist2 * (light.area / light.pdf));
    }
    sum / params.samples as f32
}
