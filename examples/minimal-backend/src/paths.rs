//! A photon's path, keyed exactly as the contract keys it (`ppm_core::rng`): its deposits in
//! path order. The photon pass in `lib.rs` runs it photon by photon; eye paths and direct
//! light are ppm-core's own ([`ppm_core::eye_path`], [`ppm_core::direct_light`]).

use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::compile::CompiledScene;
use ppm_core::emission::{EMISSION_DIMS, Emission};
use ppm_core::geometry::oct_encode;
use ppm_core::layout::{Photon, PhotonPassParams, first_hit};
use ppm_core::rng::StreamKey;
use ppm_core::trace::{FlatPose, PoseQueries};

/// A photon's dimensions: the emission's, then three per bounce (roulette, direction).
const DIMS_PER_BOUNCE: u32 = 3;

/// Traces one photon from `emission` (docs/algorithm.md 1.3), appending a deposit at each
/// diffuse surface it meets (but the first when shadow rays count direct light), with
/// Russian roulette at each; returns the ray segments traced.
pub fn photon_path(
    params: &PhotonPassParams,
    scene: &CompiledScene,
    key: &StreamKey,
    emission: &Emission,
    out: &mut Vec<Photon>,
) -> u64 {
    let mut dir = emission.direction;
    let mut origin = emission.origin + emission.normal * params.ray_epsilon;
    let mut power = emission.power * params.power_scale;
    let mut rays = 0;
    let pose = FlatPose::new(scene);
    for bounce in 0..params.max_depth {
        rays += 1;
        let Some(hit) = pose.closest_hit(origin, dir, f32::INFINITY) else {
            break;
        };
        let tri = &scene.triangles[hit.triangle as usize];
        let position = origin + dir * hit.t;
        let (material, _) = pose.surface(&hit, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let facing = if dir.dot(normal) < 0.0 {
            normal
        } else {
            -normal
        };
        let d = EMISSION_DIMS + bounce * DIMS_PER_BOUNCE;
        if bsdf::holds_visible_points(material)
            && (bounce > 0 || params.first_hit == first_hit::DEPOSIT)
        {
            // What reaches the base of a coated surface.
            let arrived = bsdf::arrival(material, -dir.dot(facing));
            out.push(Photon {
                position: position.into(),
                path: key.path,
                power: (power * arrived).into(),
                normal_oct: oct_encode(facing),
            });
        }
        let u = (key.uniform(d), (key.uniform(d + 1), key.uniform(d + 2)));
        let frame = pose.frame(&hit, material, facing);
        let Some(b) = bsdf::photon_bounce(material, dir, &frame, facing == normal, u) else {
            break;
        };
        power *= b.weight;
        dir = b.dir;
        let side = if b.transmitted { -facing } else { facing };
        origin = position + side * params.ray_epsilon;
    }
    rays
}
