//! `ppm animate` and `ppm report error-vs-time`: scenes whose objects move.

use crate::cli::interrupt::{self, Interrupted};
use crate::cli::options::{BackendChoice, MoveOptions, RenderOptions, TruthOptions};
use crate::cli::render::output_folder;
use crate::driver::{
    Budget, MoveReport, Observer, ObserverResult, Progress, Renderer, Schedule, run,
};
use crate::error_report::{self, ErrorSettings};
use anyhow::{Result, bail};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::scene::Scene;
use ppm_core::scene::path::{After, MovePath};
use scenes::file::image::ImageFiles;
use scenes::file::output::write_bytes;
use scenes::file::path::load_path_file;
use std::path::PathBuf;

/// Scene, backend and settings of a command on a moving scene.
#[derive(clap::Args)]
pub struct MovingArgs {
    /// Built-in scene name or path to a scene file (its `[[moves]]` define the motion unless
    /// --path or --random-path give another).
    scene: String,
    /// Backend that runs the passes: cpu, wgpu, or another registered one (`ppm backends`).
    #[arg(long, default_value = "cpu")]
    backend: BackendChoice,
    #[command(flatten)]
    options: RenderOptions,
    #[command(flatten)]
    moves: MoveOptions,
    /// Path file of moves nobody declared in the scene (`[[step]]` after_seconds or
    /// after_iterations, then object, translate, rotate, or camera = { eye, look_at }); the
    /// scene's `[[moves]]` are ignored.
    #[arg(long, conflicts_with = "random_path")]
    path: Option<PathBuf>,
    /// This many random rigid moves of random objects that are not lights, kept inside the
    /// scene's bounds and keyed by --seed, instead of the scene's `[[moves]]`.
    #[arg(long)]
    random_path: Option<u32>,
}

impl MovingArgs {
    /// The scene, its settings (256x256 unless the options say) and the settings of its
    /// moves.
    fn setup(&self) -> Result<(Scene, RenderParams, MoveParams)> {
        let scene = crate::load_scene(&self.scene)?;
        let params = self.options.params(&scene, Some((256, 256)))?;
        let moves = self.moves.params(&scene, &params)?;
        Ok((scene, params, moves))
    }

    /// The moves nobody declared, if the options give them (a random path's first move
    /// after `first`, the others after `then`); `None` means the scene's own `[[moves]]`,
    /// refused when it has none.
    fn unplanned(&self, scene: &Scene, first: After, then: After) -> Result<Option<MovePath>> {
        if let Some(file) = &self.path {
            return Ok(Some(load_path_file(file, scene)?));
        }
        if let Some(n) = self.random_path {
            let path = MovePath::random(scene, n, self.options.seed, first, then);
            if n == 0 || path.events.is_empty() {
                bail!(
                    "--random-path = {n}: {} has no object that may move (none but lights, or \
                     none with room inside the scene's bounds)",
                    self.scene
                );
            }
            return Ok(Some(path));
        }
        if scene.moves.is_empty() {
            bail!(
                "{}: the scene has no [[moves]]: give --path FILE or --random-path N",
                self.scene
            );
        }
        Ok(None)
    }
}

#[derive(clap::Args)]
pub struct AnimateArgs {
    #[command(flatten)]
    common: MovingArgs,
    /// Steps from frame 0 to frame 1 (the scene's move cut into equal parts; not with a
    /// path, whose own steps are the frames).
    #[arg(long, default_value_t = 8)]
    steps: u32,
    /// How each step is followed.
    #[arg(long, default_value = "local", value_parser = clap::value_parser!(MoveMode))]
    mode: MoveMode,
    /// Seconds of iterations per frame (with --random-path, also between its moves; a path
    /// file times its own moves).
    #[arg(long, default_value_t = 2.0)]
    time_per_frame: f64,
    /// Output folder: frame-NNN.exr, .png and .json.
    #[arg(short, long)]
    output: PathBuf,
}

/// Writes each frame when its render step ends, with what its move did.
struct FrameWriter<'a> {
    args: &'a AnimateArgs,
    scene: &'a str,
    /// Moves in the animation.
    steps: u32,
    last_move: Option<MoveReport>,
    frame_start: (u32, f64),
    /// Frames written so far.
    written: u32,
}

