//! The one driver: every command, report, suite and test renders through it.
//!
//! [`Renderer`] is the only code that knows how passes follow each other: it turns the render
//! settings into each pass's parameter struct in one place (`Renderer::eye_params` and its
//! siblings), runs an iteration of either estimator, and moves the scene with any
//! [`MoveMode`](ppm_core::params::MoveMode) ([`moves`]). Callers describe *what* to run as a
//! [`Schedule`] (render for a budget, move, render again, ...) and watch it through an
//! [`Observer`]; [`run`] executes it ([`schedule`]).
//!
//! An iteration of `sppm` traces a fresh jittered eye sample per slot, adds its direct light
//! to the slot's sum, then traces and gathers one photon pass; `ppm` traces its hit points
//! and direct light once per pose, and an iteration is a photon pass and its gather.

mod camera;
pub mod checkpoint;
mod local;
pub mod moves;
pub mod pass_params;
pub mod schedule;

pub use camera::CATCH_UP;
pub use local::local_move_request;
pub use moves::{MovePart, MoveReport, PhotonCounts};
pub use schedule::{
    Budget, Observer, ObserverResult, Outcome, Progress, Resume, RunError, Schedule, Step,
    Stoppable, run, run_from,
};

use crate::report::{RenderReport, left_out};
use ppm_core::compile::{CompiledScene, compile_scene};
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, GatherParams, GpuLight, GpuMaterial, GuidedEmission,
    PhotonPassParams, RecordedPath, ResolveParams, eye_flags, gather_kind, photon_flags,
};
use ppm_core::params::{Estimator, MoveParams, RenderParams};
use ppm_core::passes::{Backend, BackendError, DynamicBackend, EyeStats, LocalMoves, PhotonStats};
use ppm_core::scene::Scene;
use std::time::Instant;

/// After a local move, one iteration in this many traces eye paths and direct light only for
/// the slots with the fewest iterations (the ones the move reset, until they catch up); the
/// others serve every slot. Every slot gathers every iteration's photons. Focusing every
/// iteration gains nothing right after the move and starves the kept slots of new samples
/// afterwards (docs/algorithm.md 3b). A kept slot's direct-light correction weighs less with
/// each sample of its own; a reset slot converges faster with cheap iterations.
pub const FOCUS_PERIOD: u32 = 2;

/// Which iteration, pass and pose comes next: the keys of every random stream, so that with
/// the slots they are a render's whole state (a checkpoint saves both).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Counters {
    /// Poses loaded or moved to so far: keys `ppm`'s eye and direct passes.
    frame: u32,
    /// `sppm` iterations so far: keys their eye and direct passes.
    iteration: u32,
    /// The slots have not been traced since the last load (`sppm` starts them fresh).
    fresh: bool,
    photon_pass: u32,
    region_pass: u32,
    difference_pass: u32,
    guided_pass: u32,
    steps_since_move: u32,
}

/// A progressive render on one backend, carried across moves.
pub struct Renderer<'a> {
    backend: &'a mut dyn Backend,
    params: RenderParams,
    moves: MoveParams,
    scene: Scene,
    lights: Vec<GpuLight>,
    materials: Vec<GpuMaterial>,
    extent: f32,
    /// The current pose as the backend holds it: a local move uploads it again with the
    /// moved objects' boxes.
    compiled: CompiledScene,
    /// The pose before `compiled`, when `compiled` was refitted from it: its buffers become
    /// the next pose's by rewriting what the two refits changed
    /// ([`recompile_moved`](ppm_core::refit::recompile_moved)).
    spare: Option<CompiledScene>,
    counters: Counters,
    /// Iterations serve the slots with the fewest iterations first (after a local move).
    focus: bool,
    /// After a camera move, each iteration also traces eye paths and direct light again for
    /// the slots that started over ([`camera::CATCH_UP`]), until none is behind or they
    /// would pass this many samples, the most a slot the move kept holds.
    catch_up: Option<u32>,
    /// The slots hold this iteration's visible points and direct light already: a camera
    /// move traced them, and the iteration after it does not trace them again.
    traced: bool,
    /// Ordinary passes ask the backend to keep their paths
    /// ([`photon_flags::KEEP_PATHS`]): set by the first local move, or before it where the
    /// render says it will move ([`Renderer::expect_local_moves`]), so that a render that
    /// never moves records nothing, and the next moves' pose-A corrections are answered from
    /// them.
    keep_paths: bool,
    guide: Option<(GuidedEmission, Vec<RecordedPath>)>,
    /// Photons emitted and deposited so far, per kind.
    pub counts: PhotonCounts,
    report: RenderReport,
}

