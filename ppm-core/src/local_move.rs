//! Local mode's per-slot work (docs/algorithm.md 3b and 3c), one home for every backend's
//! local-move passes ([`crate::passes::LocalMoves`]): which slots a move of some objects from
//! pose A to pose B starts over, the disc a kept slot gathers the correction within, whether
//! its direct light may change, the probe of paths past a mirror or glass, and the change of
//! a kept slot's direct light from paired samples in both poses.
//!
//! A slot starts over when what it sees may change: its eye paths met a moved object's group
//! (pose A); or the pixel lies under pose B's outline (conservative, [`crate::screen_cover`])
//! and pose B comes nearer the eye than the farthest vertex its paths reached; or its paths
//! bounced, their box meets a moved object's box in pose B, and one of [`PROBE_PATHS`] eye
//! paths traced in pose B through stratified random points of the pixel meets a moved object
//! ([`probe_meets`]). Any other slot keeps its visible points, the light it saw directly and
//! its photon statistics. Its direct light can change only through shadow or cosine rays
//! from its visible points, or light samples from its paths' glossy bounces, to a light that
//! cross a moved object's box in either pose: all start inside the slot's box, so where a
//! segment from its box to a light's box may cross one ([`direct_may_change`]), its direct sum
//! is corrected by the change over its pixel that paired eye paths and light samples estimate
//! in both poses ([`Pair`]): an unbiased estimate, exactly zero where the move blocks or
//! frees none of the rays.

use crate::direct_light::slot_direct;
use crate::eye_path::{EyePath, EyePathSettings, Watch, camera_segment, trace_eye_path};
use crate::layout::{
    DirectLightParams, GatherParams, GpuBounds, GpuCamera, GpuTriangle, HitPoint, LocalMoveParams,
    PhotonPassParams, direct_accumulate, gather_kind, hit_flags, photon_flags,
};
use crate::reach::{Aabb, segments_may_meet};
use crate::rng::{PassKind, StratifiedStream, StreamKey};
use crate::screen_cover::covered_pixels;
use crate::trace::PoseQueries;
use crate::update::{history_kept, luminance};
use glam::Vec3;

/// A local move as every pass of it sees it: what moves, where, and how its paths are
/// traced. The driver makes it ([`crate::passes::LocalMoves::begin_local_move`]); a GPU
/// backend uploads it as a few small buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMove {
    /// The moved objects' indices (their triangles' `object`).
    pub objects: Vec<u32>,
    /// The bits of their groups ([`crate::compile::object_group`]).
    pub groups: u32,
    /// Their boxes in pose A, one per object.
    pub before: Vec<Aabb>,
    /// Their boxes in pose B, one per object.
    pub after: Vec<Aabb>,
    /// The boxes direct light comes from: each light's, or one around all of them.
    pub lights: Vec<Aabb>,
    /// The render's seed: keys the probes' and the pairs' random numbers.
    pub seed: u32,
    /// How the probes' and the pairs' eye paths are traced (the pairs also sample lights at
    /// glossy bounces, as the eye pass does).
    pub paths: EyePathSettings,
    /// The squared radius a slot that starts over gets.
    pub r2_initial: f32,
    /// The correction's squared floor radius ([`correction_r2`]).
    pub r2_floor: f32,
    /// The widest a kept slot's correction disc grows far from the move, in floor radii.
    pub widest: f32,
    /// Paired direct-light samples per kept slot whose direct light may change.
    pub direct_samples: u32,
}

impl LocalMove {
    /// The moved objects' boxes in both poses.
    pub fn moved(&self) -> Vec<Aabb> {
        self.before.iter().chain(&self.after).copied().collect()
    }

    /// The distance from `eye` to the nearest moved box in pose B.
    pub fn nearest_after(&self, eye: Vec3) -> f32 {
        self.after
            .iter()
            .map(|b| b.distance_from(eye))
            .fold(f32::INFINITY, f32::min)
    }

