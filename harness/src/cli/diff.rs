//! `ppm diff`: renders one seeded scene on two backends (the first is the reference), still
//! or through moves, prints the comparison as a table, writes `diff.json` and a heat map, and
//! fails when they disagree.

use crate::cli::options::BackendChoice;
use crate::cli::render::output_folder;
use crate::diff::history::{self, pixel_history};
use crate::diff::independent;
use crate::diff::same_seed;
use crate::diff::{
    OTHER_SEED_OFFSET, Recording, record_schedule_from, runs_of_schedule, state_after,
};
use crate::driver::checkpoint::RenderState;
use crate::driver::{Budget, Resume, Schedule};
use anyhow::{Result, bail};
use ppm_core::limits::{MemoryBudget, check_render_memory};
use ppm_core::params::{Estimator, MoveMode, MoveParams, RenderParams};
use ppm_core::scene::Scene;
use ppm_core::scene::path::After;
use scenes::file::image::ImageFiles;
use scenes::file::output::write_bytes;
use scenes::file::path::load_path_file;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct DiffArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Progressive estimator (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(Estimator))]
    estimator: Option<Estimator>,
    /// Iterations.
    #[arg(long, default_value_t = 8)]
    passes: u32,
    /// Photons per pass.
    #[arg(long, default_value_t = 100_000)]
    photons_per_pass: u32,
    /// Image width.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// Seed (independent mode: the first of each backend's seeds).
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Fraction of new photons kept per pass, in (0, 1) (default: the scene's).
    #[arg(long)]
    alpha: Option<f32>,
    /// Initial gather radius in scene units, not squared (default: the scene's).
    #[arg(long)]
    radius: Option<f32>,
    /// Eye samples (slots) per pixel.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// The two backends compared, the reference first, by registered name (`ppm backends`;
    /// `cpu,cpu` checks one backend against itself).
    #[arg(long, value_delimiter = ',', default_value = "cpu,wgpu")]
    backends: Vec<BackendChoice>,
    /// Compare through the scene's move in this mode: `--passes` iterations on frame 0, the
    /// move, `--passes` more; the slots are compared after every iteration and the move.
    #[arg(long, value_parser = clap::value_parser!(MoveMode))]
    mode: Option<MoveMode>,
    /// Compare along a path file's moves instead (`local` unless --mode says otherwise),
    /// `--passes` iterations after the last; its steps must wait iterations, not seconds,
    /// so that both backends move at the same iteration.
    #[arg(long)]
    path: Option<PathBuf>,
    /// Compare slot by slot with one seed (the default).
    #[arg(long, conflicts_with = "independent")]
    same_seed: bool,
    /// Compare statistically, each backend with its own seeds.
    #[arg(long)]
    independent: bool,
    /// Runs per backend in independent mode (at least 2: a t-test needs a spread).
    #[arg(long, default_value_t = 4)]
    runs: u32,
    /// Print the slot history of pixel X,Y on both backends instead.
    #[arg(long, value_parser = parse_pixel)]
    pixel: Option<(u32, u32)>,
    /// When a same-seed comparison of a still frame finds the backends part, write the
    /// reference backend's state just before the first step where they do (a checkpoint
    /// folder), to re-run that step alone with --replay.
    #[arg(long, conflicts_with_all = ["independent", "pixel", "mode", "path", "replay"])]
    save_state: Option<PathBuf>,
    /// Start both backends from a state written by --save-state (give the same scene and
    /// options) and compare the --passes iterations after it.
    #[arg(long, conflicts_with_all = ["independent", "mode", "path"])]
    replay: Option<PathBuf>,
    /// Folder for diff.json and the heat map (heatmap.exr, heatmap.png).
    #[arg(short, long, default_value = "out/diff")]
    output: PathBuf,
}

fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("--pixel {s}: expected X,Y"))?;
    let n = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("--pixel {s}: {e}"))
    };
    Ok((n(x)?, n(y)?))
}

