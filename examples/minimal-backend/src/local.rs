//! A local move (docs/algorithm.md 3b and 3c), as plainly as the contract allows: each pass
//! runs ppm-core's per-slot function over every slot in turn, pose A kept beside pose B for the
//! direct-light change, and the correction's photons traced as an ordinary pass's are, pose A's
//! held until pose B's join them.

use crate::{Map, MinimalBackend, fold, loaded, trace_photons};
use glam::Vec3;
use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::check::check_hit_points;
use ppm_core::compile::CompiledScene;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{Photon, SlotBounds, hit_flags};
use ppm_core::local_move::{
    CorrectionApply, CorrectionPhotons, LocalMove, Pose, View, correct_direct, moved_cover,
    prepare_slot, reset_if_seen,
};
use ppm_core::passes::{BackendError, GatherStats, LocalMoveStats, LocalMoves, PhotonStats};
use ppm_core::reach::Aabb;
use ppm_core::trace::FlatPose;
use ppm_core::update::pairing::{Partner, pose_a_partners};

/// A local move in progress.
pub struct Moving {
    /// What moves.
    request: LocalMove,
    /// Pose A, as the move began in it.
    before: CompiledScene,
    /// Where the move stands.
    stage: Stage,
}

/// A local move's correction photons: pose A's held until pose B's join them, then both,
/// pose B's paired with pose A's, until the apply folds them in.
pub enum Correction {
    /// Pose A's.
    Held(Vec<Photon>),
    /// Both poses', each deposit's pose-A partner, and the floor of the correction's disc.
    Joined(Vec<Photon>, Vec<Option<Partner>>, f32),
}

/// The passes of a local move over the slots, in their order (the correction's photons come
/// between them, [`Correction`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Begun in pose A: the update to pose B next.
    Begun,
    /// In pose B: the resets.
    PoseB,
    /// Reset: the direct-light change.
    Reset,
}

/// A slot's recorded box, or every point where none was recorded.
fn slot_box(bounds: &[SlotBounds], i: usize) -> Aabb {
    bounds.get(i).map_or(Aabb::new(Vec3::MIN, Vec3::MAX), |b| {
        Aabb::new(b.min.into(), b.max.into())
    })
}

impl MinimalBackend {
    /// The move in progress at `stage`, or the error that names `pass` and what it needs.
    fn moving_at(
        &mut self,
        stage: Stage,
        pass: &'static str,
        needs: &'static str,
    ) -> Result<&mut Moving, BackendError> {
        self.moving
            .as_mut()
            .filter(|m| m.stage == stage)
            .ok_or(BackendError::OutOfOrder { pass, needs })
    }
}

