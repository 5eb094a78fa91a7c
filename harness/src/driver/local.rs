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
//!   visible points to a light that cross a moved object's box in either pose: where a
//!   segment from its box to a light's box may cross one ([`segments_may_meet`]), its direct
//!   sum is corrected by [`CORRECTION_SAMPLES`] shadow-ray samples traced at its visible point
//!   in both poses with the same random numbers (an unbiased estimate of the change, exactly
//!   zero where the move blocks or frees none of them);
//! - the kept slots' indirect light is corrected by a difference pass per pose: ordinary
//!   photons traced in both poses with the same random numbers, whose deferred net sum is the change
//!   of every photon path the move changed. A path is the same in both poses until it
//!   crosses a moved object's box in pose A or in pose B, so only deposits made after that
//!   are stored (in both poses): the gathers cost in proportion to the light the objects
//!   touch. Pose A records, one bit per path, whether the path crossed a box at all; pose B
//!   traces only those that did (`culled_share` in the report). The correction is gathered
//!   within a disc wider than a converged slot's ([`MoveParams::correction_radii`]), and
//!   added to the flux alone: it brings no new photons to shrink the radius with.
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

use super::moves::{Compensation, MoveReport};
use super::probe::{self, ProbeSettings};
use super::{Renderer, dynamic, pass_params};
use glam::Vec3;
use ppm_core::compile::{CompiledScene, mover_boxes, object_group};
use ppm_core::layout::{
    DirectLightParams, HitPoint, SlotBounds, direct_accumulate, gather_kind, hit_flags,
};
use ppm_core::params::Estimator;
use ppm_core::passes::BackendError;
use ppm_core::reach::{Aabb, segments_may_meet};
use ppm_core::refit::recompile_moved;
use ppm_core::scene::{MaterialKind, Scene};
use ppm_core::screen_cover::covered_pixels;
use ppm_core::update::{history_kept, luminance};
use rayon::prelude::*;
use std::time::Instant;

/// Direct-light samples per slot of the paired correction, in each pose.
pub const CORRECTION_SAMPLES: u32 = 8;

/// Keys the correction's random numbers apart from every iteration's.
const CORRECTION_SEED: u32 = 0x5eed_c0de;

/// Lights up to which the direct-light test takes each emitting triangle's box; beyond, the
/// box around all of them.
const LIGHT_BOXES: usize = 16;

