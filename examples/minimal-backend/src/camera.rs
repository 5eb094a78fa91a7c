//! A camera move (docs/algorithm.md 3d), as plainly as the contract allows: the old view's
//! slots kept when it begins, then each slot of the new view, traced fresh, takes over their
//! light with ppm-core's per-slot function.

use crate::{MinimalBackend, loaded};
use ppm_core::camera_move::{CameraMove, CameraMoveStats, inherit_slot, on_an_edge};
use ppm_core::check::check_hit_points;
use ppm_core::layout::{HitPoint, SlotBounds};
use ppm_core::passes::BackendError;

/// A camera move in progress: the cameras and the old view's slots.
pub struct CameraMoving {
    request: CameraMove,
    before: Vec<HitPoint>,
    before_bounds: Vec<SlotBounds>,
    /// An eye pass has started every slot fresh since the move began.
    pub traced: bool,
}

impl MinimalBackend {
    /// [`ppm_core::passes::LocalMoves::begin_camera_move`].
    pub(crate) fn begin_camera(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        loaded(&self.scene, "camera move")?;
        if self.hit_points.is_empty() {
            return Err(BackendError::OutOfOrder {
                pass: "camera move",
                needs: "an eye pass",
            });
        }
        self.moving = None;
        self.camera_moving = Some(CameraMoving {
            request: *request,
            before: self.hit_points.clone(),
            before_bounds: self.slot_bounds.clone(),
            traced: false,
        });
        Ok(())
    }

    /// [`ppm_core::passes::LocalMoves::inherit_light`].
    pub(crate) fn inherit(&mut self) -> Result<CameraMoveStats, BackendError> {
        let scene = loaded(&self.scene, "inherit light")?;
        let moving = self
            .camera_moving
            .take_if(|m| m.traced && m.request.after == scene.camera)
            .ok_or(BackendError::OutOfOrder {
                pass: "inherit light",
                needs: "begin_camera_move, the scene update to the new camera, then an eye \
                        pass that starts the slots fresh",
            })?;
        let before = (moving.before.as_slice(), moving.before_bounds.as_slice());
        // Edges first, over the fresh slots: no slot reads a neighbour that inherited.
        let edges: Vec<bool> = (0..self.hit_points.len())
            .map(|slot| on_an_edge(&self.hit_points, slot, &moving.request, &scene.materials))
            .collect();
        let mut stats = CameraMoveStats::default();
        let slots = self.hit_points.iter_mut().zip(&mut self.slot_bounds);
        for ((hp, bounds), edge) in slots.zip(edges) {
            let took =
                !edge && inherit_slot(hp, Some(bounds), &moving.request, &scene.materials, before);
            stats.inherited += u64::from(took);
            stats.reset += u64::from(!took);
        }
        check_hit_points("inherit light", &self.hit_points)?;
        Ok(stats)
    }
}
