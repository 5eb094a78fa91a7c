//! Eye pass (docs/algorithm.md 1.1): each slot's visible point, where its eye path first meets a
//! non-specular surface, following mirror and glass chains iteratively.

use crate::chain_light::{ChainTracker, GlossyVertex};
use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::compile::camera_ray;
use ppm_core::layout::{
    ChainLight, EyePassParams, GpuCamera, HitPoint, NO_MATERIAL, SlotBounds, eye_flags, hit_flags,
};
use ppm_core::passes::EyeStats;
use ppm_core::rng::{PassKind, StreamKey, stratified_pair};
use rayon::iter::Either;
use rayon::prelude::*;

/// Writes the visible point of every slot of `hit_points` (`width * height * spp` slots,
/// slot = pixel * spp + sample), starting the slots fresh or keeping their statistics as
/// `params.flags` says; with [`eye_flags::RECORD_BOUNDS`], extends each slot's `bounds`;
/// with `chain` (a scene with glossy surfaces), writes the light its glossy bounces found.
pub fn eye_pass_main(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    hit_points: &mut [HitPoint],
    bounds: Option<&mut [SlotBounds]>,
    chain: Option<&mut [ChainLight]>,
) -> EyeStats {
    let slots = hit_points.len();
    let record = params.flags & eye_flags::RECORD_BOUNDS != 0;
    let bounds = if record { bounds } else { None };
    let (rays, visible) = hit_points
        .par_iter_mut()
        .zip(each_or_none(bounds, slots))
        .zip(each_or_none(chain, slots))
        .enumerate()
        .with_min_len(256)
        .map(|(slot, ((hp, b), c))| {
            let mut path = PathBounds::NOTHING;
            let (rays, found) = trace_eye_path(params, camera, scene, slot as u32, hp, &mut path);
            if let Some(b) = b {
                *b = extended(*b, hp, path);
            }
            if let (Some(c), Some(found)) = (c, found) {
                *c = found;
            }
            (rays, u64::from(hp.is_valid()))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    EyeStats {
        rays,
        hit_points: visible,
    }
}

/// Each element of `slice` as `Some`, or `None` `len` times.
fn each_or_none<T: Send>(
    slice: Option<&mut [T]>,
    len: usize,
) -> impl IndexedParallelIterator<Item = Option<&mut T>> {
    match slice {
        Some(slice) => Either::Left(slice.par_iter_mut().map(Some)),
        None => Either::Right((0..len).into_par_iter().map(|_| None)),
    }
}

/// A slot's bounds after an eye pass: started over where its statistics start (no direct
/// sample yet: a fresh or reset slot), left alone where it rested, else grown by `path`.
fn extended(bounds: SlotBounds, hp: &HitPoint, path: PathBounds) -> SlotBounds {
    if hp.flags & hit_flags::RESTING != 0 {
        return bounds;
    }
    let start = if hp.iterations == 0 {
        PathBounds::NOTHING
    } else {
        bounds
    };
    SlotBounds::new(
        Vec3::from(start.min).min(path.min.into()),
        Vec3::from(start.max).max(path.max.into()),
    )
}

/// The vertices of one eye path after the camera, as a box.
type PathBounds = SlotBounds;

/// Traces one slot's eye path and writes its visible point; returns the rays traced and
/// what its glossy bounces found (`None` for a slot that rests).
fn trace_eye_path(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    slot: u32,
    out: &mut HitPoint,
    vertices: &mut PathBounds,
) -> (u64, Option<ChainLight>) {
    let pixel = slot / params.spp;
    let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
    if keep && params.flags & eye_flags::FOCUS != 0 && out.iterations >= params.rest_at {
        out.flags |= hit_flags::RESTING;
        return (0, None);
    }
    // Kept slots continue their own sequence (see direct_light::sequence_start); a re-trace
    // repeats the stratum it last used.
    let start = if keep {
        out.iterations
    } else if params.flags & eye_flags::RETRACE != 0 {
        out.iterations.saturating_sub(1)
    } else {
        params.iteration
    };
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
        let sample = start * params.spp + slot % params.spp;
        stratified_pair(params.seed, PassKind::Eye, pixel, 0, sample)
    };
    let px = (pixel % camera.width) as f32 + jx;
    let py = (pixel / camera.width) as f32 + jy;
    let mut dir = camera_ray(camera, px, py);
    let mut origin = Vec3::from(camera.eye);
    let mut throughput = Vec3::ONE;
    let sample_lights = params.flags & eye_flags::SAMPLE_LIGHTS != 0;
    let mut chain = ChainTracker::new(sample_lights.then_some((key, params.ray_epsilon)));
    let end = |depth: u32, chain: &ChainTracker, stop| {
        let rays = u64::from(depth) + 1 + chain.rays();
        (rays, Some(chain.finish(scene, stop)))
    };
    for depth in 0..=params.max_depth {
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            return end(depth, &chain, None);
        };
        let tri = &scene.triangles[hit.triangle as usize];
        out.eye_met |= tri.group;
        let position = origin + dir * hit.t;
        let (material, texture) = scene.surface(&hit, position);
        let material = &material;
        *vertices = SlotBounds::new(
            Vec3::from(vertices.min).min(position),
            Vec3::from(vertices.max).max(position),
        );
        let normal = Vec3::from(tri.normal);
        let front = dir.dot(normal) < 0.0;
        let facing = if front { normal } else { -normal };
        let u_lobe = key.eye_lobe(depth);
        if let Some(weight) = bsdf::visible_point_weight(material, facing, -dir, u_lobe) {
            out.position = position.into();
            out.normal = facing.into();
            out.material = tri.material;
            // The texture's factor rides in the throughput (ppm_core::textures), and so
            // does a coat's transmittance towards the eye (ppm_core::bsdf).
            out.throughput = (throughput * texture * weight).into();
            out.flags |= hit_flags::VALID
                | if front { hit_flags::FRONT } else { 0 }
                | (tri.object << hit_flags::OBJECT_SHIFT);
            return end(depth, &chain, Some((&hit, dir)));
        }
        out.flags |= hit_flags::EYE_CHAINED;
        let at = GlossyVertex {
            position,
            frame: scene.frame(&hit, material, facing),
            front,
            wo: -dir,
            depth,
        };
        let bounce = chain.bounce(scene, material, &at, throughput, key.eye_bounce(depth));
        if bounce.weight == Vec3::ZERO {
            // A glossy direction below the surface: the path ends without a visible point.
            return end(depth, &chain, None);
        }
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = if bounce.transmitted { -facing } else { facing };
        origin = position + side * params.ray_epsilon;
    }
    end(params.max_depth, &chain, None)
}
