//! Local mode (ours; ALGORITHM.md 3b): a move keeps everything it did not change.
//!
//! Every `sppm` iteration flags, per slot, whether its eye paths met a moving object, and
//! whether they (or separately its shadow and cosine rays) crossed a box that holds a moving
//! object in all its poses (the start's
//! [`CompiledScene::movers`](ppm_core::compile::CompiledScene::movers)). A path that crosses
//! no box meets the same surfaces in every pose, so at a move:
//! - a slot starts over when what it sees may change: its eye paths met a moving object (in
//!   the pose left), or crossed a box after a mirror or glass bounce, or crossed a box from
//!   the camera in a pixel the new pose may cover ([`covered_pixels`], conservative). This
//!   finds the pixels the object newly covers, and keeps those that only saw past it, such
//!   as the floor inside a ring;
//! - any other slot keeps its visible points, the light it saw directly and its photon
//!   statistics; if one of its direct-light rays crossed a box, its direct sum is corrected
//!   by [`CORRECTION_SAMPLES`] shadow-ray samples traced at its visible point in both poses
//!   with the same random numbers (an unbiased estimate of the change, exactly zero where
//!   the move blocks or frees none of them);
//! - the kept slots' indirect light is corrected by difference passes: ordinary photons
//!   traced in both poses with the same random numbers, whose deferred net sum is the change
//!   of every photon path the move changed. A path is the same in both poses until it
//!   crosses a box, so only deposits made after that are stored (in both poses): the
//!   gathers cost in proportion to the light the object touches, and what would cancel
//!   leaves no rounding behind. Pose A records, one bit per path, whether the path crossed a
//!   box at all; pose B traces only those that did, since the others would store nothing
//!   there (`culled_share` in the report). The correction is gathered within a disc wider
//!   than a converged slot's ([`MoveParams::correction_radii`]), and added to the flux
//!   alone: it brings no new photons to shrink the radius with.
//!
//! The flags hold since a slot's statistics started, so a slot whose paths first meet the
//! object late in its life is still reset by the next move.
//!
//! Then every second iteration ([`FOCUS_PERIOD`](super::FOCUS_PERIOD)) traces eye paths and
//! direct light only for the slots with the fewest iterations: a slot whose direct sum holds
//! more iterations than the slots the move reset rests (`hit_flags::RESTING`), until they
//! catch up. Its last visible point still gathers the iteration's photons, traced anyway.
//!
//! A move to the same pose resets nothing, and its difference passes cancel.
//!
//! [`MoveParams::correction_radii`]: ppm_core::params::MoveParams::correction_radii

use super::Renderer;
use super::moves::{Compensation, MoveReport};
use glam::Vec3;
use ppm_core::compile::CompiledScene;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, HitPoint, direct_accumulate, eye_flags, gather_kind,
    hit_flags,
};
use ppm_core::params::Estimator;
use ppm_core::passes::BackendError;
use ppm_core::scene::{MaterialKind, Move, Scene};
use ppm_core::screen_cover::covered_pixels;
use std::time::Instant;

/// Direct-light samples per slot of the paired correction, in each pose.
pub const CORRECTION_SAMPLES: u32 = 8;

/// Keys the correction's random numbers apart from every iteration's.
const CORRECTION_SEED: u32 = 0x5eed_c0de;

/// Eye paths per pixel that `Renderer::probe` traces in the new pose, through independent
/// random points of it: an object that covers an eighth of what a pixel sees through a
/// mirror is missed with probability (7/8)^32 = 1.4%, a sixteenth with 13%. A pixel kept
/// that way holds a sliver of stale light, which its later iterations dilute.
pub const PROBE_PATHS: u32 = 32;

/// Keys the probe's random numbers apart from every iteration's.
const PROBE_SEED: u32 = 0x9b0b_e5ed;

/// Slots a move reset, kept, and kept with their direct sum corrected.
struct Resets {
    reset: u64,
    kept: u64,
    direct_corrected: u64,
}

