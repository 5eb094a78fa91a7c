//! Error against run time after a move (docs/algorithm.md 6): how fast each mode approaches the
//! truth of the new pose (a path-traced reference, or another renderer's image).

use crate::chart::{ChartError, Series, write_loglog_chart};
use crate::convergence::log_log_slope;
use crate::driver::{
    Budget, MoveReport, Observer, ObserverResult, PhotonCounts, Progress, Renderer, RunError,
    Schedule, Stoppable, run,
};
use ppm_core::camera_move;
use ppm_core::image::Image;
use ppm_core::layout::{HitPoint, hit_flags};
use ppm_core::metrics::relative_rmse_parts;
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::path::{After, MovePath, PathEvent};
use ppm_core::scene::{Camera, Scene};
use serde::Serialize;
use std::path::Path;

/// What to measure.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorSettings {
    /// Render settings (size, photons per pass, seed, radius, alpha).
    pub params: RenderParams,
    /// Settings of the passes that follow a move.
    pub moves: MoveParams,
    /// The moves, each after its rendering time: the scene's own `[[moves]]` after the
    /// warm-up ([`MovePath::declared`]), or a path nobody declared.
    pub path: MovePath,
    /// Seconds measured after the last move.
    pub seconds: f64,
}

/// One measurement.
#[derive(Clone, Debug, Serialize)]
pub struct Measurement {
    /// Mode.
    pub mode: MoveMode,
    /// Seconds since the move (rendering only; measuring is not counted).
    pub seconds: f64,
    /// Relative RMSE against the reference.
    pub rel_rmse: f64,
    /// Its part from pixels whose hit points the move kept (`kept^2 + reset^2 = rel_rmse^2`).
    pub kept: f64,
    /// Its part from pixels whose hit points the move reset.
    pub reset: f64,
    /// Passes since the move.
    pub passes: u32,
}

/// One mode's run after the moves.
#[derive(Clone, Debug, Serialize)]
pub struct ModeRun {
    /// Mode.
    pub mode: MoveMode,
    /// What each move did, in order (none for restart, which renders the last pose).
    pub moves: Vec<MoveReport>,
    /// Photons of each kind after the move (emitted, deposited).
    pub counts: PhotonCounts,
    /// Initial squared radius.
    pub r2_initial: f32,
    /// Measurements over time.
    pub measurements: Vec<Measurement>,
    /// Slope of the kept pixels' error against the whole rendering time (before the last
    /// move and since), from a second after it on: -0.5 where they go on converging as a
    /// consistent estimator, 0 where they stopped.
    pub kept_slope: Option<f64>,
    /// The brightest pixel right after the last move, over the truth's brightest.
    pub brightest_after_move: Option<f32>,
    /// The brightest pixel at the end, over the truth's brightest.
    pub brightest_final: Option<f32>,
    /// Milliseconds an iteration took after the last move, on average.
    pub iteration_ms: Option<f64>,
}

/// The pixels whose slots some move of the path resets (any of their slots), including slots
/// that gain or lose their visible point (an object's silhouette over the void), with one
/// iteration before each move. A path that moves the camera is followed in local mode, the
/// one that keeps light across a camera move, with 16 iterations before each move so that
/// there is light to keep and the jitter has found the edges a pixel straddles (whose slots
/// start over): a camera move resets the pixels whose slots started over.
pub fn reset_pixels(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &ErrorSettings,
) -> Result<Vec<bool>, RunError> {
    /// Compares the slots before and after each move.
    struct Resets {
        before: Vec<HitPoint>,
        camera: Camera,
        mask: Vec<bool>,
    }
    impl Observer for Resets {
        fn step_done(&mut self, _: &Progress, r: &mut Renderer) -> ObserverResult {
            self.before = r.backend().read_hit_points()?;
            Ok(())
        }
        fn moved(&mut self, _: &Progress, _: &MoveReport, r: &mut Renderer) -> ObserverResult {
            let after = r.backend().read_hit_points()?;
            if r.scene().camera != self.camera {
                self.camera = r.scene().camera.clone();
                for b in after.iter().filter(|b| camera_move::started_over(b)) {
                    self.mask[b.pixel as usize] = true;
                }
            } else {
                for (a, b) in self.before.iter().zip(&after) {
                    if b.flags & hit_flags::UPDATED != 0 || a.is_valid() != b.is_valid() {
                        self.mask[b.pixel as usize] = true;
                    }
                }
            }
            self.before = after;
            Ok(())
        }
    }
    let moves_camera = settings.path.events.iter().any(|e| e.camera.is_some());
    let (mode, before_each) = match moves_camera {
        true => (MoveMode::Local, 16),
        false => (MoveMode::Difference, 1),
    };
    // Moves with no compensation passes: difference mode needs no emitting region, so the
    // slots are updated (docs/algorithm.md 2.4's test) whatever the objects' shape around the
    // lights; the split is the same for every mode.
    let moves = MoveParams {
        difference_passes: 0,
        ..settings.moves.clone()
    };
    let path = MovePath {
        events: settings
            .path
            .events
            .iter()
            .map(|e| PathEvent {
                after: After::Iterations(before_each),
                ..e.clone()
            })
            .collect(),
    };
    let schedule = Schedule::path(&path, mode, Budget::iterations(0));
    let p = &settings.params;
    let mut resets = Resets {
        before: Vec::new(),
        camera: scene.camera.clone(),
        mask: vec![false; (p.width * p.height) as usize],
    };
    run(backend, scene, p, &moves, &schedule, &mut resets)?;
    Ok(resets.mask)
}