    /// The move as a GPU backend uploads it, beside [`LocalMove::boxes`] and
    /// [`LocalMove::objects`].
    pub fn params(&self) -> LocalMoveParams {
        LocalMoveParams {
            seed: self.seed,
            groups: self.groups,
            max_depth: self.paths.max_depth,
            ray_epsilon: self.paths.ray_epsilon,
            r2_initial: self.r2_initial,
            r2_floor: self.r2_floor,
            widest: self.widest,
            direct_samples: self.direct_samples,
            objects: self.objects.len() as u32,
            lights: self.lights.len() as u32,
            ..LocalMoveParams::default()
        }
    }

    /// Its boxes in the order [`LocalMoveParams`] counts them: the moved objects' in pose A,
    /// then in pose B, then the lights'.
    pub fn boxes(&self) -> Vec<GpuBounds> {
        self.before
            .iter()
            .chain(&self.after)
            .chain(&self.lights)
            .map(|b| GpuBounds::new(b.lo, b.hi))
            .collect()
    }

    /// The probes' path settings: no light samples.
    fn probe_paths(&self) -> EyePathSettings {
        EyePathSettings {
            sample_lights: false,
            ..self.paths
        }
    }
}

/// Which pose of a local move a pass of its correction runs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pose {
    /// Before the move: its photons carry negative power and wait for pose B's.
    A,
    /// After the move: its photons carry positive power and join pose A's.
    B,
}

/// One pose's photons of a local move's correction (docs/algorithm.md 3b): the ordinary
/// photons of `pass`, traced with the same random numbers in both poses, stored only where
/// their path has crossed a moved object's box (a path that has not is the same in both poses,
/// and its deposits would cancel), with negative power in pose A and positive in pose B.
/// Pose A's wait; pose B's join them, and [`CorrectionApply`] folds both into the kept slots at
/// once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrectionPhotons {
    /// The pose.
    pub pose: Pose,
    /// The ordinary pass whose random numbers the correction draws: its seed, pass index,
    /// photon count, depth, first hit and ray offset count; its other fields are the
    /// backend's to set. When it is the ordinary pass just traced in pose A, a backend that
    /// kept that pass's paths may answer pose A from them (`photon_flags::KEEP_PATHS`).
    pub pass: PhotonPassParams,
    /// The squared radius each kept slot gathers the correction within at least, or its
    /// `correction_r2` where wider ([`crate::update::gather::search_r2`]).
    pub r2_floor: f32,
    /// Pose B pairs each deposit with pose A's of the same path and order, so that the
    /// correction's variance counts each path's net deposit ([`crate::update::pairing`]).
    pub pair_deposits: bool,
    /// Pose A notes which paths crossed a moved box, and pose B traces only those: exact, as
    /// a path that crossed none stores nothing in either pose. A backend may leave it out.
    pub cull_uncrossed: bool,
}

impl CorrectionPhotons {
    /// The photon pass that traces them where the photon pass honours local mode's flags
    /// (the CPU and wgpu backends'): [`photon_flags::CHANGED_ONLY`], pose A recording its
    /// crossings and deposits, pose B culling, pairing and adding its photons to pose A's
    /// ([`photon_flags::ADD_TO_MAP`]), for the correction's gather.
    pub fn flagged_pass(&self) -> PhotonPassParams {
        let (sign, flags) = match self.pose {
            Pose::A => (
                -1.0,
                flag(self.pair_deposits, photon_flags::RECORD_DEPOSITS)
                    | flag(self.cull_uncrossed, photon_flags::RECORD_CROSSED),
            ),
            Pose::B => (
                1.0,
                photon_flags::ADD_TO_MAP
                    | flag(self.pair_deposits, photon_flags::PAIR_DEPOSITS)
                    | flag(self.cull_uncrossed, photon_flags::CULL_UNCROSSED),
            ),
        };
        PhotonPassParams {
            power_scale: sign,
            flags: photon_flags::CHANGED_ONLY | flags,
            mask_offset: 0,
            gather_kind: CORRECTION_GATHER,
            gather_r2_floor: self.r2_floor,
            ..self.pass
        }
    }
}

/// `bit` where `on`.
fn flag(on: bool, bit: u32) -> u32 {
    if on { bit } else { 0 }
}

