//! Local mode (ours; docs/algorithm.md 3b and 3c): a move keeps everything it did not change,
//! whatever the move. Nothing about it is known before it happens: which objects move, where
//! to, or when.
//!
//! Every `sppm` iteration records, per slot, the object groups its eye paths met
//! (`HitPoint::eye_met`, a bit per group of [`object_group`]), whether a path bounced off a
//! mirror or glass before its visible point (`EYE_CHAINED`), and the box of every vertex its
//! paths reached after the camera (`SlotBounds`). At a move of some objects from pose A to
//! pose B:
//! - a slot starts over when what it sees may change: its eye paths met a moved object's
//!   group (pose A); or the pixel lies under pose B's outline ([`covered_pixels`],
//!   conservative) and pose B comes nearer the eye than the farthest vertex its paths reached;
//!   or its paths bounced, their box meets a moved object's box in pose B, and one of
//!   [`PROBE_PATHS`](super::probe::PROBE_PATHS) eye paths traced in pose B through
//!   stratified random points of the pixel meets a moved object ([`super::probe`], traced on
//!   the host);
//! - any other slot keeps its visible points, the light it saw directly and its photon
//!   statistics. Its direct light can change only through shadow or cosine rays from its
//!   visible points, or light samples from its paths' glossy bounces, to a light that cross
//!   a moved object's box in either pose: all start inside the slot's box, so where a
//!   segment from its box to a light's box may cross one ([`segments_may_meet`]), its direct
//!   sum is corrected by the change over its pixel that paired eye paths and light samples
//!   estimate in both poses ([`super::direct_change`], traced on the host: an unbiased
//!   estimate, exactly zero where the move blocks or frees none of the rays);
//! - the kept slots' indirect light is corrected by a difference pass per pose: ordinary
//!   photons traced in both poses with the same random numbers, whose deferred net sum is the change
//!   of every photon path the move changed. A path is the same in both poses until it
//!   crosses a moved object's box in pose A or in pose B, so only deposits made after that
//!   are stored (in both poses): the gather costs in proportion to the light the objects
//!   touch. Pose A records, one bit per path, whether the path crossed a box at all; pose B
//!   traces only those that did (`culled_share` in the report), and adds its photons to pose
//!   A's, so that one gather folds both. A drag step's one-pass correction draws the random
//!   numbers of the ordinary pass just traced in pose A, whose paths a backend may have
//!   kept (`photon_flags::KEEP_PATHS`: then pose A traces no ray). The correction is gathered
//!   within a disc wider than a converged slot's ([`MoveParams::correction_radii`]), wider
//!   still far from the moved objects ([`CORRECTION_SPREAD`]), and added to the flux alone:
//!   it brings no new photons to shrink the radius with.
//!
//! The records hold since a slot's statistics started, so a slot whose paths first meet an
//! object late in its life is still reset by the next move of it. A moved light restarts.
//!
//! Then every second iteration ([`FOCUS_PERIOD`](super::FOCUS_PERIOD)) traces eye paths and
//! direct light only for the slots with the fewest iterations: a slot whose direct sum holds
//! more iterations than the slots the move reset rests (`hit_flags::RESTING`), until they
//! catch up. Its last visible point still gathers the iteration's photons, traced anyway.
//!
//! [`MoveParams::correction_radii`]: ppm_core::params::MoveParams::correction_radii

use super::direct_change::{PairsInPose, Reach, direct_changes, direct_samples_for};
use super::moves::{Compensation, MoveReport};
use super::probe::{self, HostPose, ProbeSettings};
use super::{Renderer, dynamic, pass_params};
use glam::Vec3;
use ppm_core::compile::{mover_boxes, object_group};
use ppm_core::layout::{HitPoint, SlotBounds, gather_kind, hit_flags};
use ppm_core::params::Estimator;
use ppm_core::passes::BackendError;
use ppm_core::reach::Aabb;
use ppm_core::refit::recompile_moved;
use ppm_core::scene::{MaterialKind, Scene};
use ppm_core::screen_cover::covered_pixels;
use ppm_core::update::history_kept;
use rayon::prelude::*;
use std::time::Instant;