/// Measures a run after its last move (or from its start, for restart).
struct AfterMove<'a> {
    mode: MoveMode,
    truth: &'a Image,
    reset: &'a [bool],
    /// The step whose iterations are measured (the last move is the step before).
    measured_step: usize,
    /// Seconds the last move took, counted in the time since the move.
    move_seconds: f64,
    moves: Vec<MoveReport>,
    measurements: Vec<Measurement>,
    /// The brightest pixel right after the last move and at the last measurement.
    brightest: (Option<f32>, Option<f32>),
}

impl AfterMove<'_> {
    fn measure(&mut self, r: &mut Renderer, seconds: f64, passes: u32) -> ObserverResult {
        let image = r.resolve()?;
        let brightest = Some(image.brightest() / self.truth.brightest());
        if passes == 0 {
            self.brightest.0 = brightest;
        }
        self.brightest.1 = brightest;
        let (kept, reset) = relative_rmse_parts(&image, self.truth, self.reset);
        self.measurements.push(Measurement {
            mode: self.mode,
            seconds,
            rel_rmse: kept.hypot(reset),
            kept,
            reset,
            passes,
        });
        Ok(())
    }
}

impl Observer for AfterMove<'_> {
    fn iteration(&mut self, at: &Progress, r: &mut Renderer) -> ObserverResult {
        if at.step == self.measured_step {
            self.measure(r, self.move_seconds + at.step_seconds, at.step_iterations)?;
        }
        Ok(())
    }

    fn moved(&mut self, at: &Progress, m: &MoveReport, r: &mut Renderer) -> ObserverResult {
        self.moves.push(m.clone());
        if at.step + 1 == self.measured_step {
            self.move_seconds = at.step_seconds;
            self.measure(r, at.step_seconds, 0)?;
        }
        Ok(())
    }

    fn step_done(&mut self, at: &Progress, r: &mut Renderer) -> ObserverResult {
        // Photons are counted from the move on (the thesis's tables 4.1 and 4.2).
        if at.step + 1 < self.measured_step {
            r.counts = PhotonCounts::default();
        }
        Ok(())
    }
}

