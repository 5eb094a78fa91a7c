//! Photon pass (ALGORITHM.md 1.3): photons leave the lights with the light's whole power,
//! bounce with Russian roulette, and deposit at non-specular surfaces.

use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::geometry::{oct_encode, specular_bounce, to_world};
use ppm_core::layout::{Photon, PhotonPassParams, first_hit, material_kind};
use ppm_core::passes::PhotonStats;
use ppm_core::rng::{PassKind, StreamKey};
use ppm_core::sampling::{cosine_hemisphere, sample_cdf, uniform_triangle};
use rayon::prelude::*;
use std::f32::consts::PI;

/// Random dimensions: light, point (2), direction (2), then three per bounce.
const DIM_LIGHT: u32 = 0;
const DIM_BOUNCE: u32 = 5;
const DIMS_PER_BOUNCE: u32 = 3;

/// Photons traced per parallel task: large enough to amortise scheduling, small enough to balance.
const CHUNK: u32 = 2048;

/// Traces `params.photon_count` photons; deposits come back in path order whatever the threads.
pub fn photon_pass_main(
    params: &PhotonPassParams,
    scene: &SceneData,
) -> (Vec<Photon>, PhotonStats) {
    let chunks = params.photon_count.div_ceil(CHUNK);
    let traced: Vec<(Vec<Photon>, u64)> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut deposits = Vec::new();
            let mut rays = 0;
            let end = ((c + 1) * CHUNK).min(params.photon_count);
            for local in c * CHUNK..end {
                let path = params.first_path + local;
                rays += trace_photon(params, scene, path, &mut deposits);
            }
            (deposits, rays)
        })
        .collect();
    let rays = traced.iter().map(|(_, r)| r).sum();
    let photons: Vec<Photon> = traced.into_iter().flat_map(|(d, _)| d).collect();
    let stats = PhotonStats {
        emitted: u64::from(params.photon_count),
        deposited: photons.len() as u64,
        rays,
    };
    (photons, stats)
}

/// Traces one photon path, appending its deposits; returns the ray segments traced.
fn trace_photon(
    params: &PhotonPassParams,
    scene: &SceneData,
    path: u32,
    out: &mut Vec<Photon>,
) -> u64 {
    let key = StreamKey {
        seed: params.seed,
        kind: PassKind::Photon,
        pass_index: params.pass_index,
        path,
    };
    let light = &scene.lights[sample_cdf(
        |i| scene.lights[i].cdf,
        scene.lights.len(),
        key.uniform(DIM_LIGHT),
    )];
    let (b1, b2) = uniform_triangle(key.uniform(DIM_LIGHT + 1), key.uniform(DIM_LIGHT + 2));
    let light_normal = Vec3::from(light.normal);
    let start = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
    let mut dir = to_world(
        cosine_hemisphere(key.uniform(DIM_LIGHT + 3), key.uniform(DIM_LIGHT + 4)),
        light_normal,
    );
    let mut origin = start + light_normal * params.ray_epsilon;
    // Each photon carries the light's whole power pi * A * Le, divided by its selection probability.
    let le = Vec3::from(scene.materials[light.material as usize].emission);
    let mut power = le * (PI * light.area / light.pdf * params.power_scale);
    let mut rays = 0;
    for bounce in 0..params.max_depth {
        rays += 1;
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            break;
        };
        let tri = &scene.triangles[hit.triangle as usize];
        let material = &scene.materials[tri.material as usize];
        let position = origin + dir * hit.t;
        let normal = Vec3::from(tri.normal);
        let facing = if dir.dot(normal) < 0.0 {
            normal
        } else {
            -normal
        };
        let d = DIM_BOUNCE + bounce * DIMS_PER_BOUNCE;
        match material.kind {
            material_kind::DIFFUSE => {
                if bounce > 0 || params.first_hit == first_hit::DEPOSIT {
                    out.push(Photon {
                        position: position.into(),
                        path,
                        power: power.into(),
                        normal_oct: oct_encode(facing),
                    });
                }
                let albedo = Vec3::from(material.albedo);
                let survive = albedo.max_element();
                if key.uniform(d) >= survive {
                    break;
                }
                power *= albedo / survive;
                dir = to_world(
                    cosine_hemisphere(key.uniform(d + 1), key.uniform(d + 2)),
                    facing,
                );
                origin = position + facing * params.ray_epsilon;
            }
            _ => {
                let bounce =
                    specular_bounce(material, dir, facing, facing == normal, key.uniform(d));
                power *= bounce.weight;
                dir = bounce.dir;
                let side = if bounce.transmitted { -facing } else { facing };
                origin = position + side * params.ray_epsilon;
            }
        }
    }
    rays
}