/// How a kept slot's correction disc widens with the distance `d` from its visible point to
/// the nearest moved box: to `CORRECTION_SPREAD * d`. The change a move makes to the indirect
/// light varies over about that distance, so such a disc blurs little of it and gathers more
/// of the correction's photons, whose noise the slot would otherwise keep (docs/algorithm.md
/// 3b).
const CORRECTION_SPREAD: f32 = 0.3;

/// The widest correction disc, in radii of the pass's floor, for a correction of two passes'
/// worth or more; one of `P < 2` passes' worth widens to `P` floors at most. A disc's cost
/// grows with its area, and a drag step's one-pass correction does not widen: on the drag
/// bench widening cost a cornell-box step 23 ms, two thirds of an iteration.
const CORRECTION_WIDEST: f32 = 2.0;

/// Triangles of a moved mesh whose screen cover one thread marks.
const COVER_CHUNK: usize = 8192;

/// Lights up to which the direct-light test takes each emitting triangle's box; beyond, the
/// box around all of them.
const LIGHT_BOXES: usize = 16;

/// What local mode's correction of a move is made of ([`Renderer::local_correction`]).
struct CorrectionSize {
    /// Whole passes' worth of photons: the pass counter advances by as many.
    passes: u32,
    /// The difference passes that correct the indirect light.
    photons: Compensation,
    /// Their squared floor radius.
    r2_floor: f32,
    /// The widest a kept slot's disc grows far from the move, in floor radii
    /// ([`correction_r2`]).
    widest: f32,
    /// Paired direct-light samples per corrected slot ([`direct_changes`]).
    direct_samples: u32,
}

/// Slots a move reset, kept, and kept with their direct sum corrected.
struct Resets {
    reset: u64,
    kept: u64,
    direct_corrected: u64,
}

/// The moved objects' boxes in both poses and their group bits.
struct Moved {
    /// Bits of the moved objects' groups.
    groups: u32,
    /// Their boxes in pose A.
    before: Vec<Aabb>,
    /// Their boxes in pose B.
    after: Vec<Aabb>,
}

impl Moved {
    /// Their boxes in both poses.
    fn both(&self) -> Vec<Aabb> {
        self.before.iter().chain(&self.after).copied().collect()
    }
}