/// Runs `mode` along the path: frame 0, each move after its rendering time, then iterations
/// until `settings.seconds` after the last move, measuring after each; restart renders the
/// last pose from scratch (what it keeps of earlier poses is nothing). `reset` (from
/// [`reset_pixels`]) splits the error. Ends early, with the measurements so far, when `stop`
/// says so.
pub fn run_mode(
    backend: &mut dyn Backend,
    scene: &Scene,
    mode: MoveMode,
    settings: &ErrorSettings,
    truth: &Image,
    reset: &[bool],
    stop: &dyn Fn() -> bool,
) -> Result<ModeRun, RunError> {
    let after = Budget::seconds(settings.seconds);
    let (start, schedule) = match mode {
        MoveMode::Restart => (settings.path.final_pose(scene), Schedule::frame(0, after)),
        _ => (scene.clone(), Schedule::path(&settings.path, mode, after)),
    };
    let mut observer = AfterMove {
        mode,
        truth,
        reset,
        measured_step: schedule.steps.len() - 1,
        move_seconds: 0.0,
        moves: Vec::new(),
        measurements: Vec::new(),
        brightest: (None, None),
    };
    let outcome = run(
        backend,
        &start,
        &settings.params,
        &settings.moves,
        &schedule,
        &mut Stoppable {
            observer: &mut observer,
            stop,
        },
    )?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    // Restart keeps nothing from before the last move: its history is its own.
    let before = match mode {
        MoveMode::Restart => 0.0,
        _ => settings.path.before_last().1,
    };
    let m = &observer.measurements;
    let kept: Vec<(f64, f64)> = m
        .iter()
        .filter(|m| m.seconds >= 1.0)
        .map(|m| (before + m.seconds, m.kept))
        .collect();
    let iteration_ms = match (m.iter().find(|m| m.passes > 0), m.last()) {
        (Some(a), Some(b)) if b.passes > a.passes => {
            Some((b.seconds - a.seconds) * 1e3 / f64::from(b.passes - a.passes))
        }
        _ => None,
    };
    Ok(ModeRun {
        mode,
        moves: observer.moves,
        counts: outcome.counts,
        r2_initial: settings.params.initial_radius * settings.params.initial_radius,
        kept_slope: log_log_slope(&kept),
        brightest_after_move: observer.brightest.0,
        brightest_final: observer.brightest.1,
        iteration_ms,
        measurements: observer.measurements,
    })
}

/// The error a perfect compensation that costs nothing would reach, over time: its kept
/// pixels as good as a from-scratch render of the last pose for the rendering time before
/// the last move (every change
/// removed, nothing stale, no compensation noise), its reset pixels as restart's. A mode
/// gets below it only where its reset pixels converge faster than restart's (guiding, or
/// local mode's iterations spent on them) or its kept pixels keep converging past the
/// warm-up: it says what keeping the converged light can win on the scene. `None` when
/// `stop` ended the render early (its kept pixels would be judged on less than the warm-up).
pub fn perfect_compensation(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &ErrorSettings,
    truth: &Image,
    reset: &[bool],
    restart: &ModeRun,
    stop: &dyn Fn() -> bool,
) -> Result<Option<Vec<(f64, f64)>>, RunError> {
    let mut params = settings.params.clone();
    params.seed = params.seed.wrapping_add(1);
    let budget = match settings.path.before_last() {
        (n, s) if s > 0.0 || n == 0 => Budget::seconds(s),
        (n, _) => Budget::iterations(n),
    };
    let schedule = Schedule::frame(0, budget);
    let last = settings.path.final_pose(scene);
    let mut nothing = ();
    let mut observer = Stoppable {
        observer: &mut nothing,
        stop,
    };
    let outcome = run(
        backend,
        &last,
        &params,
        &settings.moves,
        &schedule,
        &mut observer,
    )?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    if outcome.stopped {
        return Ok(None);
    }
    let (kept, _) = relative_rmse_parts(&outcome.image, truth, reset);
    Ok(Some(
        restart
            .measurements
            .iter()
            .map(|m| (m.seconds, kept.hypot(m.reset)))
            .collect(),
    ))
}

/// The CSV of all measurements: `mode,seconds,rel_rmse,kept,reset`.
pub fn csv(runs: &[ModeRun]) -> String {
    let mut s = String::from("mode,seconds,rel_rmse,kept,reset\n");
    for m in runs.iter().flat_map(|r| &r.measurements) {
        s.push_str(&format!(
            "{},{:.6},{:.6},{:.6},{:.6}\n",
            m.mode.name(),
            m.seconds,
            m.rel_rmse,
            m.kept,
            m.reset
        ));
    }
    s
}

