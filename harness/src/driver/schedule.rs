//! Schedules: what a render does, as data. A schedule starts from one pose of the scene and
//! runs steps in order (render for a budget, move to another pose); [`run`] executes it on the
//! [`Renderer`] and calls an [`Observer`] after each iteration, move and step, with the time
//! the observer takes not counted as rendering. An observer can also end the run early
//! ([`Observer::stop_requested`]: a Ctrl-C), which keeps every iteration completed.

use super::{MoveReport, PhotonCounts, Renderer};
use crate::clock::Stopwatch;
use crate::report::RenderReport;
use ppm_core::image::Image;
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::{Backend, BackendError};
use ppm_core::scene::path::{After, CameraStep, MovePath};
use ppm_core::scene::{Move, Scene};
use std::time::Instant;
use thiserror::Error;

/// How long a render step runs: until either limit is reached (none: no iteration).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Budget {
    /// Iterations.
    pub iterations: Option<u32>,
    /// Seconds of rendering.
    pub seconds: Option<f64>,
}

impl Budget {
    /// Exactly `n` iterations.
    pub fn iterations(n: u32) -> Self {
        Self {
            iterations: Some(n),
            seconds: None,
        }
    }

    /// Iterations for `s` seconds of rendering.
    pub fn seconds(s: f64) -> Self {
        Self {
            iterations: None,
            seconds: Some(s),
        }
    }

    fn spent(&self, iterations: u32, seconds: f64) -> bool {
        let by_count = self.iterations.is_some_and(|n| iterations >= n);
        let by_time = self.seconds.is_some_and(|s| seconds >= s);
        by_count || by_time || (self.iterations.is_none() && self.seconds.is_none())
    }
}

/// One step of a schedule.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Iterate until the budget is spent.
    Render(Budget),
    /// Move to the pose a fraction `time` of the way through the scene's moves (0 is frame
    /// 0, 1 is frame 1), the way `mode` says.
    Move {
        /// Where the scene's moves stand after this step.
        time: f32,
        /// How the render follows.
        mode: MoveMode,
    },
    /// Move objects of the pose that stands then, rigidly, all at once: moves nobody
    /// declared in the scene (a path's event).
    MoveObjects {
        /// The moves, applied in order.
        moves: Vec<Move>,
        /// How the render follows.
        mode: MoveMode,
    },
    /// Put the camera elsewhere (a path's event): local mode keeps the light of what is
    /// still seen ([`Renderer::move_camera`]).
    MoveCamera {
        /// Where it goes.
        camera: CameraStep,
        /// How the render follows.
        mode: MoveMode,
    },
}

impl Step {
    /// How the render follows the step, if it moves.
    fn mode(&self) -> Option<MoveMode> {
        match self {
            Step::Render(_) => None,
            Step::Move { mode, .. }
            | Step::MoveObjects { mode, .. }
            | Step::MoveCamera { mode, .. } => Some(*mode),
        }
    }
}

/// A render described as data: the starting pose and the steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// The pose the render starts in (see [`Step::Move`]).
    pub start: f32,
    /// Steps, in order.
    pub steps: Vec<Step>,
}

impl Schedule {
    /// One frame (0 or 1) rendered for `budget`.
    pub fn frame(frame: u32, budget: Budget) -> Self {
        Self {
            start: if frame >= 1 { 1.0 } else { 0.0 },
            steps: vec![Step::Render(budget)],
        }
    }

    /// Frame 0 for `warmup`, the move to frame 1 with `mode`, then `after`. Restart starts
    /// on frame 1 directly: it keeps nothing from the warm-up.
    pub fn after_move(warmup: Budget, mode: MoveMode, after: Budget) -> Self {
        if mode == MoveMode::Restart {
            return Self::frame(1, after);
        }
        Self {
            start: 0.0,
            steps: vec![
                Step::Render(warmup),
                Step::Move { time: 1.0, mode },
                Step::Render(after),
            ],
        }
    }