/// Runs the comparison; `Err` when the backends disagree or cannot run.
pub fn run(args: DiffArgs) -> Result<()> {
    let scene = crate::load_scene(&args.scene)?;
    let mut params = RenderParams::for_scene(&scene);
    if let Some(e) = args.estimator {
        params.estimator = e;
        params.direct_samples = e.default_direct_samples();
    }
    params.passes = args.passes;
    params.photons_per_pass = args.photons_per_pass;
    params.width = args.width;
    params.height = args.height;
    params.seed = args.seed;
    params.alpha = args.alpha.unwrap_or(params.alpha);
    params.initial_radius = args.radius.unwrap_or(params.initial_radius);
    params.spp = args.spp;
    params.validate("command line")?;
    let [first, second] = &args.backends[..] else {
        bail!(
            "--backends: expected two backends, A,B (got {})",
            args.backends.len()
        );
    };
    let schedule = schedule(&args, &scene)?;
    check_render_memory(&params, &scene, &MemoryBudget::detect())?;
    if args.independent && args.runs < 2 {
        bail!(
            "--runs = {}: the independent test needs at least 2 runs per backend",
            args.runs
        );
    }
    if let Some((x, y)) = args.pixel
        && (x >= params.width || y >= params.height)
    {
        bail!(
            "--pixel {x},{y}: outside the {}x{} image",
            params.width,
            params.height
        );
    }
    output_folder(&args.output, &format!("-o {}", args.output.display()))?;
    let (mut a_backend, mut b_backend) = (first.start()?, second.start()?);
    let (a_name, b_name) = (a_backend.name().to_owned(), b_backend.name().to_owned());
    let moves = MoveParams::default();
    let replayed = match &args.replay {
        Some(dir) => Some((RenderState::read(dir)?, dir)),
        None => None,
    };
    if let Some((state, dir)) = &replayed {
        println!(
            "replaying {} from its state after {} iterations",
            dir.display(),
            state.report.passes
        );
    }
    let record = |backend: &mut dyn ppm_core::passes::Backend| {
        let resume = replayed.as_ref().map(|(state, dir)| Resume {
            state,
            dir: dir.as_path(),
        });
        record_schedule_from(backend, &scene, &params, &moves, &schedule, resume)
    };
    if let Some((x, y)) = args.pixel {
        let a = record(a_backend.as_mut())?;
        let b = record(b_backend.as_mut())?;
        let rows = pixel_history(&[&a, &b], &params, x, y);
        print!("{}", history::format(&rows));
        write_bytes(
            &args.output.join("history.json"),
            serde_json::to_string_pretty(&rows)?,
        )?;
    } else if args.independent {
        let runs = |backend: &mut dyn ppm_core::passes::Backend, offset| {
            runs_of_schedule(
                backend, &scene, &params, &moves, &schedule, args.runs, offset,
            )
        };
        let a = runs(a_backend.as_mut(), 0)?;
        let b = runs(b_backend.as_mut(), OTHER_SEED_OFFSET)?;
        let report = independent::compare((&a_name, &a), (&b_name, &b), &params, 10);
        print!("{}", independent::format(&report));
        write_outputs(&args, &report, &independent::heat(&a, &b, &params))?;
        if !report.agree {
            bail!("the backends disagree (independent seeds)");
        }
    } else {
        let a = record(a_backend.as_mut())?;
        let b = record(b_backend.as_mut())?;
        let report = same_seed::compare(&a, &b, &params, 10);
        print!("{}", same_seed::format(&report));
        write_outputs(&args, &report, &same_seed::heat(&a.image, &b.image))?;
        if let Some(dir) = &args.save_state {
            save_state(dir, a_backend.as_mut(), &scene, &params, &a, &b)?;
        }
        if !report.agree {
            bail!("the backends disagree (same seed)");
        }
    }
    Ok(())
}

/// Writes into `dir` the reference backend's state just before the first step where the
/// recordings `a` and `b` part, if they do.
fn save_state(
    dir: &std::path::Path,
    reference: &mut dyn ppm_core::passes::Backend,
    scene: &Scene,
    params: &RenderParams,
    a: &Recording,
    b: &Recording,
) -> Result<()> {
    let Some(step) = same_seed::first_disagreement(a, b) else {
        println!("no step disagreed: no state saved");
        return Ok(());
    };
    let state = state_after(reference, scene, params, step - 1)?;
    state.write(dir)?;
    println!(
        "the backends part at iteration {step}: {}'s state after {} iterations is in {} \
         (ppm diff ... --replay {} --passes 1 re-runs that iteration alone)",
        a.backend,
        step - 1,
        dir.display(),
        dir.display()
    );
    Ok(())
}

/// What both backends run: frame 0, the scene's move in `--mode`, or a path file's moves.
fn schedule(args: &DiffArgs, scene: &Scene) -> Result<Schedule> {
    let budget = Budget::iterations(args.passes);
    let mode = args.mode.unwrap_or(MoveMode::Local);
    if let Some(file) = &args.path {
        let path = load_path_file(file, scene)?;
        if let Some(k) = path
            .events
            .iter()
            .position(|e| matches!(e.after, After::Seconds(_)))
        {
            bail!(
                "{}: step {} waits seconds; ppm diff needs after_iterations, so that both \
                 backends move at the same iteration",
                file.display(),
                k + 1
            );
        }
        return Ok(Schedule::path(&path, mode, budget));
    }
    if args.mode.is_some() {
        if scene.moves.is_empty() {
            bail!(
                "--mode {}: {} declares no [[moves]]; give --path FILE",
                mode.name(),
                scene.name
            );
        }
        return Ok(Schedule::after_move(budget, mode, budget));
    }
    Ok(Schedule::frame(0, budget))
}

fn write_outputs(
    args: &DiffArgs,
    report: &impl serde::Serialize,
    heat: &ppm_core::image::Image,
) -> Result<()> {
    write_bytes(
        &args.output.join("diff.json"),
        serde_json::to_string_pretty(report)?,
    )?;
    heat.write_exr(&args.output.join("heatmap.exr"))?;
    // Full red at a 10% difference (same seed) or at p = 1e-10 (independent: -log10 p = 10).
    let scale = if !args.independent { 10.0 } else { 0.1 };
    heat.write_png(&args.output.join("heatmap.png"), scale)?;
    println!("wrote {}", args.output.display());
    Ok(())
}
