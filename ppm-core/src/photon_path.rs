//! A photon's path (docs/algorithm.md 1.3): from its emission, bouncing with Russian roulette,
//! depositing at every surface that holds visible points (but the first where shadow rays
//! count direct light). One path, one function, for every backend's photon pass (the twin of
//! photon_pass.wgsl's path); a backend that keeps a pass's paths follows them through a
//! [`PathRecorder`].

use crate::bsdf;
use crate::emission::{EMISSION_DIMS, Emission};
use crate::geometry::{oct_encode, segment_meets_box};
use crate::layout::{GpuBounds, Photon, PhotonPassParams, first_hit, photon_flags};
use crate::rng::StreamKey;
use crate::trace::PoseQueries;
use glam::Vec3;

/// A photon's random dimensions: the emission's, then [`DIMS_PER_BOUNCE`] per bounce (the
/// lobe or roulette, and the direction's pair).
pub const DIM_BOUNCE: u32 = EMISSION_DIMS;
/// See [`DIM_BOUNCE`].
pub const DIMS_PER_BOUNCE: u32 = 3;

/// Follows what a path did, for a backend that keeps a pass's paths.
pub trait PathRecorder {
    /// The path traced a segment from `origin` along the unit `dir` to `t` (infinite where it
    /// left the scene).
    fn segment(&mut self, origin: Vec3, dir: Vec3, t: f32);
    /// The path deposited at the end of its segment `bounce`.
    fn deposit(&mut self, bounce: u32);
}

/// Traces the photon path `key` from `emission` in `pose`, as `params` asks, appending its
/// deposits to `out` (and telling `record` its segments and deposits, if there is one).
/// Where `params.flags` holds [`photon_flags::CHANGED_ONLY`] it stores only the deposits that
/// follow its first segment to cross one of `movers` (the move's boxes, both poses'). Returns
/// the segments traced and whether the path crossed a mover's box (always true where no flag
/// asks about them).
pub fn trace_photon_path<P: PoseQueries>(
    pose: &P,
    params: &PhotonPassParams,
    movers: &[GpuBounds],
    (key, emission): (&StreamKey, &Emission),
    out: &mut Vec<Photon>,
    mut record: Option<&mut dyn PathRecorder>,
) -> (u64, bool) {
    let mut dir = emission.direction;
    let mut origin = emission.origin + emission.normal * params.ray_epsilon;
    let mut power = emission.power * params.power_scale;
    let mut rays = 0;
    // Whether the path has crossed a mover's box so far; the boxes are tested only when a
    // flag needs the answer (ordinary passes start it true and skip the test).
    let tests_movers =
        params.flags & (photon_flags::CHANGED_ONLY | photon_flags::RECORD_CROSSED) != 0;
    let mut crossed = !tests_movers;
    let stores_all = params.flags & photon_flags::CHANGED_ONLY == 0;
    let near_mover = |origin: Vec3, dir: Vec3, t: f32| {
        movers
            .iter()
            .any(|b| segment_meets_box(origin, dir, t, b.min.into(), b.max.into()))
    };
    for bounce in 0..params.max_depth {
        rays += 1;
        let hit = pose.closest_hit(origin, dir, f32::INFINITY);
        let t = hit.map_or(f32::INFINITY, |h| h.t);
        crossed = crossed || near_mover(origin, dir, t);
        if let Some(r) = record.as_deref_mut() {
            r.segment(origin, dir, t);
        }
        let Some(hit) = hit else {
            break;
        };
        let tri = &pose.triangles()[hit.triangle as usize];
        let position = origin + dir * hit.t;
        let (material, _) = pose.surface(&hit, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let facing = if dir.dot(normal) < 0.0 {
            normal
        } else {
            -normal
        };
        let d = DIM_BOUNCE + bounce * DIMS_PER_BOUNCE;
        let front = facing == normal;
        if bsdf::holds_visible_points(material)
            && (stores_all || crossed)
            && (bounce > 0 || params.first_hit == first_hit::DEPOSIT)
        {
            // What reaches the base of a coated surface (ppm_core::bsdf::arrival).
            let arrived = bsdf::arrival(material, -dir.dot(facing));
            out.push(Photon {
                position: position.into(),
                path: key.path,
                power: (power * arrived).into(),
                normal_oct: oct_encode(facing),
            });
            if let Some(r) = record.as_deref_mut() {
                r.deposit(bounce);
            }
        }
        let u = (key.uniform(d), (key.uniform(d + 1), key.uniform(d + 2)));
        let frame = pose.frame(&hit, material, facing);
        let Some(scattered) = bsdf::photon_bounce(material, dir, &frame, front, u) else {
            break;
        };
        power *= scattered.weight;
        dir = scattered.dir;
        let side = if scattered.transmitted {
            -facing
        } else {
            facing
        };
        origin = position + side * params.ray_epsilon;
    }
    (rays, crossed)
}