    /// The scene's moves cut into `steps` equal steps, each followed by `per_frame`, after
    /// frame 0 rendered for `per_frame`.
    pub fn animation(steps: u32, mode: MoveMode, per_frame: Budget) -> Self {
        let mut s = vec![Step::Render(per_frame)];
        for k in 1..=steps {
            s.push(Step::Move {
                time: k as f32 / steps as f32,
                mode,
            });
            s.push(Step::Render(per_frame));
        }
        Self {
            start: 0.0,
            steps: s,
        }
    }
}

impl Schedule {
    /// Frame 0, then each event of `path` after its rendering time, the way `mode` says
    /// (restart starts over at each), then `after`.
    pub fn path(path: &MovePath, mode: MoveMode, after: Budget) -> Self {
        let mut steps = Vec::new();
        for event in &path.events {
            steps.push(Step::Render(match event.after {
                After::Seconds(s) => Budget::seconds(s),
                After::Iterations(n) => Budget::iterations(n),
            }));
            if !event.moves.is_empty() {
                steps.push(Step::MoveObjects {
                    moves: event.moves.clone(),
                    mode,
                });
            }
            if let Some(camera) = event.camera {
                steps.push(Step::MoveCamera { camera, mode });
            }
        }
        steps.push(Step::Render(after));
        Self { start: 0.0, steps }
    }

    /// Whether a step moves the scene.
    pub fn moves(&self) -> bool {
        self.steps.iter().any(|s| !matches!(s, Step::Render(_)))
    }
}

/// Where a run stands.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Index of the current step.
    pub step: usize,
    /// Iterations in the current step.
    pub step_iterations: u32,
    /// Seconds of rendering in the current step.
    pub step_seconds: f64,
    /// Iterations since the start.
    pub iterations: u32,
    /// Seconds of rendering since the start (observers not counted).
    pub seconds: f64,
}

/// What an observer returns: an error stops the run.
pub type ObserverResult = Result<(), Box<dyn std::error::Error + Send + Sync>>;

/// Watches a run: reads buffers, measures, writes frames. Every method defaults to nothing.
pub trait Observer {
    /// After each iteration.
    fn iteration(&mut self, _at: &Progress, _renderer: &mut Renderer) -> ObserverResult {
        Ok(())
    }

    /// After each move.
    fn moved(
        &mut self,
        _at: &Progress,
        _m: &MoveReport,
        _renderer: &mut Renderer,
    ) -> ObserverResult {
        Ok(())
    }

    /// After each render step has spent its budget.
    fn step_done(&mut self, _at: &Progress, _renderer: &mut Renderer) -> ObserverResult {
        Ok(())
    }

    /// Asked after each iteration, move and step: `true` ends the run there, as if every
    /// budget were spent (the step in progress gets no `step_done`), and the run resolves
    /// the image of the iterations completed.
    fn stop_requested(&mut self) -> bool {
        false
    }
}

/// Watches nothing.
impl Observer for () {}

/// An observer that also ends the run when `stop` says so (a Ctrl-C): lets a caller that
/// only holds a stop condition make any observer stoppable.
pub struct Stoppable<'a> {
    /// The observer told of everything.
    pub observer: &'a mut dyn Observer,
    /// Whether to stop now.
    pub stop: &'a dyn Fn() -> bool,
}

impl Observer for Stoppable<'_> {
    fn iteration(&mut self, at: &Progress, renderer: &mut Renderer) -> ObserverResult {
        self.observer.iteration(at, renderer)
    }

    fn moved(&mut self, at: &Progress, m: &MoveReport, renderer: &mut Renderer) -> ObserverResult {
        self.observer.moved(at, m, renderer)
    }

    fn step_done(&mut self, at: &Progress, renderer: &mut Renderer) -> ObserverResult {
        self.observer.step_done(at, renderer)
    }

    fn stop_requested(&mut self) -> bool {
        (self.stop)() || self.observer.stop_requested()
    }
}

/// Why a run could not go on.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scene could not be loaded (before any pass ran).
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// The observer failed.
    #[error("{0}")]
    Observer(Box<dyn std::error::Error + Send + Sync>),
    /// The checkpoint to resume from does not fit this render.
    #[error(transparent)]
    Checkpoint(#[from] super::checkpoint::CheckpointError),
}

