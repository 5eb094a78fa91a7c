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
//!   [`PROBE_PATHS`](ppm_core::local_move::PROBE_PATHS) eye paths traced in pose B through
//!   stratified random points of the pixel meets a moved object;
//! - any other slot keeps its visible points, the light it saw directly and its photon
//!   statistics. Its direct light can change only through shadow or cosine rays from its
//!   visible points, or light samples from its paths' glossy bounces, to a light that cross
//!   a moved object's box in either pose: all start inside the slot's box, so where a
//!   segment from its box to a light's box may cross one, its direct sum is corrected by the
//!   change over its pixel that paired eye paths and light samples estimate in both poses
//!   (an unbiased estimate, exactly zero where the move blocks or frees none of the rays);
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
//! The decisions and the direct-light change are the backend's passes, run where its slots
//! live ([`LocalMoves::begin_local_move`], `local_resets`, `local_direct_change`, over
//! [`ppm_core::local_move`]'s per-slot functions); this module sizes the move and orders the
//! passes, and reads back their counters, never the slots.
//!
//! [`LocalMoves::begin_local_move`]: ppm_core::passes::LocalMoves::begin_local_move
//!
//! Then every second iteration ([`FOCUS_PERIOD`](super::FOCUS_PERIOD)) traces eye paths and
//! direct light only for the slots with the fewest iterations: a slot whose direct sum holds
//! more iterations than the slots the move reset rests (`hit_flags::RESTING`), until they
//! catch up. Its last visible point still gathers the iteration's photons, traced anyway.
//!
//! [`MoveParams::correction_radii`]: ppm_core::params::MoveParams::correction_radii

use super::moves::{Laps, MoveReport};
use super::{Renderer, local, pass_params};
use glam::Vec3;
use ppm_core::compile::{CompiledScene, object_group, widened_boxes};
use ppm_core::eye_path::EyePathSettings;
use ppm_core::layout::GpuLight;
use ppm_core::layout::gather_kind;
use ppm_core::local_move::{
    CorrectionApply, CorrectionPhotons, LocalMove, Pose, direct_samples_for,
};
use ppm_core::params::{Estimator, RenderParams};
use ppm_core::passes::{BackendError, PhotonStats};
use ppm_core::reach::Aabb;
use ppm_core::refit::recompile_moved;
use ppm_core::rng::DIFFERENCE_PASS_BASE;
use ppm_core::scene::{MaterialKind, Scene};
use std::time::Instant;

/// The widest correction disc, in radii of the pass's floor, for a correction of two passes'
/// worth or more; one of `P < 2` passes' worth widens to `P` floors at most. A disc's cost
/// grows with its area, and a drag step's one-pass correction does not widen: there it cost
/// a step a large share of an iteration (docs/algorithm.md 3b).
const CORRECTION_WIDEST: f32 = 2.0;

/// Lights up to which the direct-light test takes each emitting triangle's box; beyond, the
/// box around all of them.
const LIGHT_BOXES: usize = 16;

/// What local mode's correction of a move is made of ([`Renderer::local_correction`]).
struct CorrectionSize {
    /// Whole passes' worth of photons: the pass counter advances by as many.
    passes: u32,
    /// The photons of the one pass per pose that corrects the indirect light.
    photons: u32,
    /// Their squared floor radius.
    r2_floor: f32,
    /// The widest a kept slot's disc grows far from the move, in floor radii
    /// ([`correction_r2`](ppm_core::local_move::correction_r2)).
    widest: f32,
    /// Paired direct-light samples per corrected slot.
    direct_samples: u32,
}

