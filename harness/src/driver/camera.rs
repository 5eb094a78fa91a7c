//! Camera moves (docs/algorithm.md 3d): the view changes, the light in the scene does not.
//!
//! In local mode each slot of the new view takes over the light of the earlier slots near
//! its visible point where that light does not depend on the direction it is seen from,
//! through the backend's camera-move passes ([`ppm_core::passes::LocalMoves`]); the rest
//! start over and the iterations that follow serve them first. Restart, the thesis's modes,
//! `ppm`'s fixed hit points and a backend without the passes start over.

use super::{MoveReport, Renderer, local, pass_params};
use ppm_core::camera_move::CameraMove;
use ppm_core::compile::gpu_camera;
use ppm_core::layout::eye_flags;
use ppm_core::params::{Estimator, MoveMode};
use ppm_core::passes::BackendError;
use ppm_core::scene::Camera;
use std::time::Instant;

/// Eye and direct-light passes each iteration adds, after a camera move, for the slots that
/// started over: an edge of the new view (a light's outline above all) starts over, and its
/// antialiasing is what its error is made of, which only eye samples reduce; each such pass
/// costs only the slots it serves, a few in a hundred. Six rather than four bring
/// cornell-box and cornell-bunny to restart's 8-s error in about 1.6 s rather than 2.1, and
/// keep a camera step within two iterations on both backends, which eight do not on wgpu
/// (docs/moves.md).
pub const CATCH_UP: u32 = 6;

impl Renderer<'_> {
    /// Moves the camera to `camera` the way `mode` says: local mode keeps the light of what
    /// is still seen, every other mode starts over (the report says why).
    pub fn move_camera(
        &mut self,
        camera: Camera,
        mode: MoveMode,
    ) -> Result<MoveReport, BackendError> {
        let start = Instant::now();
        let mut report = MoveReport::new(mode);
        let why_not = if mode != MoveMode::Local {
            Some(format!("{mode:?} mode keeps nothing of a camera move"))
        } else if self.params.estimator == Estimator::Ppm {
            Some("ppm traces its hit points once per view: a new view starts over".to_owned())
        } else if !self.has_image() {
            Some("no iteration has run: nothing to keep".to_owned())
        } else if self.backend.local_moves().is_none() {
            Some(format!(
                "backend '{}' has no local-move passes",
                self.backend.name()
            ))
        } else {
            None
        };
        let why_not = match why_not {
            Some(why) => Some(why),
            None => self.keep_light(camera.clone(), &mut report)?,
        };
        if let Some(why) = why_not {
            self.look_from(camera)?;
            report.restarted = Some(why);
        }
        report.seconds = start.elapsed().as_secs_f64();
        self.report.times.moves += report.seconds;
        Ok(report)
    }

    /// The camera move's passes: the old view's slots kept, the new camera, a fresh eye pass,
    /// the inheritance and the iteration's direct light. Returns why not, where the backend
    /// refused to begin (nothing changed then).
    fn keep_light(
        &mut self,
        camera: Camera,
        report: &mut MoveReport,
    ) -> Result<Option<String>, BackendError> {
        let (width, height) = (self.params.width, self.params.height);
        let request = CameraMove {
            before: self.compiled.camera,
            after: gpu_camera(&camera, width, height),
            spp: self.params.spp,
        };
        match local(self.backend)?.begin_camera_move(&request) {
            Err(BackendError::Unsupported(why)) => return Ok(Some(why)),
            begun => begun?,
        }
        self.scene.camera = camera;
        self.compiled.camera = request.after;
        local(self.backend)?.update_scene(&self.compiled)?;
        let key = self.counters.iteration;
        self.eye_pass(key, false)?;
        let stats = local(self.backend)?.inherit_light()?;
        self.direct_light(key, true)?;
        self.counters.iteration += 1;
        // The slots that started over hold this one sample: the next iterations serve them
        // first, and catch them up.
        self.counters.steps_since_move = 1;
        self.focus = true;
        // No slot holds more samples than there were eye passes before this one.
        self.catch_up = Some(key);
        self.traced = true;
        report.kept = stats.inherited;
        report.updated = stats.reset;
        Ok(None)
    }
}

impl Renderer<'_> {
    /// [`CATCH_UP`] eye and direct-light passes for the slots with fewer direct samples than
    /// the iterations since the move times `CATCH_UP + 1`; the others rest. Ends the catch-up
    /// once a pass finds no slot behind, or once that many would pass `level`, the samples
    /// a kept slot may hold: the slots that started over are level with the kept ones then,
    /// and every slot gains the same again (else every slot would fall behind the target
    /// that grows as fast as they do, and every iteration would trace them all five times).
    pub(super) fn catch_up(&mut self, level: u32) -> Result<(), BackendError> {
        let target = (self.counters.steps_since_move + 1) * (CATCH_UP + 1);
        if target > level {
            self.catch_up = None;
            return Ok(());
        }
        for _ in 0..CATCH_UP {
            let key = self.counters.iteration;
            let mut params = pass_params::eye_pass(&self.params, self.extent, key, true);
            params.flags |= eye_flags::FOCUS;
            params.rest_at = target;
            if self.run_eye_pass(&params)?.rays == 0 {
                self.catch_up = None;
                return Ok(());
            }
            self.direct_light(key, true)?;
            self.counters.iteration += 1;
        }
        Ok(())
    }
}