/// A checkpoint to continue from, and the folder it came from (named in errors).
pub struct Resume<'a> {
    /// The state.
    pub state: &'a super::checkpoint::RenderState,
    /// Its folder.
    pub dir: &'a std::path::Path,
}

/// A finished (or stopped) run.
pub struct Outcome {
    /// The image of the last statistics; non-finite pixels, if a pass failed, are zero.
    pub image: Image,
    /// What ran, how long it took, and what was left out.
    pub report: RenderReport,
    /// Every move, in order.
    pub moves: Vec<MoveReport>,
    /// Photons of each kind.
    pub counts: PhotonCounts,
    /// The pass error that stopped the run early, if any: the image holds what came before.
    pub error: Option<BackendError>,
    /// The observer ended the run before its schedule was done (see
    /// [`Observer::stop_requested`]).
    pub stopped: bool,
}

/// Runs `schedule` on `backend`: `scene` posed at its start, `params` and `moves` for every
/// pass, `observer` told of every iteration, move and finished step.
pub fn run(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    moves: &MoveParams,
    schedule: &Schedule,
    observer: &mut dyn Observer,
) -> Result<Outcome, RunError> {
    run_from(backend, scene, params, moves, schedule, observer, None)
}

/// [`run`], continuing from a checkpoint when `resume` gives one: the schedule then runs on
/// from the state it holds (its budgets count what this run adds), and the report's times
/// include the seconds before it.
pub fn run_from(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    moves: &MoveParams,
    schedule: &Schedule,
    observer: &mut dyn Observer,
    resume: Option<Resume>,
) -> Result<Outcome, RunError> {
    let total = Instant::now();
    let mut renderer = Renderer::start(backend, scene.at_time(schedule.start), params, moves)?;
    let before = match &resume {
        Some(r) => {
            renderer.restore(r.state, r.dir)?;
            r.state.seconds
        }
        None => 0.0,
    };
    if schedule
        .steps
        .iter()
        .any(|s| s.mode() == Some(MoveMode::Local))
    {
        renderer.expect_local_moves()?;
    }
    let mut clock = Stopwatch::start();
    let mut at = Progress {
        step: 0,
        step_iterations: 0,
        step_seconds: 0.0,
        iterations: 0,
        seconds: 0.0,
    };
    let mut move_reports = Vec::new();
    let mut error = None;
    let mut stopped = false;
    'steps: for (index, step) in schedule.steps.iter().enumerate() {
        at.step = index;
        at.step_iterations = 0;
        let step_start = clock.seconds();
        let observed = match step {
            &Step::Render(budget) => {
                while !budget.spent(at.step_iterations, clock.seconds() - step_start) {
                    if let Err(e) = renderer.iteration() {
                        error = Some(e);
                        break 'steps;
                    }
                    at.step_iterations += 1;
                    at.iterations += 1;
                    at.step_seconds = clock.seconds() - step_start;
                    at.seconds = clock.seconds();
                    clock.pause();
                    let observed = observer.iteration(&at, &mut renderer);
                    clock.resume();
                    observed.map_err(RunError::Observer)?;
                    let spent = budget.spent(at.step_iterations, clock.seconds() - step_start);
                    if !spent && observer.stop_requested() {
                        stopped = true;
                        break 'steps;
                    }
                }
                clock.pause();
                observer.step_done(&at, &mut renderer)
            }
            Step::Move { .. } | Step::MoveObjects { .. } | Step::MoveCamera { .. } => {
                let moved = match step {
                    &Step::Move { time, mode } => renderer.move_to(scene.at_time(time), mode),
                    Step::MoveObjects { moves, mode } => renderer.move_objects(moves, *mode),
                    Step::MoveCamera { camera, mode } => {
                        let placed = camera.place(&renderer.scene().camera);
                        renderer.move_camera(placed, *mode)
                    }
                    Step::Render(_) => unreachable!("matched above"),
                };
                at.step_seconds = clock.seconds() - step_start;
                at.seconds = clock.seconds();
                clock.pause();
                match moved {
                    Ok(m) => {
                        let observed = observer.moved(&at, &m, &mut renderer);
                        move_reports.push(m);
                        observed
                    }
                    Err(e) => {
                        error = Some(e);
                        break 'steps;
                    }
                }
            }
        };
        clock.resume();
        observed.map_err(RunError::Observer)?;
        if observer.stop_requested() {
            stopped = index + 1 < schedule.steps.len();
            break;
        }
    }
    let mut image = renderer.resolve()?;
    let mut report = renderer.final_report(schedule.moves());
    report.frame = u32::from(schedule.start >= 1.0);
    for p in image.pixels.iter_mut().flatten().filter(|v| !v.is_finite()) {
        *p = 0.0;
        report.non_finite_pixels_zeroed += 1;
    }
    report.times.total = before + total.elapsed().as_secs_f64();
    report.error = error.as_ref().map(ToString::to_string);
    report.interrupted = stopped;
    Ok(Outcome {
        image,
        report,
        moves: move_reports,
        counts: renderer.counts.clone(),
        error,
        stopped,
    })
}