/// The gather kind of a correction's photons: kept slots fold them into their pending sums,
/// flux only.
pub const CORRECTION_GATHER: u32 =
    gather_kind::REGION_POSITIVE | gather_kind::DEFERRED | gather_kind::ADD_FLUX;

/// What folds a local move's correction into the kept slots, once both poses' photons are
/// traced ([`CorrectionPhotons`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrectionApply {
    /// The render's `alpha`.
    pub alpha: f32,
    /// Photons of each pose's pass: each stands for the ordinary photons a slot counted over
    /// that many.
    pub photons: u32,
}

impl CorrectionApply {
    /// The gathers that fold the correction in where the gather pass honours local mode's
    /// kinds: the photons of both poses into the pending sums ([`CORRECTION_GATHER`]), then the
    /// sums into the flux, the history weighed against their variance
    /// ([`gather_kind::REGION_APPLY`] with [`gather_kind::ADD_FLUX`]).
    pub fn gathers(&self) -> [GatherParams; 2] {
        let gather = |kind| GatherParams {
            alpha: self.alpha,
            emitted_increment: 0.0,
            kind,
            region_photons: self.photons as f32,
        };
        [
            gather(CORRECTION_GATHER),
            gather(gather_kind::REGION_APPLY | gather_kind::ADD_FLUX),
        ]
    }
}

/// How a kept slot's correction disc widens with the distance `d` from its visible point to
/// the nearest moved box: to `CORRECTION_SPREAD * d`. The change a move makes to the indirect
/// light varies over about that distance, so such a disc blurs little of it and gathers more
/// of the correction's photons, whose noise the slot would otherwise keep (docs/algorithm.md
/// 3b).
pub const CORRECTION_SPREAD: f32 = 0.3;

/// The squared radius of a kept slot's correction disc (`HitPoint::correction_r2`) whose
/// visible point is at `position`: the floor's, widened to [`CORRECTION_SPREAD`] times the
/// distance to the nearest of the `moved` boxes, at most `widest` floors.
pub fn correction_r2(position: Vec3, moved: &[Aabb], r2_floor: f32, widest: f32) -> f32 {
    let floor = r2_floor.sqrt();
    let nearest = moved
        .iter()
        .map(|b| b.distance_from(position))
        .fold(f32::INFINITY, f32::min);
    let r = (CORRECTION_SPREAD * nearest).clamp(floor, widest * floor);
    r * r
}

/// Whether a ray from a point of `from` to a light may cross one of the `moved` boxes: a
/// light sample's shadow ray, or a BSDF sample's ray that reaches a light (docs/algorithm.md
/// 3c).
pub fn direct_may_change(from: &Aabb, lights: &[Aabb], moved: &[Aabb]) -> bool {
    lights
        .iter()
        .any(|l| moved.iter().any(|m| segments_may_meet(from, l, m)))
}

/// The first half of a local move at one slot, in pose A: the disc it gathers the correction
/// within ([`correction_r2`]), `DIRECT_MAY_CHANGE` where its direct light may change, and the
/// flags of the last move and of resting cleared. `bounds` is the box of its paths' vertices.
pub fn prepare_slot(hp: &mut HitPoint, bounds: &Aabb, request: &LocalMove, moved: &[Aabb]) {
    hp.flags &= !(hit_flags::UPDATED | hit_flags::RESTING | hit_flags::DIRECT_MAY_CHANGE);
    hp.correction_r2 = correction_r2(hp.position.into(), moved, request.r2_floor, request.widest);
    if direct_may_change(bounds, &request.lights, moved) {
        hp.flags |= hit_flags::DIRECT_MAY_CHANGE;
    }
}

/// What a move may do to what a slot sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// It may change: the slot starts over.
    Changes,
    /// Only a probe of the pixel's paths in pose B can tell ([`probe_meets`]).
    Probe,
    /// It cannot change.
    Kept,
}

