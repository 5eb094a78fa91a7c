//! Local mode (ours; ALGORITHM.md 3b): a move keeps everything it did not change.
//!
//! Every `sppm` iteration flags the slots whose eye paths, and separately whose shadow and
//! cosine rays, crossed a box that holds a moving object in all its poses (the start's
//! [`CompiledScene::movers`](ppm_core::compile::CompiledScene::movers)). A path that crosses
//! no box meets the same surfaces in every pose, so at a move:
//! - a slot whose eye paths crossed a box starts over: what it saw may change (this covers
//!   pixels the object newly covers, and paths through mirrors and glass);
//! - any other slot keeps its visible points, the light it saw directly and its photon
//!   statistics; its direct-light sum restarts only if one of its rays crossed a box;
//! - the kept slots' indirect light is corrected by difference passes: ordinary photons
//!   traced in both poses with the same random numbers, whose deferred net sum is the change
//!   of every photon path the move changed.
//!
//! A move to the same pose resets nothing, and its difference passes cancel.

use super::Renderer;
use super::moves::{Compensation, MoveReport};
use ppm_core::layout::{HitPoint, gather_kind, hit_flags};
use ppm_core::params::Estimator;
use ppm_core::passes::BackendError;
use ppm_core::scene::{MaterialKind, Move, Scene};
use std::time::Instant;

/// Slots a move reset, kept, and kept with their direct sum restarted.
struct Resets {
    reset: u64,
    kept: u64,
    direct_restarted: u64,
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
        Ok(Compensation::Difference)
    }

    /// Moves to `next`: difference passes in pose A, the resets, difference passes in pose
    /// B, their net change applied once to the kept slots.
    pub(super) fn move_locally(
        &mut self,
        next: Scene,
        mut report: MoveReport,
        start: Instant,
    ) -> Result<MoveReport, BackendError> {
        let changed = self.scene.moving_vertices() != next.moving_vertices();
        self.compensate(&Compensation::Difference, gather_kind::REGION_NEGATIVE)?;
        let compiled = self.compile(&next);
        self.backend.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        self.adopt(next, &compiled);
        self.frame += 1;
        let resets = self.reset_near_movers(changed)?;
        report.updated = resets.reset;
        report.kept = resets.kept;
        report.direct_restarted = resets.direct_restarted;
        self.compensate(&Compensation::Difference, gather_kind::REGION_POSITIVE)?;
        self.difference_pass += self.moves.difference_passes;
        if self.moves.difference_passes > 0 {
            self.gather(gather_kind::REGION_APPLY, 0.0, 0.0)?;
        }
        self.guide = None;
        self.steps_since_move = 0;
        report.seconds = start.elapsed().as_secs_f64();
        self.report.times.moves += report.seconds;
        Ok(report)
    }

    /// Starts over the slots whose eye paths crossed a mover's box and restarts the direct
    /// sums of those whose rays did (only when the geometry `changed`); marks the reset slots
    /// `UPDATED`, so the compensation skips them.
    fn reset_near_movers(&mut self, changed: bool) -> Result<Resets, BackendError> {
        let mut slots = self.backend.read_hit_points()?;
        let mut resets = Resets {
            reset: 0,
            kept: 0,
            direct_restarted: 0,
        };
        let r2_initial = self.params.initial_radius * self.params.initial_radius;
        for hp in &mut slots {
            if changed && hp.flags & hit_flags::EYE_NEAR_MOVER != 0 {
                *hp = HitPoint {
                    r2: r2_initial,
                    flags: hit_flags::UPDATED,
                    ..HitPoint::empty(hp.pixel)
                };
                resets.reset += 1;
                continue;
            }
            hp.flags &= !hit_flags::UPDATED;
            if changed && hp.flags & hit_flags::SHADOW_NEAR_MOVER != 0 {
                hp.direct = [0.0; 3];
                hp.iterations = 0;
                hp.flags &= !hit_flags::SHADOW_NEAR_MOVER;
                resets.direct_restarted += 1;
            }
            resets.kept += 1;
        }
        self.backend.write_hit_points(&slots)?;
        Ok(resets)
    }
}
