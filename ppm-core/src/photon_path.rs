//! A photon's path (docs/algorithm.md 1.3): from its emission, bouncing with Russian roulette,
//! depositing at every surface that holds visible points (but the first where shadow rays
//! count direct light). One path, one function, for every backend's photon pass (the twin of
//! photon_pass.wgsl's path); a backend that keeps a pass's paths follows them through a
//! [`PathRecorder`].

use crate::bsdf;
use crate::emission::{EMISSION_DIMS, Emission, PhotonSource};
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

/// The random numbers and settings that decide a pass's paths and deposits, whatever its
/// flags, gather and sign.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PathKey {
    seed: u32,
    pass_index: u32,
    photon_count: u32,
    first_path: u32,
    max_depth: u32,
    first_hit: u32,
    ray_epsilon: u32,
}

impl PathKey {
    fn of(params: &PhotonPassParams) -> Self {
        Self {
            seed: params.seed,
            pass_index: params.pass_index,
            photon_count: params.photon_count,
            first_path: params.first_path,
            max_depth: params.max_depth,
            first_hit: params.first_hit,
            ray_epsilon: params.ray_epsilon.to_bits(),
        }
    }
}

/// An ordinary pass whose paths a backend kept ([`photon_flags::KEEP_PATHS`]), and what they
/// answer: the rule every backend that keeps paths follows, whatever it keeps of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeptPass {
    key: PathKey,
    power_scale: f32,
}

impl KeptPass {
    /// Whether a pass of `params` from `source` keeps its paths: an ordinary pass that asks
    /// and stores every deposit.
    pub fn wanted(params: &PhotonPassParams, source: &PhotonSource<'_>) -> bool {
        params.flags & photon_flags::KEEP_PATHS != 0
            && params.flags
                & (photon_flags::CHANGED_ONLY
                    | photon_flags::CULL_UNCROSSED
                    | photon_flags::ADD_TO_MAP)
                == 0
            && matches!(source, PhotonSource::Lights)
    }

    /// The pass `params`, whose paths were kept.
    pub fn of(params: &PhotonPassParams) -> Self {
        Self {
            key: PathKey::of(params),
            power_scale: params.power_scale,
        }
    }

    /// The sign that turns this pass's deposits into those of a pass of `params` from
    /// `source`, when that pass is a [`photon_flags::CHANGED_ONLY`] pass of the same paths
    /// (same random numbers and settings, the power scale the same or negated) that culls
    /// nothing; `None` when the kept paths cannot answer it. The caller checks that the pose
    /// is the one they were traced in.
    pub fn answers(&self, params: &PhotonPassParams, source: &PhotonSource<'_>) -> Option<f32> {
        let same_paths = matches!(source, PhotonSource::Lights) && PathKey::of(params) == self.key;
        let changed_only = params.flags & photon_flags::CHANGED_ONLY != 0
            && params.flags & photon_flags::CULL_UNCROSSED == 0;
        if !(same_paths && changed_only) {
            return None;
        }
        match params.power_scale {
            s if s == self.power_scale => Some(1.0),
            s if s == -self.power_scale => Some(-1.0),
            _ => None,
        }
    }
}

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