/// What the move `request` may do to what slot `hp` sees, from its records: the groups its
/// eye paths met, whether they bounced, and `bounds`, the box of their vertices; `covered`:
/// whether pose B's outline covers its pixel; `(eye, nearest)`: the camera's position and its
/// distance to the nearest moved box in pose B ([`LocalMove::nearest_after`]).
pub fn view_test(
    hp: &HitPoint,
    bounds: &Aabb,
    covered: bool,
    (eye, nearest): (Vec3, f32),
    request: &LocalMove,
) -> View {
    if hp.eye_met & request.groups != 0
        || covered && (bounds.is_empty() || nearest < bounds.farthest_from(eye))
    {
        return View::Changes;
    }
    if hp.flags & hit_flags::EYE_CHAINED != 0 && request.after.iter().any(|b| b.overlaps(bounds)) {
        return View::Probe;
    }
    View::Kept
}

/// A slot the move starts over: no visible point, no statistics, `r2` its initial value,
/// flagged `UPDATED` so that the correction leaves it out and the focus serves it.
pub fn reset_slot(hp: &mut HitPoint, r2_initial: f32) {
    *hp = HitPoint {
        r2: r2_initial,
        flags: hit_flags::UPDATED,
        ..HitPoint::empty(hp.pixel)
    };
}

/// The resets of a local move at one slot, in pose B (`pose`, `camera`): the slot starts over
/// ([`reset_slot`]) where the move may change what it sees ([`view_test`], with `covered`
/// from [`moved_cover`], and the [`probe_meets`] of its pixel where only a probe can tell).
/// Returns the view it was found in, and whether it started over.
pub fn reset_if_seen<P: PoseQueries>(
    hp: &mut HitPoint,
    bounds: &Aabb,
    covered: bool,
    (pose, camera, nearest): (&P, &GpuCamera, f32),
    request: &LocalMove,
) -> (View, bool) {
    let view = view_test(hp, bounds, covered, (camera.eye.into(), nearest), request);
    let changes = match view {
        View::Changes => true,
        View::Probe => probe_meets(pose, camera, hp.pixel, request),
        View::Kept => false,
    };
    if changes {
        reset_slot(hp, request.r2_initial);
    }
    (view, changes)
}

/// Per pixel (row-major), whether pose B's outline of the moved `objects` may cover it
/// ([`covered_pixels`]): their triangles in `pose`, found by their object.
pub fn moved_cover<P: PoseQueries>(pose: &P, camera: &GpuCamera, objects: &[u32]) -> Vec<bool> {
    covered_pixels(camera, &moved_triangles(pose.triangles(), objects))
}

/// The vertices of the `triangles` of the moved `objects`.
pub fn moved_triangles(triangles: &[GpuTriangle], objects: &[u32]) -> Vec<[Vec3; 3]> {
    triangles
        .iter()
        .filter(|t| objects.contains(&t.object))
        .map(|t| {
            let v0 = Vec3::from(t.v0);
            [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)]
        })
        .collect()
}

/// The direct-light change of a local move at slot `slot` (its pixel `hp.pixel`), in pose B:
/// where the slot is kept, flagged `DIRECT_MAY_CHANGE` and holds a direct sum, its
/// `request.direct_samples` pairs are traced in both poses ([`Pair::difference`], `known`
/// holding them in pose A if the last move left them) and the sum corrected
/// ([`apply_direct_change`]). Returns the pairs in pose B, `None` for a slot left alone.
pub fn correct_direct<A: PoseQueries, B: PoseQueries>(
    hp: &mut HitPoint,
    slot: u32,
    (before, after, camera): (&A, &B, &GpuCamera),
    (request, moved): (&LocalMove, &[Aabb]),
    known: Option<&[PairInPose]>,
) -> Option<Box<[PairInPose]>> {
    if hp.flags & hit_flags::DIRECT_MAY_CHANGE == 0 || hp.iterations == 0 {
        return None;
    }
    let (diffs, pairs): (Vec<Vec3>, Vec<PairInPose>) = (0..request.direct_samples)
        .map(|k| {
            let pair = Pair::new(slot, hp.pixel, k, request);
            let known = known.and_then(|p| p.get(k as usize));
            pair.difference((before, after, camera), (&request.lights, moved), known)
        })
        .unzip();
    apply_direct_change(hp, &change_of(&diffs));
    Some(pairs.into_boxed_slice())
}

