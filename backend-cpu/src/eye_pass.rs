//! Eye pass (ALGORITHM.md 1.1): each slot's visible point, where its eye path first meets a
//! non-specular surface, following mirror and glass chains iteratively.

use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::compile::camera_ray;
use ppm_core::geometry::{Transport, specular_bounce};
use ppm_core::layout::{
    EyePassParams, GpuCamera, HitPoint, NO_MATERIAL, eye_flags, hit_flags, material_kind,
};
use ppm_core::passes::EyeStats;
use ppm_core::rng::{PassKind, StreamKey, stratified_pair};
use rayon::prelude::*;

/// Random dimension `DIM_GLASS + depth` picks glass reflection or refraction; the point in
/// the pixel is stratified over the pixel's samples (slots times iterations).
const DIM_GLASS: u32 = 2;

/// Writes the visible point of every slot of `hit_points` (`width * height * spp` slots,
/// slot = pixel * spp + sample), starting the slots fresh or keeping their statistics as
/// `params.flags` says.
pub fn eye_pass_main(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    hit_points: &mut [HitPoint],
) -> EyeStats {
    let (rays, visible) = hit_points
        .par_iter_mut()
        .enumerate()
        .with_min_len(256)
        .map(|(slot, hp)| {
            let rays = trace_eye_path(params, camera, scene, slot as u32, hp);
            (rays, u64::from(hp.is_valid()))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    EyeStats {
        rays,
        hit_points: visible,
    }
}

/// Traces one slot's eye path and writes its visible point; returns the rays traced.
fn trace_eye_path(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    slot: u32,
    out: &mut HitPoint,
) -> u64 {
    let pixel = slot / params.spp;
    let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
    if keep && params.flags & eye_flags::FOCUS != 0 && out.iterations >= params.rest_at {
        out.flags |= hit_flags::RESTING;
        return 0;
    }
    *out = if keep {
        HitPoint {
            position: [0.0; 3],
            normal: [0.0; 3],
            material: NO_MATERIAL,
            throughput: [0.0; 3],
            flags: out.flags & hit_flags::KEPT,
            ..*out
        }
    } else {
        HitPoint {
            r2: params.r2_initial,
            ..HitPoint::empty(pixel)
        }
    };
    let key = StreamKey {
        seed: params.seed,
        kind: PassKind::Eye,
        pass_index: params.iteration,
        path: slot,
    };
    let (jx, jy) = if params.spp == 1 && params.flags & eye_flags::JITTER == 0 {
        (0.5, 0.5)
    } else {
        // Kept slots continue their own sequence (see direct_light::sequence_start).
        let start = if keep {
            out.iterations
        } else {
            params.iteration
        };
        let sample = start * params.spp + slot % params.spp;
        stratified_pair(params.seed, PassKind::Eye, pixel, 0, sample)
    };
    let px = (pixel % camera.width) as f32 + jx;
    let py = (pixel / camera.width) as f32 + jy;
    let mut dir = camera_ray(camera, px, py);
    let mut origin = Vec3::from(camera.eye);
    let mut throughput = Vec3::ONE;
    for depth in 0..=params.max_depth {
        let hit = scene.closest_hit(origin, dir, f32::INFINITY);
        if scene.near_mover(origin, dir, hit.map_or(f32::INFINITY, |h| h.t)) {
            out.flags |= if depth == 0 {
                hit_flags::EYE_NEAR_MOVER
            } else {
                hit_flags::EYE_CHAIN_NEAR_MOVER
            };
        }
        let Some(hit) = hit else {
            return u64::from(depth) + 1;
        };
        let tri = &scene.triangles[hit.triangle as usize];
        if tri.moving != 0 {
            out.flags |= hit_flags::EYE_MET_MOVER;
        }
        let material = &scene.materials[tri.material as usize];
        let position = origin + dir * hit.t;
        let normal = Vec3::from(tri.normal);
        let front = dir.dot(normal) < 0.0;
        let facing = if front { normal } else { -normal };
        match material.kind {
            material_kind::DIFFUSE => {
                out.position = position.into();
                out.normal = facing.into();
                out.material = tri.material;
                out.throughput = throughput.into();
                out.flags |= hit_flags::VALID
                    | if front { hit_flags::FRONT } else { 0 }
                    | (tri.object << hit_flags::OBJECT_SHIFT);
                return u64::from(depth) + 1;
            }
            _ => {
                let u = key.uniform(DIM_GLASS + depth);
                let bounce = specular_bounce(material, dir, facing, front, u, Transport::Radiance);
                throughput *= bounce.weight;
                dir = bounce.dir;
                let side = if bounce.transmitted { -facing } else { facing };
                origin = position + side * params.ray_epsilon;
            }
        }
    }
    u64::from(params.max_depth) + 1
}