/// The log-log chart of the runs, with the perfect-compensation curve dashed in grey where
/// it was measured (it needs the restart run), as `stem.png` and `stem.svg`.
pub fn chart(
    stem: &Path,
    scene: &str,
    runs: &[ModeRun],
    perfect: &[(f64, f64)],
) -> Result<(), ChartError> {
    let colour = |m: MoveMode| match m {
        MoveMode::Restart => [0.8, 0.1, 0.1],
        MoveMode::Thesis => [0.1, 0.3, 0.9],
        MoveMode::Area => [0.1, 0.6, 0.2],
        MoveMode::Difference => [0.9, 0.6, 0.0],
        MoveMode::Local => [0.6, 0.1, 0.7],
    };
    let mut series: Vec<Series> = runs
        .iter()
        .map(|r| Series {
            name: r.mode.name(),
            colour: colour(r.mode),
            points: r
                .measurements
                .iter()
                .map(|m| (m.seconds, m.rel_rmse))
                .collect(),
            dashed: false,
        })
        .collect();
    if !perfect.is_empty() {
        series.push(Series {
            name: "perfect",
            colour: [0.55; 3],
            points: perfect.to_vec(),
            dashed: true,
        });
    }
    write_loglog_chart(
        stem,
        &format!("{scene}: error after the move"),
        "seconds since the move",
        "relative rmse",
        &series,
    )
}

/// The thesis's tables 4.1 (compensating modes) and 4.2 (restart) for these runs.
pub fn tables(runs: &[ModeRun], triangles: usize) -> String {
    let mut s = String::new();
    s.push_str(
        "Table 4.1 (ours): photons after the move, by kind, with the initial squared radius\n",
    );
    s.push_str(&format!(
        "{:<8} {:>9} {:>22} {:>22} {:>22} {:>16} {:>8}\n",
        "mode",
        "triangles",
        "compensation (r2)",
        "positive (r2)",
        "guided+testing (r2)",
        "valid photons",
        "time"
    ));
    for r in runs.iter().filter(|r| r.mode != MoveMode::Restart) {
        let c = &r.counts;
        let positive = c.region.emitted + c.ordinary.emitted;
        let valid = c.compensation.deposited
            + c.region.deposited
            + c.ordinary.deposited
            + c.testing.deposited
            + c.guided.deposited;
        let t = r.measurements.last().map_or(0.0, |m| m.seconds);
        s.push_str(&format!(
            "{:<8} {:>9} {:>22} {:>22} {:>22} {:>16} {:>7.2}s\n",
            r.mode.name(),
            triangles,
            format!("{}k({})", c.compensation.emitted / 1000, r.r2_initial),
            format!("{}k({})", positive / 1000, r.r2_initial),
            format!(
                "{}k({})",
                (c.guided.emitted + c.testing.emitted) / 1000,
                r.r2_initial
            ),
            format!("{}k", valid / 1000),
            t
        ));
    }
    s.push_str("Table 4.2 (PPM restart): photons after the move\n");
    s.push_str(&format!(
        "{:<8} {:>9} {:>22} {:>16} {:>8}\n",
        "mode", "triangles", "total photons (r2)", "valid photons", "time"
    ));
    for r in runs.iter().filter(|r| r.mode == MoveMode::Restart) {
        let t = r.measurements.last().map_or(0.0, |m| m.seconds);
        s.push_str(&format!(
            "{:<8} {:>9} {:>22} {:>16} {:>7.2}s\n",
            r.mode.name(),
            triangles,
            format!("{}k({})", r.counts.ordinary.emitted / 1000, r.r2_initial),
            format!("{}k", r.counts.ordinary.deposited / 1000),
            t
        ));
    }
    s
}

/// Restart's final error: the level every other curve is timed against.
pub fn restart_final_error(runs: &[ModeRun]) -> Option<f64> {
    runs.iter()
        .find(|r| r.mode == MoveMode::Restart)
        .and_then(|r| r.measurements.last())
        .map(|m| m.rel_rmse)
}

/// Seconds each mode needs to reach restart's final error (`None` if it never does).
pub fn time_to_restart_error(runs: &[ModeRun]) -> Vec<(MoveMode, Option<f64>)> {
    let Some(target) = restart_final_error(runs) else {
        return Vec::new();
    };
    runs.iter()
        .map(|r| {
            let points: Vec<_> = r
                .measurements
                .iter()
                .map(|m| (m.seconds, m.rel_rmse))
                .collect();
            (r.mode, time_to_reach(&points, target))
        })
        .collect()
}

/// When the curve `points` (seconds, error) first reaches `target`, interpolating linearly
/// between measurements; `None` if it never does.
pub fn time_to_reach(points: &[(f64, f64)], target: f64) -> Option<f64> {
    if let Some(&(t, _)) = points.first().filter(|p| p.1 <= target) {
        return Some(t);
    }
    points.windows(2).find_map(|w| {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        (e1 <= target).then(|| t0 + (e0 - target) / (e0 - e1) * (t1 - t0))
    })
}