impl Renderer<'_> {
    /// Why local mode cannot keep anything for a move of `changed` objects, if it cannot.
    pub(super) fn local_plan(&self, changed: &[usize]) -> Result<Compensation, String> {
        if self.params.estimator != Estimator::Sppm {
            return Err("local mode keeps sppm slots; ppm restarts".to_owned());
        }
        // Nothing records what a light's photons and shadow rays reached.
        let emits = |&o: &usize| {
            let material = self.scene.objects[o].material;
            matches!(
                self.scene.materials[material].kind,
                MaterialKind::Light { .. }
            )
        };
        if let Some(&light) = changed.iter().find(|o| emits(o)) {
            return Err(format!(
                "a light moves ({}): local mode restarts",
                self.scene.objects[light].name
            ));
        }
        Ok(self.local_correction().photons)
    }

    /// Local mode's correction of a move. Its size follows the history the move keeps
    /// ([`MoveParams::correction_for`]): a slot keeps the share of its history worth keeping
    /// against the correction's noise, so a long history is worth more photons and direct
    /// samples, more photons a narrower floor disc (less blur of the change), and a wider
    /// one far from the move.
    ///
    /// [`MoveParams::correction_for`]: ppm_core::params::MoveParams::correction_for
    fn local_correction(&self) -> CorrectionSize {
        let (share, radii) = self
            .moves
            .correction_for(self.counters.iteration, self.counters.steps_since_move);
        // At most `correction_passes` passes' worth, which the options hold under 2^32.
        let photons = (f64::from(share) * f64::from(self.params.photons_per_pass)).round();
        let photons = photons.min(f64::from(u32::MAX)) as u32;
        let r2_floor = (radii * self.params.initial_radius).powi(2);
        CorrectionSize {
            // Pass indices advance by whole passes, so no two moves share random numbers.
            passes: share.ceil() as u32,
            photons: Compensation::Difference {
                correction_photons: Some(photons),
                r2_floor,
            },
            r2_floor,
            widest: CORRECTION_WIDEST.min(share),
            direct_samples: direct_samples_for(share),
        }
    }

    /// Moves the `changed` objects to their pose in `next`: the resets, then difference
    /// passes and the paired direct-light correction in pose A and in pose B, their net
    /// change applied once to the kept slots.
    pub(super) fn move_locally(
        &mut self,
        next: Scene,
        changed: &[usize],
        mut report: MoveReport,
        start: Instant,
    ) -> Result<MoveReport, BackendError> {
        // From now on ordinary passes keep their paths for the next move's pose A.
        self.keep_paths = true;
        // The passes of both poses test the moved objects' boxes in both poses: a path is the
        // same in A and B until it crosses one.
        let movers = mover_boxes(&self.scene, &next, changed, self.extent);
        // Pose A's tree refitted to pose B, rebuilt only once it has grown (ppm_core::refit).
        let mut compiled = recompile_moved(&self.compiled, &next, changed, self.spare.take());
        compiled.movers = movers.clone();
        self.compiled.movers = movers;
        let moved = Moved {
            groups: changed.iter().fold(0, |g, &o| g | object_group(o)),
            before: changed.iter().map(|&o| aabb(&self.scene, o)).collect(),
            after: changed.iter().map(|&o| aabb(&next, o)).collect(),
        };
        // The resets depend only on the records and on pose B, so they come first: the
        // passes below then skip the reset slots in both poses alike.
        let size = self.local_correction();
        let mut slots = self.backend.read_hit_points()?;
        // Pose B as the host's probes trace it, copied once if one of them needs it.
        let after = HostPose::new(&compiled);
        let resets = self.reset_near(&mut slots, &next, &after, changed, &moved, &size)?;
        // The last move's pose B, if it left this pose: its copy and its direct pairs.
        let (copy, known) = self.host_copy.take().unzip();
        let mut pairs = PairsInPose::default();
        if resets.direct_corrected > 0 {
            let before = HostPose::reusing(&self.compiled, copy);
            let poses = (&before, &after);
            pairs = self.correct_direct(&mut slots, poses, &moved, size.direct_samples, known);
        }
        self.backend.write_hit_points(&slots)?;
        report.updated = resets.reset;
        report.kept = resets.kept;
        report.direct_corrected = resets.direct_corrected;
        // Deposits per photon of the passes so far (counters a caller may reset aside).
        let per_photon =
            self.report.photons_deposited as f64 / self.report.photons_emitted.max(1) as f64;
        let stored_before = self.counts.compensation.deposited + self.counts.region.deposited;
        let emitted_before = self.counts.compensation.emitted + self.counts.region.emitted;
        dynamic(self.backend)?.update_scene(&self.compiled)?;
        self.compensate(&size.photons, gather_kind::REGION_NEGATIVE)?;
        dynamic(self.backend)?.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        let copy = after.into_copy();
        self.adopt(next, compiled);
        self.host_copy = copy.map(|copy| (copy, pairs));
        self.counters.frame += 1;
        let positive = self.compensate(&size.photons, gather_kind::REGION_POSITIVE)?;
        if positive.emitted > 0 {
            report.culled_share = Some(positive.culled as f64 / positive.emitted as f64);
        }
        self.counters.difference_pass += size.passes;
        if size.passes > 0 {
            self.gather(gather_kind::REGION_APPLY | gather_kind::ADD_FLUX, 0.0, 0.0)?;
        }
        let stored = self.counts.compensation.deposited + self.counts.region.deposited;
        let emitted = self.counts.compensation.emitted + self.counts.region.emitted;
        if emitted > emitted_before && per_photon > 0.0 {
            report.changed_share = Some(
                (stored - stored_before) as f64 / ((emitted - emitted_before) as f64 * per_photon),
            );
        }
        self.guide = None;
        self.counters.steps_since_move = 0;
        report.seconds = start.elapsed().as_secs_f64();
        self.report.times.moves += report.seconds;
        Ok(report)
    }

    /// Corrects the direct sums of the kept `slots` flagged `DIRECT_MAY_CHANGE` by their
    /// change from pose `before` to `after` of the `moved` objects ([`direct_changes`]),
    /// each weighed against its history (docs/algorithm.md 3c): against the slot's
    /// corrected mean `D` over `N` iterations (relative noise about `1 / N`), a change known
    /// to a variance `V` leaves the history worth `N' = N / (1 + N V / lum(D)^2)` iterations
    /// ([`history_kept`]), and the sum keeps its mean at that count. An unchanged slot keeps
    /// all of it. Channels the change drives below zero are clamped there. `samples` pairs
    /// per slot; `known` holds them in pose `before` if the last move left it. Returns them in
    /// pose `after`.
    fn correct_direct(
        &self,
        slots: &mut [HitPoint],
        poses: (&HostPose, &HostPose),
        moved: &Moved,
        samples: u32,
        known: Option<PairsInPose>,
    ) -> PairsInPose {
        let corrected: Vec<bool> = slots
            .iter()
            .map(|hp| hp.flags & hit_flags::DIRECT_MAY_CHANGE != 0 && hp.iterations > 0)
            .collect();
        let (lights, boxes) = (self.light_boxes(), moved.both());
        let reach = Reach {
            lights: &lights,
            moved: &boxes,
        };
        let (changes, pairs) = direct_changes(
            poses,
            slots,
            &corrected,
            samples,
            &self.probe_settings(),
            &reach,
            known.as_ref(),
        );
        slots.par_iter_mut().zip(changes).for_each(|(hp, change)| {
            // No pair changed: the sum stays as it is, bit for bit.
            let Some(change) = change.filter(|c| c.mean != [0.0; 3]) else {
                return;
            };
            let n = hp.iterations as f32;
            let mean: [f32; 3] =
                std::array::from_fn(|c| (hp.direct[c] / n + change.mean[c]).max(0.0));
            let kept = history_kept(n, mean, change.variance);
            let count = ((n * kept).round() as u32).clamp(1, hp.iterations);
            hp.direct = mean.map(|d| d * count as f32);
            hp.iterations = count;
        });
        pairs
    }

    /// Starts over the `slots` whose view the move of `changed` objects to `next`
    /// (`after`) may change (see the module doc) and marks them `UPDATED`, so the
    /// compensation skips them; marks `DIRECT_MAY_CHANGE` the kept slots whose direct light it
    /// may change, and sizes each kept slot's correction disc ([`correction_r2`]) as `size`
    /// says.
    fn reset_near(
        &mut self,
        slots: &mut [HitPoint],
        next: &Scene,
        after: &HostPose,
        changed: &[usize],
        moved: &Moved,
        size: &CorrectionSize,
    ) -> Result<Resets, BackendError> {
        let bounds = dynamic(self.backend)?.read_slot_bounds()?;
        let camera = &after.compiled.camera;
        // A mesh's cover in parts, one per thread's share of triangles (cornell-bunny's 70,000
        // took 6 ms in one), or'ed into one.
        let covered = changed
            .par_iter()
            .flat_map(|&o| next.objects[o].triangles.par_chunks(COVER_CHUNK))
            .map(|part| covered_pixels(camera, part))
            .reduce_with(|mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x |= *y);
                a
            })
            .unwrap_or_else(|| covered_pixels(camera, &[]));
        let eye = Vec3::from(camera.eye);
        let nearest = moved
            .after
            .iter()
            .map(|b| b.distance_from(eye))
            .fold(f32::INFINITY, f32::min);
        let reached = |i: usize| {
            bounds
                .get(i)
                .map_or(Aabb::new(Vec3::MIN, Vec3::MAX), slot_box)
        };
        // Pose A's records, and pose B in front of what the pixel's paths reached.
        let decide = |i: usize, hp: &HitPoint| {
            let b = reached(i);
            hp.eye_met & moved.groups != 0
                || covered[hp.pixel as usize] && (b.is_empty() || nearest < b.farthest_from(eye))
        };
        // Paths past a mirror or glass whose box meets pose B: the probe decides.
        let chained = |i: usize, hp: &HitPoint| {
            hp.flags & hit_flags::EYE_CHAINED != 0
                && moved.after.iter().any(|b| b.overlaps(&reached(i)))
        };
        let decided: Vec<bool> = slots
            .par_iter()
            .enumerate()
            .map(|(i, hp)| decide(i, hp))
            .collect();
        let undecided: Vec<bool> = slots
            .par_iter()
            .enumerate()
            .map(|(i, hp)| !decided[i] && chained(i, hp))
            .collect();
        let met_in_b = self.probe(after, slots, &undecided, moved.groups);
        let lights = self.light_boxes();
        let boxes = moved.both();
        let reach = Reach {
            lights: &lights,
            moved: &boxes,
        };
        let r2_initial = self.params.initial_radius * self.params.initial_radius;
        let (reset, corrected) = slots
            .par_iter_mut()
            .enumerate()
            .map(|(i, hp)| {
                let sees_change = decided[i] || undecided[i] && met_in_b[hp.pixel as usize];
                if sees_change {
                    *hp = HitPoint {
                        r2: r2_initial,
                        flags: hit_flags::UPDATED,
                        ..HitPoint::empty(hp.pixel)
                    };
                    return (1, 0);
                }
                hp.flags &=
                    !(hit_flags::UPDATED | hit_flags::RESTING | hit_flags::DIRECT_MAY_CHANGE);
                hp.correction_r2 = correction_r2(hp.position.into(), &boxes, size);
                if reach.direct_may_change(&reached(i)) {
                    hp.flags |= hit_flags::DIRECT_MAY_CHANGE;
                    return (0, 1);
                }
                (0, 0)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        Ok(Resets {
            reset,
            kept: slots.len() as u64 - reset,
            direct_corrected: corrected,
        })
    }

    /// How the host traces the probes' eye paths: the render's seed, depth and ray offset.
    fn probe_settings(&self) -> ProbeSettings {
        ProbeSettings {
            seed: self.params.seed,
            max_depth: self.params.max_eye_depth,
            ray_epsilon: pass_params::ray_epsilon(&self.params, self.extent),
            sample_lights: false,
        }
    }

    /// The boxes the direct-light test reaches for: each light's (a box inside another
    /// counted once: a quad's two triangles share theirs), or one around all of them.
    fn light_boxes(&self) -> Vec<Aabb> {
        let mut boxes: Vec<Aabb> = Vec::new();
        for l in &self.lights {
            let v0 = Vec3::from(l.v0);
            let b = Aabb::of_triangle([v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)]);
            if !boxes.iter().any(|kept| kept.contains(&b)) {
                boxes.push(b);
            }
        }
        if boxes.len() <= LIGHT_BOXES {
            return boxes;
        }
        vec![boxes.iter().skip(1).fold(boxes[0], |a, b| a.union(b))]
    }

    /// Per pixel, whether the probe's paths through it meet one of the moved `groups` in
    /// pose `next`, for the pixels of the `probed` slots ([`super::probe`]); empty when
    /// none is probed.
    fn probe(
        &self,
        next: &HostPose,
        slots: &[HitPoint],
        probed: &[bool],
        groups: u32,
    ) -> Vec<bool> {
        let mut pixels: Vec<u32> = slots
            .iter()
            .zip(probed)
            .filter(|(_, p)| **p)
            .map(|(hp, _)| hp.pixel)
            .collect();
        if pixels.is_empty() {
            return Vec::new();
        }
        pixels.dedup();
        let settings = self.probe_settings();
        let mut met = vec![false; (self.params.width * self.params.height) as usize];
        for (pixel, hit) in pixels
            .iter()
            .zip(probe::paths_meet(next, &pixels, groups, &settings))
        {
            met[*pixel as usize] |= hit;
        }
        met
    }
}