/// Eye paths per pixel the probe traces, through stratified random points of it (an
/// Owen-scrambled Sobol sequence per pixel): an object that covers an eighth of what a pixel
/// sees through a mirror would be missed by independent points with probability
/// (7/8)^32 = 1.4%, a sixteenth with 13%, and stratified points spread further. A pixel kept
/// that way holds a sliver of stale light, which its later iterations dilute.
pub const PROBE_PATHS: u32 = 32;

/// Keys the probe's random numbers apart from every iteration's.
pub const PROBE_SEED: u32 = 0x9b0b_e5ed;

/// Whether one of [`PROBE_PATHS`] eye paths through random points of `pixel`, traced in
/// `pose` (pose B), meets one of the moved objects' groups at any surface up to and
/// including the first that holds a visible point.
pub fn probe_meets<P: PoseQueries>(
    pose: &P,
    camera: &GpuCamera,
    pixel: u32,
    request: &LocalMove,
) -> bool {
    let seed = request.seed ^ PROBE_SEED;
    let points = StratifiedStream::new(seed, PassKind::Eye, pixel);
    let watch = Watch {
        groups: request.groups,
        boxes: &[],
    };
    let settings = request.probe_paths();
    (0..PROBE_PATHS).any(|path| {
        let key = StreamKey {
            seed,
            kind: PassKind::Eye,
            pass_index: path,
            path: pixel,
        };
        let jitter = points.pair(0, path);
        trace_eye_path(pose, camera, (pixel, jitter), &key, &settings, &watch).watched
    })
}

/// The most paired samples a slot gets: eye paths through stratified points of its pixel,
/// one light sample each.
pub const MOST_SAMPLES: u32 = 16;

/// Paired samples per slot for a correction of `share` passes' worth of photons
/// (`MoveParams::correction_for`): 4 per pass, from 4 to [`MOST_SAMPLES`]. A long history is
/// worth a well-known change, and 16 samples are a small part of a large move; a drag step's
/// short one is not, and 16 samples would make each step half as dear again
/// (docs/algorithm.md 3b).
pub fn direct_samples_for(share: f32) -> u32 {
    (4.0 * share).round().clamp(4.0, MOST_SAMPLES as f32) as u32
}

/// Keys the correction's random numbers apart from every iteration's.
pub const CHANGE_SEED: u32 = 0x5eed_c0de;

/// A slot's estimated change of its mean direct radiance (per iteration, throughput
/// included).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectChange {
    /// The mean change over the paired samples.
    pub mean: [f32; 3],
    /// The variance of that mean's luminance, at least `lum(mean)^2 / k` for `k` samples: as
    /// uncertain as an all-or-nothing change seen by that many, so that pairs that happen to
    /// agree do not pass for an exact change.
    pub variance: f32,
}

/// The mean of paired differences and its variance (see [`DirectChange::variance`]).
pub fn change_of(diffs: &[Vec3]) -> DirectChange {
    let k = diffs.len() as f32;
    let mean = diffs.iter().sum::<Vec3>() / k;
    let lum = |v: Vec3| luminance(v.into());
    let spread = diffs
        .iter()
        .map(|d| (lum(*d) - lum(mean)).powi(2))
        .sum::<f32>();
    let sample_variance = spread / (k * (k - 1.0)).max(1.0);
    DirectChange {
        mean: mean.into(),
        variance: sample_variance.max(lum(mean).powi(2) / k),
    }
}