/// The backend's local-move passes; an error on a backend without them, whose moves restart
/// before any of these is called ([`Renderer::move_to`]).
fn local(backend: &mut dyn Backend) -> Result<&mut dyn LocalMoves, BackendError> {
    let name = backend.name().to_owned();
    backend.local_moves().ok_or_else(|| {
        BackendError::Unsupported(format!("backend '{name}' has no local-move passes"))
    })
}

/// The backend's passes of the thesis's modes; an error on a backend without them, whose
/// moves in those modes restart before any of these is called ([`Renderer::move_to`]).
fn dynamic(backend: &mut dyn Backend) -> Result<&mut dyn DynamicBackend, BackendError> {
    let name = backend.name().to_owned();
    backend
        .dynamic()
        .ok_or_else(|| BackendError::Unsupported(format!("backend '{name}' has no dynamic passes")))
}

impl<'a> Renderer<'a> {
    /// Loads `scene` (already posed) on `backend`; `ppm` also traces its hit points and
    /// direct light here.
    pub fn start(
        backend: &'a mut dyn Backend,
        scene: Scene,
        params: &RenderParams,
        moves: &MoveParams,
    ) -> Result<Self, BackendError> {
        let compiled = compile_scene(&scene, params.width, params.height);
        let mut report = RenderReport::new(backend.name(), &scene, params, &compiled);
        report.left_out = left_out(&compiled.features, params, false);
        let mut r = Self {
            backend,
            params: params.clone(),
            moves: moves.clone(),
            scene,
            lights: compiled.lights.clone(),
            materials: compiled.materials.clone(),
            extent: compiled.extent,
            compiled,
            spare: None,
            counters: Counters {
                fresh: true,
                ..Counters::default()
            },
            focus: false,
            catch_up: None,
            traced: false,
            keep_paths: false,
            guide: None,
            counts: PhotonCounts::default(),
            report,
        };
        r.start_over()?;
        Ok(r)
    }

    /// Starts over on `scene`: its buffers, fresh slots, and for `ppm` the eye pass and
    /// direct light.
    fn load(&mut self, scene: Scene, compiled: CompiledScene) -> Result<(), BackendError> {
        self.adopt(scene, compiled);
        self.start_over()
    }

    /// Uploads the current pose with fresh slots, and for `ppm` traces the eye pass and
    /// direct light.
    fn start_over(&mut self) -> Result<(), BackendError> {
        let t = Instant::now();
        self.backend.load_scene(&self.compiled)?;
        self.report.times.upload += t.elapsed().as_secs_f64();
        self.report.times.bvh_build += self.compiled.bvh_build_time.as_secs_f64();
        self.guide = None;
        self.focus = false;
        self.catch_up = None;
        self.traced = false;
        self.counters.fresh = true;
        if self.params.estimator == Estimator::Ppm {
            self.eye_pass(self.counters.frame, false)?;
            self.direct_light(self.counters.frame, false)?;
        }
        Ok(())
    }

    /// Flattens `scene`, a pose of this render's scene.
    fn compile(&self, scene: &Scene) -> CompiledScene {
        compile_scene(scene, self.params.width, self.params.height)
    }

    /// Takes `scene` and its flattened form (which the backend now holds) as the pose.
    fn adopt(&mut self, scene: Scene, compiled: CompiledScene) {
        self.scene = scene;
        self.lights = compiled.lights.clone();
        self.materials = compiled.materials.clone();
        self.extent = compiled.extent;
        let refitted_from = compiled.refit_from.as_ref().map(|w| w.pose);
        let before = std::mem::replace(&mut self.compiled, compiled);
        self.spare = Some(before).filter(|b| refitted_from == Some(b.pose));
    }