impl LocalMoves for MinimalBackend {
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.scene = Some(scene.clone());
        // A move begun in pose A goes on in this pose, its pose B.
        if let Some(m) = self.moving.as_mut().filter(|m| m.stage == Stage::Begun) {
            m.stage = Stage::PoseB;
        }
        Ok(())
    }

    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        let before = loaded(&self.scene, "local move")?.clone();
        if self.hit_points.is_empty() {
            return Err(BackendError::OutOfOrder {
                pass: "local move",
                needs: "an eye pass",
            });
        }
        let moved = request.moved();
        for (i, hp) in self.hit_points.iter_mut().enumerate() {
            prepare_slot(hp, &slot_box(&self.slot_bounds, i), request, &moved);
        }
        self.moving = Some(Moving {
            request: request.clone(),
            before,
            stage: Stage::Begun,
        });
        Ok(())
    }

    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        let needs = "a local move begun, then the scene updated to pose B";
        let request = self
            .moving_at(Stage::PoseB, "local resets", needs)?
            .request
            .clone();
        let after = loaded(&self.scene, "local resets")?;
        let (pose, camera) = (FlatPose::new(after), &after.camera);
        let covered = moved_cover(&pose, camera, &request.objects);
        let nearest = request.nearest_after(camera.eye.into());
        let mut stats = LocalMoveStats::default();
        for (i, hp) in self.hit_points.iter_mut().enumerate() {
            let bounds = slot_box(&self.slot_bounds, i);
            let covered = covered[hp.pixel as usize];
            let poses = (&pose, camera, nearest);
            let (view, reset) = reset_if_seen(hp, &bounds, covered, poses, &request);
            stats.reset += u64::from(reset);
            stats.probed += u64::from(view == View::Probe);
            stats.direct_corrected +=
                u64::from(!reset && hp.flags & hit_flags::DIRECT_MAY_CHANGE != 0);
        }
        stats.kept = self.hit_points.len() as u64 - stats.reset;
        self.moving_at(Stage::PoseB, "local resets", needs)?.stage = Stage::Reset;
        check_hit_points("local resets", &self.hit_points)?;
        Ok(stats)
    }

    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        let needs = "the local resets";
        let moving =
            self.moving
                .take_if(|m| m.stage == Stage::Reset)
                .ok_or(BackendError::OutOfOrder {
                    pass: "local direct change",
                    needs,
                })?;
        let after = self.scene.as_ref().expect("a move runs on a loaded scene");
        let (a, b) = (FlatPose::new(&moving.before), FlatPose::new(after));
        let moved = moving.request.moved();
        let mut stats = LocalMoveStats::default();
        for (slot, hp) in self.hit_points.iter_mut().enumerate() {
            let poses = (&a, &b, &after.camera);
            let changed = correct_direct(hp, slot as u32, poses, (&moving.request, &moved), None);
            stats.direct_corrected += u64::from(changed.is_some());
        }
        check_hit_points("local direct change", &self.hit_points)?;
        Ok(stats)
    }

    fn correction_photons(
        &mut self,
        request: &CorrectionPhotons,
    ) -> Result<PhotonStats, BackendError> {
        let held = match (request.pose, self.correction.take()) {
            (Pose::A, _) => None,
            (Pose::B, Some(Correction::Held(held))) => Some(held),
            (Pose::B, _) => {
                return Err(BackendError::OutOfOrder {
                    pass: "correction photons in pose B",
                    needs: "pose A's correction photons",
                });
            }
        };
        // Every path is traced: culling the ones that crossed no moved box would store the
        // same deposits (none of theirs) in less time.
        let scene = loaded(&self.scene, "correction photons")?;
        let pass = request.flagged_pass();
        let (photons, stats) = trace_photons(scene, &pass, &PhotonSource::Lights)?;
        // What reads back as the last pass's deposits; no ordinary gather may take them.
        self.photons.clone_from(&photons);
        self.map_kind = Some(pass.gather_kind);
        self.correction = Some(match held {
            None => Correction::Held(photons),
            Some(held) => {
                let mut partners = vec![None; held.len()];
                match request.pair_deposits {
                    true => partners.extend(pose_a_partners(&held, &photons)),
                    false => partners.resize(held.len() + photons.len(), None),
                }
                let both = held.into_iter().chain(photons).collect();
                Correction::Joined(both, partners, request.r2_floor)
            }
        });
        Ok(stats)
    }

    fn apply_correction(&mut self, request: &CorrectionApply) -> Result<GatherStats, BackendError> {
        let Some(Correction::Joined(photons, partners, r2_floor)) = self.correction.take() else {
            return Err(BackendError::OutOfOrder {
                pass: "apply correction",
                needs: "both poses' correction photons",
            });
        };
        let materials = &loaded(&self.scene, "apply correction")?.materials;
        let map = Map {
            photons: &photons,
            partners: &partners,
            r2_floor,
        };
        let [gather, apply] = request.gathers();
        let slots = (&mut self.hit_points[..], &mut self.pending[..]);
        let stats = fold(&gather, slots, (materials, self.r2_initial), &map);
        let nothing = Map {
            photons: &[],
            partners: &[],
            r2_floor: 0.0,
        };
        let slots = (&mut self.hit_points[..], &mut self.pending[..]);
        fold(&apply, slots, (materials, self.r2_initial), &nothing);
        check_hit_points("apply correction", &self.hit_points)?;
        Ok(stats)
    }

    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        self.begin_camera(request)
    }

    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError> {
        self.inherit()
    }
}