/// Corrects a kept slot's direct sum by `change`, weighed against its history
/// (docs/algorithm.md 3c): against the slot's corrected mean `D` over `N` iterations
/// (relative noise about `1 / N`), a change known to a variance `V` leaves the history worth
/// `N' = N / (1 + N V / lum(D)^2)` iterations ([`history_kept`]), and the sum keeps its mean at
/// that count. A change of nothing keeps the sum bit for bit; channels the change drives below
/// zero are clamped there.
pub fn apply_direct_change(hp: &mut HitPoint, change: &DirectChange) {
    if change.mean == [0.0; 3] || hp.iterations == 0 {
        return;
    }
    let n = hp.iterations as f32;
    let mean: [f32; 3] = std::array::from_fn(|c| (hp.direct[c] / n + change.mean[c]).max(0.0));
    let kept = history_kept(n, mean, change.variance);
    let count = ((n * kept).round() as u32).clamp(1, hp.iterations);
    hp.direct = mean.map(|d| d * count as f32);
    hp.iterations = count;
}

/// A pair's eye path in the pose it was traced in, and its direct light there if it was
/// evaluated: what the next move's pose A reuses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairInPose {
    /// The eye path.
    pub path: EyePath,
    /// Its direct light, where it was evaluated.
    pub light: Option<Vec3>,
}

/// One paired sample of a slot: an eye path through a point of its pixel and a light sample
/// where it ends, drawn from the same random numbers in both poses. Every move draws a slot's
/// pairs from the same numbers, so what they found in one move's pose B is what the next
/// move's would find in its pose A: a backend may keep it ([`PairInPose`]) so that a drag
/// traces each pose once. Each move's correction stays unbiased, its pairs being drawn
/// independently of the slot's iterations; successive moves' errors then cancel along a drag
/// (their sum is one estimate of the whole change) instead of adding up.
pub struct Pair {
    pixel: u32,
    slot: u32,
    jitter: (f32, f32),
    key: StreamKey,
    light: DirectLightParams,
    settings: EyePathSettings,
}

impl Pair {
    /// Sample `k` of slot `slot` (pixel `pixel`) of the move `request`.
    pub fn new(slot: u32, pixel: u32, k: u32, request: &LocalMove) -> Self {
        let seed = request.seed ^ CHANGE_SEED;
        Self {
            pixel,
            slot,
            jitter: StratifiedStream::new(seed, PassKind::Eye, slot).pair(0, k),
            key: StreamKey {
                seed,
                kind: PassKind::Eye,
                pass_index: k,
                path: slot,
            },
            light: DirectLightParams {
                seed,
                iteration: k,
                samples: 1,
                ray_epsilon: request.paths.ray_epsilon,
                accumulate: direct_accumulate::REPLACE,
                ..DirectLightParams::default()
            },
            // Its eye paths take the light samples the eye pass takes at glossy bounces.
            settings: EyePathSettings {
                sample_lights: true,
                ..request.paths
            },
        }
    }

    /// Its eye path in `pose`, noting whether it crossed one of `boxes`.
    pub fn trace<P: PoseQueries>(&self, pose: &P, camera: &GpuCamera, boxes: &[Aabb]) -> EyePath {
        let watch = Watch { groups: 0, boxes };
        trace_eye_path(
            pose,
            camera,
            (self.pixel, self.jitter),
            &self.key,
            &self.settings,
            &watch,
        )
    }

    /// The direct light that `path` brings to the eye in `pose`.
    pub fn direct<P: PoseQueries>(&self, pose: &P, path: &EyePath) -> Vec3 {
        let visible = path
            .visible
            .map_or(HitPoint::empty(self.pixel), |v| v.hit_point(self.pixel));
        slot_direct(&self.light, pose, &visible, &path.chain, self.slot).0
    }