    /// One iteration: for `sppm` an eye pass and direct light (where a camera move has not
    /// just traced them), then for both estimators one photon pass and its gather (after a
    /// move, guided and ordinary passes alternate while there are recorded paths).
    pub fn iteration(&mut self) -> Result<(), BackendError> {
        if self.params.estimator == Estimator::Sppm {
            if !std::mem::take(&mut self.traced) {
                let key = self.counters.iteration;
                self.eye_pass(key, !self.counters.fresh)?;
                self.direct_light(key, true)?;
                self.counters.iteration += 1;
                self.counters.fresh = false;
            }
            if let Some(level) = self.catch_up {
                self.catch_up(level)?;
            }
        }
        let guided_turn = self.counters.steps_since_move.is_multiple_of(2);
        self.counters.steps_since_move += 1;
        match &self.guide {
            Some((guide, paths)) if guided_turn => {
                let (guide, paths) = (*guide, paths.clone());
                let n = self.params.photons_per_pass;
                let kind = gather_kind::GUIDED;
                let params = self.photon_params(self.counters.guided_pass, n, 1.0, kind);
                let t = Instant::now();
                let source = PhotonSource::Guided {
                    guide,
                    paths: &paths,
                };
                let stats = self.backend.photon_pass(&params, &source)?;
                self.count_photons(&stats, t);
                self.counters.guided_pass += 1;
                self.counts.guided.add(&stats);
                self.gather(kind, n as f32, 0.0)?;
            }
            _ => self.ordinary_pass()?,
        }
        self.report.passes += 1;
        self.collect_device_times()
    }

    /// Adds what the backend's device measured since the last call (a move's passes, then an
    /// iteration's) to the report; nothing where it measures nothing.
    fn collect_device_times(&mut self) -> Result<(), BackendError> {
        if let Some(times) = self.backend.device_times()? {
            let total = self.report.device_times.get_or_insert_default();
            ppm_core::device_time::add(total, &times);
        }
        Ok(())
    }

    /// One ordinary photon pass, gathered by every slot.
    fn ordinary_pass(&mut self) -> Result<(), BackendError> {
        let n = self.params.photons_per_pass;
        let kind = gather_kind::ORDINARY;
        let mut params = self.photon_params(self.counters.photon_pass, n, 1.0, kind);
        if self.keep_paths {
            params.flags |= photon_flags::KEEP_PATHS;
        }
        let t = Instant::now();
        let stats = self.backend.photon_pass(&params, &PhotonSource::Lights)?;
        self.count_photons(&stats, t);
        self.counters.photon_pass += 1;
        self.counts.ordinary.add(&stats);
        self.gather(kind, n as f32, 0.0)
    }

    /// The image of the current statistics (black before `sppm`'s first iteration, which has
    /// traced no slot yet).
    pub fn resolve(&mut self) -> Result<Image, BackendError> {
        if !self.has_image() {
            return Ok(Image::new(self.params.width, self.params.height));
        }
        let t = Instant::now();
        let image = self.backend.resolve(&self.resolve_params())?;
        self.report.times.resolve += t.elapsed().as_secs_f64();
        self.collect_device_times()?;
        Ok(image)
    }

    /// The backend, for read-back between passes.
    pub fn backend(&mut self) -> &mut dyn Backend {
        self.backend
    }

    /// The render's settings.
    pub fn params(&self) -> &RenderParams {
        &self.params
    }

    /// The current pose.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// What [`Renderer::resolve`] asks the backend for.
    pub fn resolve_params(&self) -> ResolveParams {
        ResolveParams {
            width: self.params.width,
            height: self.params.height,
            spp: self.params.spp,
            _pad0: 0,
        }
    }

    /// Whether the slots hold statistics to show (`sppm` has none before its first
    /// iteration after a load).
    pub fn has_image(&self) -> bool {
        !(self.counters.fresh && self.params.estimator == Estimator::Sppm)
    }

    /// Starts over from `camera`: every slot sees something else, so nothing is kept.
    pub fn look_from(&mut self, camera: ppm_core::scene::Camera) -> Result<(), BackendError> {
        let mut scene = self.scene.clone();
        scene.camera = camera;
        self.counters.frame += 1;
        let compiled = self.compile(&scene);
        self.load(scene, compiled)
    }