/// An observer made of a closure called after each iteration.
pub struct EachIteration<F>(pub F);

impl<F> Observer for EachIteration<F>
where
    F: FnMut(&Progress, &mut Renderer) -> ObserverResult,
{
    fn iteration(&mut self, at: &Progress, renderer: &mut Renderer) -> ObserverResult {
        (self.0)(at, renderer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_budget_ends_at_whichever_limit_comes_first() {
        let both = Budget {
            iterations: Some(3),
            seconds: Some(1.0),
        };
        assert!(!both.spent(2, 0.5));
        assert!(both.spent(3, 0.5));
        assert!(both.spent(1, 1.0));
        assert!(Budget::default().spent(0, 0.0), "no limit: nothing to run");
        assert!(Budget::iterations(0).spent(0, 0.0));
    }

    /// An observer asking to stop from the start: a run of a hundred iterations ends after
    /// the first (the one in progress when asked), keeps it, and says it was stopped.
    #[test]
    fn a_stop_request_ends_the_run_after_the_iteration_in_progress() {
        let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
        let mut params = RenderParams::for_scene(&scene);
        (params.width, params.height, params.photons_per_pass) = (8, 8, 1000);
        let mut backend = backend_cpu::CpuBackend::new();
        let mut seen = 0;
        let mut count = EachIteration(|_: &Progress, _: &mut Renderer| {
            seen += 1;
            Ok(())
        });
        let stop = || true;
        let mut observer = Stoppable {
            observer: &mut count,
            stop: &stop,
        };
        let outcome = run(
            &mut backend,
            &scene,
            &params,
            &MoveParams::default(),
            &Schedule::frame(0, Budget::iterations(100)),
            &mut observer,
        )
        .unwrap();
        assert!(outcome.stopped && outcome.report.interrupted);
        assert_eq!((outcome.report.passes, seen), (1, 1));
        let unstopped = run(
            &mut backend,
            &scene,
            &params,
            &MoveParams::default(),
            &Schedule::frame(0, Budget::iterations(2)),
            &mut (),
        )
        .unwrap();
        assert!(!unstopped.stopped && !unstopped.report.interrupted);
        assert_eq!(unstopped.report.passes, 2);
    }

    #[test]
    fn restart_skips_the_warm_up_and_starts_on_the_new_pose() {
        let s = Schedule::after_move(
            Budget::seconds(15.0),
            MoveMode::Restart,
            Budget::seconds(8.0),
        );
        assert_eq!(s, Schedule::frame(1, Budget::seconds(8.0)));
        let a = Schedule::animation(2, MoveMode::Area, Budget::iterations(1));
        assert_eq!(a.steps.len(), 5);
        assert_eq!(
            a.steps[3],
            Step::Move {
                time: 1.0,
                mode: MoveMode::Area
            }
        );
    }
}