impl Renderer<'_> {
    /// Why local mode cannot keep anything for a move to `next`, if it cannot.
    pub(super) fn local_plan(&self, next: &Scene) -> Result<Compensation, String> {
        if self.params.estimator != Estimator::Sppm {
            return Err("local mode keeps sppm slots; ppm restarts".to_owned());
        }
        // Rays that escaped or met a wall are not flagged; a moving light could reach them.
        let emits = |m: &Move| {
            let material = self.scene.objects[m.object].material;
            matches!(
                self.scene.materials[material].kind,
                MaterialKind::Light { .. }
            )
        };
        if self.scene.moves.iter().any(emits) {
            return Err("a light moves: local mode restarts".to_owned());
        }
        let inside = |scene: &Scene| {
            scene.moves.iter().zip(&self.movers).all(|(m, b)| {
                let (lo, hi) = scene.objects[m.object].bounds();
                lo.cmpge(b.min.into()).all() && hi.cmple(b.max.into()).all()
            })
        };
        if self.movers.len() != next.moves.len() || !inside(&self.scene) || !inside(next) {
            return Err("the move leaves the boxes flagged since the start".to_owned());
        }
        Ok(self.local_correction())
    }

    /// Local mode's indirect correction: difference passes that store only the deposits of
    /// paths that crossed a mover's box (the others cancel between the poses), gathered
    /// within `correction_radii` initial radii at least. A converged slot's disc is a
    /// fraction of the initial one: the few hundred thousand photons of a correction would
    /// reach it too sparsely, and their noise would stay in statistics built from millions
    /// (on cornell-box the kept pixels' error is 0.047 within one initial radius, 0.035
    /// within two). The wider disc trades that noise for a blur of the change: 15 s after
    /// warm-up, pixel error 1 s / 8 s after the move within two, three and four radii is
    /// 0.039 / 0.027, 0.036 / 0.027 and 0.035 / 0.026 on cornell-box, 0.041 / 0.027,
    /// 0.035 / 0.024 and 0.034 / 0.023 on cornell-bunny, but 0.161 / 0.141, 0.163 / 0.140
    /// and 0.180 / 0.150 on wedding-band, whose caustics blur. Three is the default.
    fn local_correction(&self) -> Compensation {
        Compensation::Difference {
            changed_only: true,
            r2_floor: (self.moves.correction_radii * self.params.initial_radius).powi(2),
        }
    }

    /// Moves to `next`: the resets, then difference passes and the paired direct-light
    /// correction in pose A and in pose B, their net change applied once to the kept slots.
    pub(super) fn move_locally(
        &mut self,
        next: Scene,
        mut report: MoveReport,
        start: Instant,
    ) -> Result<MoveReport, BackendError> {
        // The resets depend only on the flags and on pose B's outline, so they come first:
        // the passes below then skip the reset slots in both poses alike.
        let changed = self.scene.moving_vertices() != next.moving_vertices();
        let compiled = self.compile(&next);
        let resets = self.reset_near_movers(changed, &next, &compiled)?;
        report.updated = resets.reset;
        report.kept = resets.kept;
        report.direct_corrected = resets.direct_corrected;
        // Deposits per photon of the passes so far (counters a caller may reset aside).
        let per_photon =
            self.report.photons_deposited as f64 / self.report.photons_emitted.max(1) as f64;
        let stored_before = self.counts.compensation.deposited + self.counts.region.deposited;
        let emitted_before = self.counts.compensation.emitted + self.counts.region.emitted;
        let correction = self.local_correction();
        self.compensate(&correction, gather_kind::REGION_NEGATIVE)?;
        if changed {
            self.correct_direct(-1.0)?;
        }
        self.backend.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        self.adopt(next, &compiled);
        self.frame += 1;
        if changed {
            self.correct_direct(1.0)?;
        }
        let positive = self.compensate(&correction, gather_kind::REGION_POSITIVE)?;
        if positive.emitted > 0 {
            report.culled_share = Some(positive.culled as f64 / positive.emitted as f64);
        }
        self.difference_pass += self.moves.difference_passes;
        if self.moves.difference_passes > 0 {
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
        self.steps_since_move = 0;
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
            iteration: self.difference_pass,
            accumulate: direct_accumulate::CORRECT,
            sign,
            ..self.direct_params(0, true)
        };
        self.run_direct_light(&params)
    }

    /// Starts over the slots whose view the move to `next` (`compiled`) may change (only when
    /// the geometry `changed`; see the module doc) and marks them `UPDATED`, so the
    /// compensation skips them; counts the kept slots whose direct sums the paired correction
    /// reaches.
    fn reset_near_movers(
        &mut self,
        changed: bool,
        next: &Scene,
        compiled: &CompiledScene,
    ) -> Result<Resets, BackendError> {
        let mut slots = self.backend.read_hit_points()?;
        let posed: Vec<[Vec3; 3]> = next
            .moves
            .iter()
            .flat_map(|m| next.objects[m.object].triangles.iter().copied())
            .collect();
        let covered = covered_pixels(&compiled.camera, &posed);
        let decided = |hp: &HitPoint| {
            hp.flags & hit_flags::EYE_MET_MOVER != 0
                || hp.flags & hit_flags::EYE_NEAR_MOVER != 0 && covered[hp.pixel as usize]
        };
        let chained = |hp: &HitPoint| hp.flags & hit_flags::EYE_CHAIN_NEAR_MOVER != 0;
        let undecided = |hp: &HitPoint| chained(hp) && !decided(hp);
        let met_in_b = if changed && slots.iter().any(undecided) {
            self.probe(compiled, &slots, undecided)?
        } else {
            Vec::new()
        };
        let sees_change = |hp: &HitPoint| decided(hp) || chained(hp) && met_in_b[hp.pixel as usize];
        let mut resets = Resets {
            reset: 0,
            kept: 0,
            direct_corrected: 0,
        };
        let r2_initial = self.params.initial_radius * self.params.initial_radius;
        for hp in &mut slots {
            if changed && sees_change(hp) {
                *hp = HitPoint {
                    r2: r2_initial,
                    flags: hit_flags::UPDATED,
                    ..HitPoint::empty(hp.pixel)
                };
                resets.reset += 1;
                continue;
            }
            hp.flags &= !(hit_flags::UPDATED | hit_flags::RESTING);
            if hp.flags & hit_flags::SHADOW_NEAR_MOVER != 0 {
                resets.direct_corrected += 1;
            }
            resets.kept += 1;
        }
        self.backend.write_hit_points(&slots)?;
        Ok(resets)
    }

    /// Per pixel, whether one of [`PROBE_PATHS`] eye paths through random points of it
    /// meets a moving object in the pose `next` holds, for the `probed` slots: the test for paths that
    /// crossed a mover's box after a mirror or glass bounce, which the screen cannot judge.
    /// Every other slot rests, so the probe costs in proportion to the slots it decides.
    /// Leaves scratch in the slots (the caller writes them back) and the current pose loaded.
    fn probe(
        &mut self,
        next: &CompiledScene,
        slots: &[HitPoint],
        probed: impl Fn(&HitPoint) -> bool,
    ) -> Result<Vec<bool>, BackendError> {
        // A kept slot continues its own sample sequence from `iterations` and rests from
        // `rest_at` on: the probed slots start theirs at 0, and each pass's own seed gives
        // them a fresh point. `EYE_MET_MOVER` is a kept flag, so it gathers over the passes.
        let scratch: Vec<HitPoint> = slots
            .iter()
            .map(|hp| HitPoint {
                iterations: if probed(hp) { 0 } else { u32::MAX },
                flags: hp.flags & !hit_flags::EYE_MET_MOVER,
                ..*hp
            })
            .collect();
        self.backend.write_hit_points(&scratch)?;
        self.backend.update_scene(next)?;
        for path in 0..PROBE_PATHS {
            let params = EyePassParams {
                seed: self.params.seed ^ PROBE_SEED ^ path,
                flags: eye_flags::KEEP_STATISTICS | eye_flags::JITTER | eye_flags::FOCUS,
                rest_at: 1,
                ..self.eye_params(path, true)
            };
            self.backend.eye_pass(&params)?;
        }
        let mut met = vec![false; (self.params.width * self.params.height) as usize];
        for hp in self.backend.read_hit_points()? {
            met[hp.pixel as usize] |= hp.flags & hit_flags::EYE_MET_MOVER != 0;
        }
        self.backend.update_scene(&self.compile(&self.scene))?;
        Ok(met)
    }
}