/// Slots a move reset, kept, and kept with their direct sum corrected, and every slot's
/// direct sum before the correction.
struct Resets {
    reset: u64,
    kept: u64,
    direct_corrected: u64,
    direct_before: Vec<[f32; 3]>,
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
        Ok(self.local_correction().1)
    }

    /// Local mode's indirect correction: difference passes that store only the deposits of
    /// paths that crossed a moved object's box (the others cancel between the poses),
    /// gathered within a disc wider than a converged slot's. Its size follows the history
    /// the move keeps ([`MoveParams::correction_for`]): a slot keeps the share of its history
    /// worth keeping against the correction's noise, so a long history is worth more
    /// photons, and more photons a narrower disc (less blur of the change).
    ///
    /// [`MoveParams::correction_for`]: ppm_core::params::MoveParams::correction_for
    fn local_correction(&self) -> (u32, Compensation) {
        let (share, radii) = self.moves.correction_for(self.counters.steps_since_move);
        // At most `correction_passes` passes' worth, which the options hold under 2^32.
        let photons = (f64::from(share) * f64::from(self.params.photons_per_pass)).round();
        let photons = photons.min(f64::from(u32::MAX)) as u32;
        let correction = Compensation::Difference {
            correction_photons: Some(photons),
            r2_floor: (radii * self.params.initial_radius).powi(2),
        };
        // Pass indices advance by whole passes, so no two moves share random numbers.
        (share.ceil() as u32, correction)
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
        // The passes of both poses test the moved objects' boxes in both poses: a path is the
        // same in A and B until it crosses one.
        let movers = mover_boxes(&self.scene, &next, changed, self.extent);
        // Pose A's tree refitted to pose B, rebuilt only once it has grown (ppm_core::refit).
        let mut compiled = recompile_moved(&self.compiled, &next, changed);
        compiled.movers = movers.clone();
        self.compiled.movers = movers;
        let moved = Moved {
            groups: changed.iter().fold(0, |g, &o| g | object_group(o)),
            before: changed.iter().map(|&o| aabb(&self.scene, o)).collect(),
            after: changed.iter().map(|&o| aabb(&next, o)).collect(),
        };
        // The resets depend only on the records and on pose B, so they come first: the
        // passes below then skip the reset slots in both poses alike.
        let resets = self.reset_near(&next, &compiled, changed, &moved)?;
        report.updated = resets.reset;
        report.kept = resets.kept;
        report.direct_corrected = resets.direct_corrected;
        // Deposits per photon of the passes so far (counters a caller may reset aside).
        let per_photon =
            self.report.photons_deposited as f64 / self.report.photons_emitted.max(1) as f64;
        let stored_before = self.counts.compensation.deposited + self.counts.region.deposited;
        let emitted_before = self.counts.compensation.emitted + self.counts.region.emitted;
        let (passes, correction) = self.local_correction();
        dynamic(self.backend)?.update_scene(&self.compiled)?;
        self.compensate(&correction, gather_kind::REGION_NEGATIVE)?;
        if resets.direct_corrected > 0 {
            self.correct_direct(-1.0)?;
        }
        dynamic(self.backend)?.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        self.adopt(next, compiled);
        self.counters.frame += 1;
        if resets.direct_corrected > 0 {
            self.correct_direct(1.0)?;
            self.weigh_direct_corrections(&resets.direct_before)?;
        }
        let positive = self.compensate(&correction, gather_kind::REGION_POSITIVE)?;
        if positive.emitted > 0 {
            report.culled_share = Some(positive.culled as f64 / positive.emitted as f64);
        }
        self.counters.difference_pass += passes;
        if passes > 0 {
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

    /// Half of the paired direct-light correction, in the current pose (`sign` -1 before the
    /// move, +1 after it; the same random numbers both times).
    fn correct_direct(&mut self, sign: f32) -> Result<(), BackendError> {
        let params = DirectLightParams {
            seed: self.params.seed ^ CORRECTION_SEED,
            samples: CORRECTION_SAMPLES,
            iteration: self.counters.difference_pass,
            accumulate: direct_accumulate::CORRECT,
            sign,
            ..self.direct_params(0, true)
        };
        self.run_direct_light(&params)
    }

    /// Weighs each corrected direct sum against its correction (docs/algorithm.md 3c): the
    /// paired samples estimate the change at one visible point of the pixel, so a change of
    /// size `d` is known only to about `d`; against the slot's mean `D` over `N` iterations
    /// (relative noise about `1 / N`) its history is then worth
    /// `N' = N / (1 + N d^2 / D^2)` iterations ([`history_kept`]), and the sum keeps its mean
    /// at that count. An unchanged slot (`d = 0`) keeps all of it; a large change leaves the
    /// samples that follow to decide, at the rate of a consistent estimator. Channels the
    /// correction drove below zero are clamped there.
    fn weigh_direct_corrections(&mut self, before: &[[f32; 3]]) -> Result<(), BackendError> {
        let mut slots = self.backend.read_hit_points()?;
        slots.par_iter_mut().zip(before).for_each(|(hp, old)| {
            if hp.flags & hit_flags::DIRECT_MAY_CHANGE == 0 || hp.iterations == 0 {
                return;
            }
            let n = hp.iterations as f32;
            let corrected = hp.direct.map(|d| d.max(0.0));
            let change = std::array::from_fn(|c| (hp.direct[c] - old[c]) / n);
            let mean = corrected.map(|d| d / n);
            let kept = history_kept(n, mean, luminance(change).powi(2));
            let count = ((n * kept).round() as u32).clamp(1, hp.iterations);
            hp.direct = corrected.map(|d| d * count as f32 / n);
            hp.iterations = count;
        });
        self.backend.write_hit_points(&slots)
    }

    /// Starts over the slots whose view the move of `changed` objects to `next` (`compiled`)
    /// may change (see the module doc) and marks them `UPDATED`, so the compensation skips
    /// them; marks `DIRECT_MAY_CHANGE` the kept slots whose direct light it may change.
    fn reset_near(
        &mut self,
        next: &Scene,
        compiled: &CompiledScene,
        changed: &[usize],
        moved: &Moved,
    ) -> Result<Resets, BackendError> {
        let mut slots = self.backend.read_hit_points()?;
        let bounds = dynamic(self.backend)?.read_slot_bounds()?;
        let posed: Vec<[Vec3; 3]> = changed
            .iter()
            .flat_map(|&o| next.objects[o].triangles.iter().copied())
            .collect();
        let covered = covered_pixels(&compiled.camera, &posed);
        let eye = Vec3::from(compiled.camera.eye);
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
        let decided = |i: usize, hp: &HitPoint| {
            let b = reached(i);
            hp.eye_met & moved.groups != 0
                || covered[hp.pixel as usize] && (b.is_empty() || nearest < b.farthest_from(eye))
        };
        // Paths past a mirror or glass whose box meets pose B: the probe decides.
        let chained = |i: usize, hp: &HitPoint| {
            hp.flags & hit_flags::EYE_CHAINED != 0
                && moved.after.iter().any(|b| b.overlaps(&reached(i)))
        };
        let undecided: Vec<bool> = slots
            .iter()
            .enumerate()
            .map(|(i, hp)| !decided(i, hp) && chained(i, hp))
            .collect();
        let met_in_b = self.probe(compiled, &slots, &undecided, moved.groups);
        let lights = self.light_boxes();
        let boxes: Vec<Aabb> = moved.before.iter().chain(&moved.after).copied().collect();
        let direct_may_change = |b: &Aabb| {
            lights
                .iter()
                .any(|l| boxes.iter().any(|m| segments_may_meet(b, l, m)))
        };
        let r2_initial = self.params.initial_radius * self.params.initial_radius;
        let (reset, corrected) = slots
            .par_iter_mut()
            .enumerate()
            .map(|(i, hp)| {
                let sees_change = decided(i, hp) || undecided[i] && met_in_b[hp.pixel as usize];
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
                if direct_may_change(&reached(i)) {
                    hp.flags |= hit_flags::DIRECT_MAY_CHANGE;
                    return (0, 1);
                }
                (0, 0)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        self.backend.write_hit_points(&slots)?;
        Ok(Resets {
            reset,
            kept: slots.len() as u64 - reset,
            direct_corrected: corrected,
            direct_before: slots.iter().map(|hp| hp.direct).collect(),
        })
    }

    /// The boxes the direct-light test reaches for: each light's, or one around all of them.
    fn light_boxes(&self) -> Vec<Aabb> {
        let boxes: Vec<Aabb> = self
            .lights
            .iter()
            .map(|l| {
                let v0 = Vec3::from(l.v0);
                Aabb::of_triangle([v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)])
            })
            .collect();
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
        next: &CompiledScene,
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
        let settings = ProbeSettings {
            seed: self.params.seed,
            max_depth: self.params.max_eye_depth,
            ray_epsilon: pass_params::ray_epsilon(&self.params, self.extent),
        };
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

/// A slot's recorded box.
fn slot_box(b: &SlotBounds) -> Aabb {
    Aabb::new(b.min.into(), b.max.into())
}