    /// Its direct light in pose `after` less that in `before`, and the pair in pose `after`,
    /// for a move of the `moved` boxes with direct light from the `lights` boxes. `known` is
    /// the pair in pose `before`, if a move left it: its light is pose A's, and when its path
    /// went straight to its visible point without crossing a moved box, it is pose B's path
    /// too. Otherwise pose B is traced first. When its eye path neither bounced nor crossed a
    /// moved box, it is pose A's path too and is not traced again; when, besides, no ray from
    /// its visible point to a light may cross a moved box, the difference is exactly zero.
    pub fn difference<A: PoseQueries, B: PoseQueries>(
        &self,
        (before, after, camera): (&A, &B, &GpuCamera),
        (lights, moved): (&[Aabb], &[Aabb]),
        known: Option<&PairInPose>,
    ) -> (Vec3, PairInPose) {
        let straight = |path: &EyePath| {
            let (origin, dir) = camera_segment(camera, self.pixel, self.jitter);
            let watch = Watch {
                groups: 0,
                boxes: moved,
            };
            !path.chained && !watch.crossed(origin, dir, path.first_t)
        };
        let b = match known {
            // Its crossing was just tested against this move's boxes, not the last move's.
            Some(a) if straight(&a.path) => EyePath {
                crossed: false,
                ..a.path
            },
            _ => self.trace(after, camera, moved),
        };
        let same_path = !b.crossed && !b.chained;
        // The box of the visible point and of its rays' origin, offset along the normal.
        let same_light = |v: &crate::eye_path::Visible| {
            let offset = v.position + v.normal * self.settings.ray_epsilon;
            let from = Aabb::new(v.position.min(offset), v.position.max(offset));
            !direct_may_change(&from, lights, moved)
        };
        let known_light = known.and_then(|a| a.light);
        if same_path && b.visible.as_ref().is_none_or(same_light) {
            let unchanged = PairInPose {
                path: b,
                light: known_light,
            };
            return (Vec3::ZERO, unchanged);
        }
        let a = known_light.unwrap_or_else(|| match known {
            Some(a) => self.direct(before, &a.path),
            None if same_path => self.direct(before, &b),
            None => self.direct(before, &self.trace(before, camera, &[])),
        });
        let light = self.direct(after, &b);
        let pair = PairInPose {
            path: b,
            light: Some(light),
        };
        (light - a, pair)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No change is exactly none; pairs that agree are still as uncertain as an
    /// all-or-nothing change seen by as many samples; pairs that disagree give their sample
    /// variance of the mean.
    #[test]
    fn the_change_and_how_well_it_is_known() {
        let none = change_of(&[Vec3::ZERO; 4]);
        assert_eq!((none.mean, none.variance), ([0.0; 3], 0.0));
        let agree = change_of(&[Vec3::splat(-2.0); 4]);
        assert_eq!(agree.mean, [-2.0; 3]);
        assert!((agree.variance - 1.0).abs() < 1e-5, "{agree:?}");
        // Luminances 0 and -4 in turn: mean -2, squared deviations 16 in all over 4 pairs,
        // so the mean's variance is 16 / (4 x 3).
        let split = change_of(&[Vec3::ZERO, Vec3::splat(-4.0), Vec3::ZERO, Vec3::splat(-4.0)]);
        assert_eq!(split.mean, [-2.0; 3]);
        assert!((split.variance - 16.0 / 12.0).abs() < 1e-4, "{split:?}");
    }

    /// Four pairs a pass, from 4 to the most.
    #[test]
    fn a_longer_history_draws_more_pairs() {
        assert_eq!(direct_samples_for(1.0), 4);
        assert_eq!(direct_samples_for(2.0), 8);
        assert_eq!(direct_samples_for(8.0), MOST_SAMPLES);
    }

    /// Near the move a slot keeps the floor disc; it widens with the distance at
    /// `CORRECTION_SPREAD`, to twice the floor after a long history and not at all for a
    /// drag step's one pass.
    #[test]
    fn the_correction_disc_widens_with_the_distance_from_the_move() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        let at = |x: f32, widest: f32| correction_r2(Vec3::new(x, 0.5, 0.5), &boxes, 4.0, widest);
        // Inside the box and near it: the floor (radius 2).
        assert_eq!(at(0.5, 2.0), 4.0);
        assert_eq!(at(1.0 + 2.0 / CORRECTION_SPREAD, 2.0), 4.0);
        // Halfway to the widest: radius 3 at a distance of 10.
        assert!((at(11.0, 2.0) - 9.0).abs() < 1e-4, "{}", at(11.0, 2.0));
        // Far away: twice the floor, or the floor alone for a one-pass correction.
        assert_eq!(at(1e6, 2.0), 16.0);
        assert_eq!(at(1e6, 1.0), 4.0);
    }
}
