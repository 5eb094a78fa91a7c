//! Error against run time (ALGORITHM.md 6): after a move, how fast each mode approaches a
//! long from-scratch render of the new pose.

use crate::chart::{ChartError, Series, write_loglog_chart};
use crate::dynamic::{DynamicParams, Mode, MoveReport, PhotonCounts, Progressive};
use crate::render::render;
use ppm_core::image::{Image, relative_rmse_parts};
use ppm_core::layout::hit_flags;
use ppm_core::params::RenderParams;
use ppm_core::passes::{BackendError, DynamicBackend};
use ppm_core::scene::Scene;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorSettings {
    /// Render settings (size, photons per pass, seed, radius, alpha).
    pub params: RenderParams,
    /// Dynamic-pass settings.
    pub dynamic: DynamicParams,
    /// Seconds of ordinary passes on the old pose before the move.
    pub warmup_seconds: f64,
    /// Seconds measured after the move.
    pub seconds: f64,
    /// Photon passes of the from-scratch reference of the new pose.
    pub reference_passes: u32,
}

/// One measurement.
#[derive(Clone, Debug, Serialize)]
pub struct Measurement {
    /// Mode.
    pub mode: Mode,
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

/// One mode's run after the move.
#[derive(Clone, Debug, Serialize)]
pub struct ModeRun {
    /// Mode.
    pub mode: Mode,
    /// The move (absent for restart).
    pub moved: Option<MoveReport>,
    /// Photons of each kind after the move (emitted, deposited).
    pub counts: PhotonCounts,
    /// Initial squared radius.
    pub r2_initial: f32,
    /// Measurements over time.
    pub measurements: Vec<Measurement>,
}

/// The reference image of `scene` at frame 1, from `path` when cached there, else rendered
/// (seed offset so it shares no numbers with the runs) and cached.
pub fn reference(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    settings: &ErrorSettings,
    path: &Path,
) -> Result<Image, Box<dyn std::error::Error>> {
    if let Ok(img) = read_exr(path)
        && (img.width, img.height) == (settings.params.width, settings.params.height)
    {
        return Ok(img);
    }
    let mut p = settings.params.clone();
    p.passes = settings.reference_passes;
    p.time_budget = None;
    p.seed = p.seed.wrapping_add(0x5eed);
    let outcome = render(backend, scene, 1, &p, &mut |_, _| {})?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    outcome.image.write_exr(path)?;
    Ok(outcome.image)
}

fn read_exr(path: &Path) -> Result<Image, Box<dyn std::error::Error>> {
    let read = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| Image::new(res.width() as u32, res.height() as u32),
        |img: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width as usize;
            img.pixels[pos.y() * w + pos.x()] = [r, g, b]
        },
    )?;
    Ok(read.layer_data.channel_data.pixels)
}

/// The cache file of a reference: keyed by scene name, resolution, passes, photons, seed,
/// radius, alpha and shadow rays.
pub fn reference_path(cache: &Path, scene: &Scene, settings: &ErrorSettings) -> PathBuf {
    let p = &settings.params;
    cache.join(format!(
        "reference-{}-{}x{}-{}x{}-s{}-r{}-a{}-d{}.exr",
        scene.name,
        p.width,
        p.height,
        settings.reference_passes,
        p.photons_per_pass,
        p.seed,
        p.initial_radius,
        p.alpha,
        p.direct_samples
    ))
}

/// The pixels whose hit points the move from frame 0 to frame 1 resets (any of their slots),
/// including slots that gain or lose their surface (an object's silhouette over the void).
pub fn reset_pixels(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    settings: &ErrorSettings,
) -> Result<Vec<bool>, BackendError> {
    // A move with no compensation passes: difference mode needs no emitting region, so the
    // hit points are updated whatever the object's shape around the lights.
    let dynamic = DynamicParams {
        difference_passes: 0,
        ..settings.dynamic.clone()
    };
    let mut render = Progressive::start(backend, scene.at_frame(0), &settings.params, &dynamic)?;
    let before = render.backend().read_hit_points()?;
    render.move_to(scene.at_frame(1), Mode::Difference)?;
    let mut mask = vec![false; (settings.params.width * settings.params.height) as usize];
    for (a, b) in before.iter().zip(render.backend().read_hit_points()?) {
        if b.flags & hit_flags::UPDATED != 0 || a.is_valid() != b.is_valid() {
            mask[b.pixel as usize] = true;
        }
    }
    Ok(mask)
}

/// Runs `mode` after a move: warm-up on frame 0 (not for restart), the move, then passes until
/// `settings.seconds`, measuring after each; `reset` (from [`reset_pixels`]) splits the error.
pub fn run_mode(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    mode: Mode,
    settings: &ErrorSettings,
    truth: &Image,
    reset: &[bool],
) -> Result<ModeRun, BackendError> {
    let mut measurements = Vec::new();
    let mut measure =
        |render: &mut Progressive, seconds: f64, passes: u32| -> Result<(), BackendError> {
            let image = render.resolve()?;
            let (kept, reset) = relative_rmse_parts(&image, truth, reset);
            measurements.push(Measurement {
                mode,
                seconds,
                rel_rmse: kept.hypot(reset),
                kept,
                reset,
                passes,
            });
            Ok(())
        };
    let (mut render, moved, mut clock) = if mode == Mode::Restart {
        let clock = Stopwatch::start();
        (
            Progressive::start(
                backend,
                scene.at_frame(1),
                &settings.params,
                &settings.dynamic,
            )?,
            None,
            clock,
        )
    } else {
        let mut render = Progressive::start(
            backend,
            scene.at_frame(0),
            &settings.params,
            &settings.dynamic,
        )?;
        let warm = Instant::now();
        while warm.elapsed().as_secs_f64() < settings.warmup_seconds {
            render.ordinary_pass()?;
        }
        render.counts = PhotonCounts::default();
        let clock = Stopwatch::start();
        let moved = render.move_to(scene.at_frame(1), mode)?;
        (render, Some(moved), clock)
    };
    clock.pause();
    measure(&mut render, clock.seconds(), 0)?;
    let mut passes = 0;
    while clock.seconds() < settings.seconds {
        clock.resume();
        render.step()?;
        clock.pause();
        passes += 1;
        measure(&mut render, clock.seconds(), passes)?;
    }
    Ok(ModeRun {
        mode,
        moved,
        counts: render.counts.clone(),
        r2_initial: settings.params.initial_radius * settings.params.initial_radius,
        measurements,
    })
}