/// Object `o`'s box as posed in `scene`.
fn aabb(scene: &Scene, o: usize) -> Aabb {
    let (lo, hi) = scene.objects[o].bounds();
    Aabb::new(lo, hi)
}

/// The squared radius of a kept slot's correction disc (`HitPoint::correction_r2`) whose
/// visible point is at `position`: the floor's, widened to [`CORRECTION_SPREAD`] times the
/// distance to the nearest of the moved `boxes`, at most `size.widest` floors.
fn correction_r2(position: Vec3, boxes: &[Aabb], size: &CorrectionSize) -> f32 {
    let floor = size.r2_floor.sqrt();
    let nearest = boxes
        .iter()
        .map(|b| b.distance_from(position))
        .fold(f32::INFINITY, f32::min);
    let r = (CORRECTION_SPREAD * nearest).clamp(floor, size.widest * floor);
    r * r
}

/// A slot's recorded box.
fn slot_box(b: &SlotBounds) -> Aabb {
    Aabb::new(b.min.into(), b.max.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size(share: f32) -> CorrectionSize {
        CorrectionSize {
            passes: share.ceil() as u32,
            photons: Compensation::Difference {
                correction_photons: None,
                r2_floor: 4.0,
            },
            r2_floor: 4.0,
            widest: CORRECTION_WIDEST.min(share),
            direct_samples: direct_samples_for(share),
        }
    }

    /// The pose a local move keeps for the next is the pose the render now holds
    /// (triangles, tree and materials, byte for byte), after every move of a drag, and each
    /// move after the first writes its pose into the buffers of the pose before last
    /// (nothing else holds them: the backend and the host's traces share the current
    /// pose's); a restart drops both.
    #[test]
    fn the_pose_kept_for_the_next_move_is_the_pose_rendered() {
        use ppm_core::params::{MoveMode, MoveParams, RenderParams};
        use ppm_core::scene::Move;
        let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
        let mut params = RenderParams::for_scene(&scene);
        (params.width, params.height, params.photons_per_pass) = (24, 24, 2000);
        let step = Move {
            translation: Vec3::new(-2.0, 0.0, 1.0),
            rotation: glam::Quat::from_rotation_y(0.05),
            ..scene.moves[0]
        };
        let mut backend = backend_cpu::CpuBackend::new();
        let mut r = Renderer::start(&mut backend, scene, &params, &MoveParams::default()).unwrap();
        fn bytes<T: bytemuck::Pod>(v: &[T]) -> &[u8] {
            bytemuck::cast_slice(v)
        }
        let mut lent = 0;
        for _ in 0..3 {
            r.iteration().unwrap();
            let spare = r.spare.as_ref().map(|s| s.triangles.as_ptr());
            r.move_objects(&[step], MoveMode::Local).unwrap();
            lent += usize::from(spare == Some(r.compiled.triangles.as_ptr()));
            let (copy, _) = r.host_copy.as_ref().expect("the move kept its pose B");
            assert_eq!(copy.triangles, r.compiled.triangles);
            assert_eq!(bytes(&copy.bvh.nodes), bytes(&r.compiled.bvh.nodes));
            assert_eq!(copy.materials, r.compiled.materials);
        }
        assert_eq!(
            lent, 2,
            "the second and third moves reuse the pose before last"
        );
        r.move_objects(&[step], MoveMode::Restart).unwrap();
        assert!(r.host_copy.is_none() && r.spare.is_none());
    }

    /// Near the move a slot keeps the floor disc; it widens with the distance at
    /// `CORRECTION_SPREAD`, to twice the floor after a long history and not at all for a
    /// drag step's one pass.
    #[test]
    fn the_correction_disc_widens_with_the_distance_from_the_move() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        let at = |x: f32, share: f32| correction_r2(Vec3::new(x, 0.5, 0.5), &boxes, &size(share));
        // Inside the box and near it: the floor (radius 2).
        assert_eq!(at(0.5, 8.0), 4.0);
        assert_eq!(at(1.0 + 2.0 / CORRECTION_SPREAD, 8.0), 4.0);
        // Halfway to the widest: radius 3 at a distance of 10.
        assert!((at(11.0, 8.0) - 9.0).abs() < 1e-4, "{}", at(11.0, 8.0));
        // Far away: twice the floor, or the floor alone for a one-pass correction.
        assert_eq!(at(1e6, 8.0), 16.0);
        assert_eq!(at(1e6, 1.0), 4.0);
    }
}