impl Observer for FrameWriter<'_> {
    fn moved(&mut self, _: &Progress, m: &MoveReport, _: &mut Renderer) -> ObserverResult {
        self.last_move = Some(m.clone());
        Ok(())
    }

    fn step_done(&mut self, at: &Progress, r: &mut Renderer) -> ObserverResult {
        let frame = at.step / 2;
        let image = r.resolve()?;
        let stem = self.args.output.join(format!("frame-{frame:03}"));
        image.write_exr(&stem.with_extension("exr"))?;
        image.write_png(&stem.with_extension("png"), 1.0)?;
        let iterations = at.iterations - self.frame_start.0;
        let seconds = at.seconds - self.frame_start.1;
        let report = serde_json::json!({
            "scene": self.scene, "frame": frame, "steps": self.steps,
            "mode": self.args.mode, "estimator": r.params().estimator, "iterations": iterations,
            "seconds": seconds, "move": self.last_move.take(), "photons": r.counts,
            "left_out": r.final_report(self.steps > 0).left_out,
        });
        write_bytes(
            &stem.with_extension("json"),
            serde_json::to_string_pretty(&report)?,
        )?;
        self.written += 1;
        println!(
            "frame {frame}: {iterations} iterations, {seconds:.2}s -> {}",
            stem.with_extension("exr").display()
        );
        self.frame_start = (at.iterations, at.seconds);
        Ok(())
    }

    fn stop_requested(&mut self) -> bool {
        interrupt::requested()
    }
}

pub fn animate(args: AnimateArgs) -> Result<()> {
    interrupt::install()?;
    let (scene, params, moves) = args.common.setup()?;
    if args.steps == 0 {
        bail!("--steps = 0: must be at least 1");
    }
    if !(args.time_per_frame.is_finite() && args.time_per_frame > 0.0) {
        bail!(
            "--time-per-frame = {}: must be a positive number of seconds",
            args.time_per_frame
        );
    }
    let frame = Budget::seconds(args.time_per_frame);
    let each = After::Seconds(args.time_per_frame);
    let (schedule, steps) = match args.common.unplanned(&scene, each, each)? {
        Some(path) => (
            Schedule::path(&path, args.mode, frame),
            path.events.len() as u32,
        ),
        None => (
            Schedule::animation(args.steps, args.mode, frame),
            args.steps,
        ),
    };
    output_folder(&args.output, &format!("-o {}", args.output.display()))?;
    let mut backend = args.common.backend.start()?;
    eprintln!(
        "rendering {} in {steps} steps ({}), {}s a frame",
        scene.name,
        args.mode.name(),
        args.time_per_frame
    );
    let mut writer = FrameWriter {
        args: &args,
        scene: &scene.name,
        steps,
        last_move: None,
        frame_start: (0, 0.0),
        written: 0,
    };
    let outcome = run(
        backend.as_mut(),
        &scene,
        &params,
        &moves,
        &schedule,
        &mut writer,
    )?;
    if let Some(e) = outcome.error {
        bail!("the animation stopped: {e}");
    }
    if outcome.stopped {
        return Err(Interrupted(format!(
            "the {} frames completed are in {}",
            writer.written,
            args.output.display()
        ))
        .into());
    }
    Ok(())
}