    /// Changes the photons of each later pass and the fraction `alpha` each later gather
    /// keeps, between iterations: the statistics gathered so far stay valid, since every
    /// gather normalises by the photons it counted. Refused (nothing changed) when the
    /// settings would not validate, with the field named.
    pub fn retune(&mut self, photons_per_pass: u32, alpha: f32) -> Result<(), BackendError> {
        let mut next = self.params.clone();
        next.photons_per_pass = photons_per_pass;
        next.alpha = alpha;
        next.validate("retune")
            .map_err(|e| BackendError::Unsupported(e.to_string()))?;
        self.params = next;
        Ok(())
    }

    /// What ran so far: counters and time per pass kind (on the device up to the last
    /// iteration or resolve).
    pub fn report(&self) -> &RenderReport {
        &self.report
    }

    /// The report as a finished render writes it: what ran, and `left_out` saying what the
    /// scene and the settings did not need (the compensation passes too unless `moving`) and
    /// what the backend never created.
    pub fn final_report(&mut self, moving: bool) -> RenderReport {
        let mut report = self.report.clone();
        report.left_out = left_out(&report.features, &self.params, moving);
        report.left_out.extend(self.backend.not_created());
        report
    }

    /// The eye pass keyed by `key` ([`pass_params::eye_pass`]), and after a local move the
    /// focus on the slots with the fewest iterations.
    fn eye_params(&self, key: u32, keep: bool) -> EyePassParams {
        let mut params = pass_params::eye_pass(&self.params, self.extent, key, keep);
        // After a local move the reset slots hold `steps_since_move` iterations: every other
        // iteration, the slots that hold more rest, until those catch up.
        if self.focus && keep && self.counters.steps_since_move.is_multiple_of(FOCUS_PERIOD) {
            params.flags |= eye_flags::FOCUS;
            params.rest_at = self.counters.steps_since_move + 1;
        }
        params
    }

    fn eye_pass(&mut self, key: u32, keep: bool) -> Result<(), BackendError> {
        self.run_eye_pass(&self.eye_params(key, keep)).map(|_| ())
    }

    /// Runs an eye pass and counts its time and rays.
    fn run_eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError> {
        let t = Instant::now();
        let stats = self.backend.eye_pass(params)?;
        self.report.times.eye += t.elapsed().as_secs_f64();
        self.report.rays.eye += stats.rays;
        self.report.hit_points = stats.hit_points;
        Ok(stats)
    }

    fn direct_params(&self, key: u32, accumulate: bool) -> DirectLightParams {
        pass_params::direct_light(&self.params, self.extent, key, accumulate)
    }

    fn direct_light(&mut self, key: u32, accumulate: bool) -> Result<(), BackendError> {
        self.run_direct_light(&self.direct_params(key, accumulate))
    }

    /// Runs a direct-light pass and counts its time and rays.
    fn run_direct_light(&mut self, params: &DirectLightParams) -> Result<(), BackendError> {
        let t = Instant::now();
        let stats = self.backend.direct_light(params)?;
        self.report.times.direct += t.elapsed().as_secs_f64();
        self.report.rays.shadow += stats.rays;
        Ok(())
    }

    fn photon_params(
        &self,
        pass_index: u32,
        photon_count: u32,
        power_scale: f32,
        gather_kind: u32,
    ) -> PhotonPassParams {
        pass_params::photon_pass(
            &self.params,
            self.extent,
            pass_index,
            photon_count,
            power_scale,
            gather_kind,
        )
    }

    fn count_photons(&mut self, stats: &PhotonStats, started: Instant) {
        self.report.times.photon += started.elapsed().as_secs_f64();
        self.report.photons_emitted += stats.emitted;
        self.report.photons_deposited += stats.deposited;
        self.report.rays.photon += stats.rays;
    }

    fn gather(
        &mut self,
        kind: u32,
        emitted_increment: f32,
        region_photons: f32,
    ) -> Result<(), BackendError> {
        let t = Instant::now();
        let stats = self.backend.gather_pass(&GatherParams {
            alpha: self.params.alpha,
            emitted_increment,
            kind,
            region_photons,
        })?;
        self.report.times.gather += t.elapsed().as_secs_f64();
        self.report.photons_gathered += stats.photons_gathered;
        Ok(())
    }
}