/// The error a perfect compensation that costs nothing would reach, over time: its kept
/// pixels as good as a from-scratch render of frame 1 for the warm-up time (every change
/// removed, nothing stale, no compensation noise), its reset pixels as restart's. Unless
/// guiding makes the reset pixels converge faster than restart's, no compensating mode gets
/// below this curve: it says what the method can win on the scene at all.
pub fn perfect_compensation(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    settings: &ErrorSettings,
    truth: &Image,
    reset: &[bool],
    restart: &ModeRun,
) -> Result<Vec<(f64, f64)>, BackendError> {
    let mut params = settings.params.clone();
    params.seed = params.seed.wrapping_add(1);
    let mut render = Progressive::start(backend, scene.at_frame(1), &params, &settings.dynamic)?;
    let warm = Instant::now();
    while warm.elapsed().as_secs_f64() < settings.warmup_seconds {
        render.ordinary_pass()?;
    }
    let (kept, _) = relative_rmse_parts(&render.resolve()?, truth, reset);
    Ok(restart
        .measurements
        .iter()
        .map(|m| (m.seconds, kept.hypot(m.reset)))
        .collect())
}

/// Wall-clock time with pauses, so measuring is not charged to rendering.
struct Stopwatch {
    running_since: Option<Instant>,
    banked: f64,
}

impl Stopwatch {
    fn start() -> Self {
        Self {
            running_since: Some(Instant::now()),
            banked: 0.0,
        }
    }
    fn pause(&mut self) {
        if let Some(t) = self.running_since.take() {
            self.banked += t.elapsed().as_secs_f64();
        }
    }
    fn resume(&mut self) {
        self.running_since.get_or_insert_with(Instant::now);
    }
    fn seconds(&self) -> f64 {
        self.banked
            + self
                .running_since
                .map_or(0.0, |t| t.elapsed().as_secs_f64())
    }
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

/// The log-log chart of the runs, with the perfect-compensation curve dashed in grey, as
/// `stem.png` and `stem.svg`.
pub fn chart(
    stem: &Path,
    scene: &str,
    runs: &[ModeRun],
    perfect: &[(f64, f64)],
) -> Result<(), ChartError> {
    let colour = |m: Mode| match m {
        Mode::Restart => [0.8, 0.1, 0.1],
        Mode::Thesis => [0.1, 0.3, 0.9],
        Mode::Area => [0.1, 0.6, 0.2],
        Mode::Difference => [0.9, 0.6, 0.0],
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
    series.push(Series {
        name: "perfect",
        colour: [0.55; 3],
        points: perfect.to_vec(),
        dashed: true,
    });
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
    for r in runs.iter().filter(|r| r.mode != Mode::Restart) {
        let c = &r.counts;
        let positive = c.region.0 + c.ordinary.0;
        let valid = c.compensation.1 + c.region.1 + c.ordinary.1 + c.testing.1 + c.guided.1;
        let t = r.measurements.last().map_or(0.0, |m| m.seconds);
        s.push_str(&format!(
            "{:<8} {:>9} {:>22} {:>22} {:>22} {:>16} {:>7.2}s\n",
            r.mode.name(),
            triangles,
            format!("{}k({})", c.compensation.0 / 1000, r.r2_initial),
            format!("{}k({})", positive / 1000, r.r2_initial),
            format!("{}k({})", (c.guided.0 + c.testing.0) / 1000, r.r2_initial),
            format!("{}k", valid / 1000),
            t
        ));
    }
    s.push_str("Table 4.2 (PPM restart): photons after the move\n");
    s.push_str(&format!(
        "{:<8} {:>9} {:>22} {:>16} {:>8}\n",
        "mode", "triangles", "total photons (r2)", "valid photons", "time"
    ));
    for r in runs.iter().filter(|r| r.mode == Mode::Restart) {
        let t = r.measurements.last().map_or(0.0, |m| m.seconds);
        s.push_str(&format!(
            "{:<8} {:>9} {:>22} {:>16} {:>7.2}s\n",
            r.mode.name(),
            triangles,
            format!("{}k({})", r.counts.ordinary.0 / 1000, r.r2_initial),
            format!("{}k", r.counts.ordinary.1 / 1000),
            t
        ));
    }
    s
}

/// Restart's final error: the level every other curve is timed against.
pub fn restart_final_error(runs: &[ModeRun]) -> Option<f64> {
    runs.iter()
        .find(|r| r.mode == Mode::Restart)
        .and_then(|r| r.measurements.last())
        .map(|m| m.rel_rmse)
}

/// Seconds each mode needs to reach restart's final error (`None` if it never does).
pub fn time_to_restart_error(runs: &[ModeRun]) -> Vec<(Mode, Option<f64>)> {
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