impl Renderer<'_> {
    /// Says that this render will move in local mode (`ppm view`, a schedule with local
    /// moves): ordinary passes keep their paths from now on, so that even the first move's
    /// pose A is answered from them, and the backend prepares what moves need
    /// ([`LocalMoves::prepare_moves`]), so that the first move costs what the later ones do.
    /// Nothing on a backend without local moves, whose moves restart.
    ///
    /// [`LocalMoves::prepare_moves`]: ppm_core::passes::LocalMoves::prepare_moves
    pub fn expect_local_moves(&mut self) -> Result<(), BackendError> {
        let Some(moves) = self.backend.local_moves() else {
            return Ok(());
        };
        moves.prepare_moves()?;
        self.keep_paths = true;
        Ok(())
    }

    /// Why local mode cannot keep anything for a move of `changed` objects, if it cannot.
    pub(super) fn local_plan(&self, changed: &[usize]) -> Result<(), String> {
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
        Ok(())
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
            photons,
            r2_floor,
            widest: CORRECTION_WIDEST.min(share),
            direct_samples: direct_samples_for(share),
        }
    }

    /// Moves the `changed` objects to their pose in `next`: the backend's passes of the move
    /// in pose A (each slot's correction disc, what its direct light may see change), the
    /// correction's pose-A photons, the scene update, the resets and the direct-light change
    /// in pose B, then pose B's photons and the net correction applied once to the kept slots.
    pub(super) fn move_locally(
        &mut self,
        next: Scene,
        changed: &[usize],
        mut report: MoveReport,
        start: Instant,
    ) -> Result<MoveReport, BackendError> {
        let mut laps = Laps::from(start);
        // From now on ordinary passes keep their paths for the next move's pose A.
        self.keep_paths = true;
        // The passes of both poses test the moved objects' boxes in both poses: a path is the
        // same in A and B until it crosses one.
        // Pose A's tree refitted to pose B, rebuilt only once it has grown (ppm_core::refit).
        let mut compiled = recompile_moved(&self.compiled, &next, changed, self.spare.take());
        laps.lap("refit");
        let size = self.local_correction();
        let request = self.local_move(&compiled, changed, &size);
        let boxes = request.before.iter().chain(&request.after);
        let movers = widened_boxes(boxes.map(|b| (b.lo, b.hi)), self.extent);
        compiled.movers = movers.clone();
        self.compiled.movers = movers;
        laps.lap("request");
        // Deposits per photon of the passes so far (counters a caller may reset aside).
        let per_photon =
            self.report.photons_deposited as f64 / self.report.photons_emitted.max(1) as f64;
        let stored_before = self.counts.compensation.deposited + self.counts.region.deposited;
        let emitted_before = self.counts.compensation.emitted + self.counts.region.emitted;
        local(self.backend)?.update_scene(&self.compiled)?;
        local(self.backend)?.begin_local_move(&request)?;
        laps.lap("begin");
        // One pass per pose; a drag step's draws the numbers of the ordinary pass just traced.
        let pass_index = self
            .reused_pass(size.photons, 1)
            .unwrap_or(DIFFERENCE_PASS_BASE + self.counters.difference_pass);
        let correction = |pose| CorrectionPhotons {
            pose,
            pass: self.photon_params(pass_index, size.photons, 1.0, gather_kind::ORDINARY),
            r2_floor: size.r2_floor,
            pair_deposits: self.moves.pair_deposits,
            cull_uncrossed: self.moves.cull_uncrossed,
        };
        let (before, after) = (correction(Pose::A), correction(Pose::B));
        if size.photons > 0 {
            let stats = self.correction_photons(&before)?;
            self.counts.compensation.add(&stats);
        }
        laps.lap("pose A photons");
        local(self.backend)?.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        self.adopt(next, compiled);
        self.counters.frame += 1;
        laps.lap("update");
        let resets = local(self.backend)?.local_resets()?;
        laps.lap("resets");
        local(self.backend)?.local_direct_change()?;
        laps.lap("direct change");
        report.updated = resets.reset;
        report.kept = resets.kept;
        report.direct_corrected = resets.direct_corrected;
        if size.photons > 0 {
            let positive = self.correction_photons(&after)?;
            laps.lap("pose B photons");
            self.counts.region.add(&positive);
            if positive.emitted > 0 {
                report.culled_share = Some(positive.culled as f64 / positive.emitted as f64);
            }
            let t = Instant::now();
            let apply = CorrectionApply {
                alpha: self.params.alpha,
                photons: size.photons,
            };
            let stats = local(self.backend)?.apply_correction(&apply)?;
            self.report.times.gather += t.elapsed().as_secs_f64();
            self.report.photons_gathered += stats.photons_gathered;
            laps.lap("apply");
        }
        self.counters.difference_pass += size.passes;
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
        report.parts = laps.parts;
        self.report.times.moves += report.seconds;
        Ok(report)
    }

    /// One pose's photons of a local move's correction, counted as photon passes are.
    fn correction_photons(
        &mut self,
        request: &CorrectionPhotons,
    ) -> Result<PhotonStats, BackendError> {
        let t = Instant::now();
        let stats = local(self.backend)?.correction_photons(request)?;
        self.count_photons(&stats, t);
        Ok(stats)
    }

    /// The move of the `changed` objects to their pose `next` as the backend's passes see
    /// it, sized as `size` says.
    fn local_move(
        &self,
        next: &CompiledScene,
        changed: &[usize],
        size: &CorrectionSize,
    ) -> LocalMove {
        let correction = (size.r2_floor, size.widest, size.direct_samples);
        local_move_request((&self.compiled, next), changed, &self.params, correction)
    }
}