#[derive(clap::Args)]
pub struct ErrorArgs {
    #[command(flatten)]
    common: MovingArgs,
    /// Seconds of iterations on frame 0 before the (first) move; a path file times its own.
    #[arg(long, default_value_t = 10.0)]
    warmup: f64,
    /// Seconds of iterations between the moves of a random path.
    #[arg(long, default_value_t = 1.0)]
    between: f64,
    /// Seconds measured after the (last) move.
    #[arg(long, default_value_t = 8.0)]
    seconds: f64,
    /// Modes to measure, comma-separated (default: all); the perfect-compensation bound
    /// needs `restart`.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(MoveMode))]
    modes: Vec<MoveMode>,
    #[command(flatten)]
    truth: TruthOptions,
    /// Output folder: error-vs-time.csv, .json and .png.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn error_vs_time(args: ErrorArgs) -> Result<()> {
    interrupt::install()?;
    let (scene, params, moves) = args.common.setup()?;
    for (name, v) in [
        ("--warmup", args.warmup),
        ("--between", args.between),
        ("--seconds", args.seconds),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("{name} = {v}: must be a positive number of seconds");
        }
    }
    let warmup = After::Seconds(args.warmup);
    let path = args
        .common
        .unplanned(&scene, warmup, After::Seconds(args.between))?
        .unwrap_or_else(|| MovePath::declared(&scene, warmup));
    output_folder(&args.output, &format!("-o {}", args.output.display()))?;
    let settings = ErrorSettings {
        params,
        moves,
        path,
        seconds: args.seconds,
    };
    let last_pose = settings.path.final_pose(&scene);
    let truth = args.truth.truth(&last_pose, 0, &settings.params)?;
    let truth = &truth.image;
    let mut backend = args.common.backend.start()?;
    eprintln!("finding the pixels the move resets");
    let reset = error_report::reset_pixels(backend.as_mut(), &scene, &settings)?;
    let modes = if args.modes.is_empty() {
        MoveMode::ALL.to_vec()
    } else {
        args.modes.clone()
    };
    let mut runs = Vec::new();
    for mode in modes {
        if interrupt::requested() {
            break;
        }
        eprintln!("measuring {}", mode.name());
        runs.push(error_report::run_mode(
            backend.as_mut(),
            &scene,
            mode,
            &settings,
            truth,
            &reset,
            &interrupt::requested,
        )?);
    }
    let restart = runs.iter().find(|r| r.mode == MoveMode::Restart);
    let perfect = match restart {
        Some(restart) if !interrupt::requested() => {
            eprintln!("measuring the perfect-compensation bound");
            error_report::perfect_compensation(
                backend.as_mut(),
                &scene,
                &settings,
                truth,
                &reset,
                restart,
                &interrupt::requested,
            )?
        }
        _ => None,
    }
    .unwrap_or_default();
    let interrupted = interrupt::requested();
    let target = error_report::restart_final_error(&runs);
    let perfect_time = target.and_then(|t| error_report::time_to_reach(&perfect, t));
    let out = &args.output;
    write_bytes(&out.join("error-vs-time.csv"), error_report::csv(&runs))?;
    let json = serde_json::json!({ "scene": scene.name, "settings": settings, "runs": runs,
        "reset_pixels": reset.iter().filter(|&&r| r).count(),
        "perfect_compensation": perfect,
        "seconds_to_restart_error": error_report::time_to_restart_error(&runs),
        "perfect_seconds_to_restart_error": perfect_time, "interrupted": interrupted });
    write_bytes(
        &out.join("error-vs-time.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    error_report::chart(&out.join("error-vs-time"), &scene.name, &runs, &perfect)?;
    print!("{}", error_report::tables(&runs, scene.triangle_count()));
    // The bound is measured only beside a restart run; without one there is nothing to say.
    let reached = error_report::time_to_restart_error(&runs)
        .into_iter()
        .map(|(mode, t)| (mode.name(), t))
        .chain((!perfect.is_empty()).then_some(("perfect", perfect_time)));
    for (name, t) in reached {
        match t {
            Some(t) => println!("{name:<10} reaches restart's final error after {t:.2}s"),
            None => println!(
                "{name:<10} does not reach restart's final error within {:.1}s",
                args.seconds
            ),
        }
    }
    for r in &runs {
        let fmt =
            |v: Option<f64>, digits: usize| v.map_or("-".to_owned(), |v| format!("{v:.digits$}"));
        let last_move = r.moves.last().map(|m| m.seconds * 1e3);
        println!(
            "{:<10} kept pixels' slope {} against the whole rendering time; brightest pixel {}x \
             the truth's after the move, {}x at the end; last move {} ms, an iteration {} ms",
            r.mode.name(),
            fmt(r.kept_slope, 2),
            fmt(r.brightest_after_move.map(f64::from), 2),
            fmt(r.brightest_final.map(f64::from), 2),
            fmt(last_move, 1),
            fmt(r.iteration_ms, 1)
        );
    }
    println!("wrote {}", out.display());
    if interrupted {
        return Err(Interrupted(format!(
            "{} of {} modes measured, the last one partly; rows so far in {}",
            runs.len(),
            MoveMode::ALL.len(),
            out.display()
        ))
        .into());
    }
    Ok(())
}