/// The local move of the `changed` objects from pose `before` to pose `after`, rendered with
/// `params`, its correction's floor, widest disc and direct-light pairs `correction`: what
/// every pass of it needs
/// ([`LocalMoves::begin_local_move`](ppm_core::passes::LocalMoves::begin_local_move)).
pub fn local_move_request(
    (before, after): (&CompiledScene, &CompiledScene),
    changed: &[usize],
    params: &RenderParams,
    (r2_floor, widest, direct_samples): (f32, f32, u32),
) -> LocalMove {
    let aabb = |pose: &CompiledScene, o: usize| {
        let [lo, hi] = pose.object_bounds[o];
        Aabb::new(lo, hi)
    };
    LocalMove {
        objects: changed.iter().map(|&o| o as u32).collect(),
        groups: changed.iter().fold(0, |g, &o| g | object_group(o)),
        before: changed.iter().map(|&o| aabb(before, o)).collect(),
        after: changed.iter().map(|&o| aabb(after, o)).collect(),
        lights: light_boxes(&before.lights),
        seed: params.seed,
        paths: EyePathSettings {
            max_depth: params.max_eye_depth,
            ray_epsilon: pass_params::ray_epsilon(params, before.extent),
            sample_lights: false,
        },
        r2_initial: params.initial_radius * params.initial_radius,
        r2_floor,
        widest,
        direct_samples,
    }
}

/// The boxes the direct-light test reaches for: each light's (a box inside another counted
/// once: a quad's two triangles share theirs), or one around all of them.
fn light_boxes(lights: &[GpuLight]) -> Vec<Aabb> {
    let mut boxes: Vec<Aabb> = Vec::new();
    for l in lights {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Each local move after the first writes its pose into the buffers of the pose before
    /// last (nothing else holds them once the backend's move has ended); a restart drops it.
    #[test]
    fn a_drag_writes_each_pose_into_the_buffers_of_the_pose_before_last() {
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
        let mut lent = 0;
        for _ in 0..3 {
            r.iteration().unwrap();
            let spare = r.spare.as_ref().map(|s| s.triangles.as_ptr());
            r.move_objects(&[step], MoveMode::Local).unwrap();
            lent += usize::from(spare == Some(r.compiled.triangles.as_ptr()));
        }
        assert_eq!(
            lent, 2,
            "the second and third moves reuse the pose before last"
        );
        r.move_objects(&[step], MoveMode::Restart).unwrap();
        assert!(r.spare.is_none());
    }
}
