//! `ppm`: render the canonical scenes, list them, and (later) compare backends.

use anyhow::{Context, Result, bail};
use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use clap::{Parser, Subcommand, ValueEnum};
use harness::render::{Progress, render};
use indicatif::{ProgressBar, ProgressStyle};
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::passes::Backend;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "ppm",
    version,
    about = "Progressive photon mapping with compensation photons"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene progressively and write EXR, PNG and a JSON report.
    Render(RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Render one seeded scene on the CPU and wgpu backends and compare them.
    Diff(DiffArgs),
}

#[derive(clap::Args)]
struct DiffArgs {
    /// Built-in scene name or path to a TOML scene file.
    scene: String,
    /// Photon passes.
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
    /// Compare hit point by hit point with one seed (the default).
    #[arg(long, conflicts_with = "independent")]
    same_seed: bool,
    /// Compare statistically, each backend with its own seeds.
    #[arg(long)]
    independent: bool,
    /// Runs per backend in independent mode.
    #[arg(long, default_value_t = 4)]
    runs: u32,
    /// Print the hit-point history of pixel X,Y on both backends instead.
    #[arg(long, value_parser = parse_pixel)]
    pixel: Option<(u32, u32)>,
    /// Folder for diff.json and the heat map (heatmap.exr, heatmap.png).
    #[arg(short, long, default_value = "out/diff")]
    output: PathBuf,
}

impl From<DiffArgs> for harness::diff_command::DiffRequest {
    fn from(a: DiffArgs) -> Self {
        use harness::diff_command::DiffMode;
        let mode = match (a.pixel, a.independent) {
            (Some((x, y)), _) => DiffMode::Pixel { x, y },
            (None, true) => DiffMode::Independent { runs: a.runs },
            (None, false) => DiffMode::SameSeed,
        };
        Self {
            scene: a.scene,
            passes: a.passes,
            photons_per_pass: a.photons_per_pass,
            width: a.width,
            height: a.height,
            seed: a.seed,
            mode,
            output: a.output,
        }
    }
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

#[derive(Clone, Copy, ValueEnum)]
enum BackendChoice {
    /// rayon on this machine's cores.
    Cpu,
    /// WGSL compute shaders on the best wgpu adapter (a GPU, or lavapipe on the CPU).
    Wgpu,
}

#[derive(Clone, Copy, ValueEnum)]
enum DirectChoice {
    /// Shadow rays; photons skip their first surface (the thesis).
    Explicit,
    /// Photons carry direct light too (classic PPM).
    Photons,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Built-in scene name (see `ppm scenes`) or path to a TOML scene file.
    scene: String,
    /// Backend that runs the passes.
    #[arg(long, value_enum, default_value = "cpu")]
    backend: BackendChoice,
    /// Image width (default: the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (default: the scene's).
    #[arg(long)]
    height: Option<u32>,
    /// Photon passes (default: the scene's; unbounded when only --time-budget is given).
    #[arg(long)]
    passes: Option<u32>,
    /// Photons emitted per pass (default: the scene's).
    #[arg(long)]
    photons_per_pass: Option<u32>,
    /// Stop the photon passes after this many seconds.
    #[arg(long)]
    time_budget: Option<f64>,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Fraction of new photons kept per pass, in (0, 1) (default: the scene's).
    #[arg(long)]
    alpha: Option<f32>,
    /// Initial gather radius in scene units, not squared (default: the scene's).
    #[arg(long)]
    radius: Option<f32>,
    /// Eye samples per pixel (1 = through the pixel centre).
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Where direct light comes from.
    #[arg(long, value_enum, default_value = "explicit")]
    direct: DirectChoice,
    /// Shadow rays per hit point with explicit direct light.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Exposure multiplier of the PNG preview (the EXR is always linear).
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Output EXR; the PNG preview and JSON report are written beside it.
    #[arg(short, long)]
    output: PathBuf,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Scenes => {
            for s in scenes::BUILTIN {
                println!("{:<14} {}", s.name, s.description);
            }
            Ok(())
        }
        Command::Render(args) => run_render(args),
        Command::Diff(args) => harness::diff_command::run(&args.into()),
    }
}

fn run_render(args: RenderArgs) -> Result<()> {
    let scene = harness::load_scene(&args.scene)?;
    let mut params = RenderParams::for_scene(&scene);
    params.width = args.width.unwrap_or(params.width);
    params.height = args.height.unwrap_or(params.height);
    params.passes = match (args.passes, args.time_budget) {
        (Some(p), _) => p,
        (None, Some(_)) => u32::MAX,
        (None, None) => params.passes,
    };
    params.photons_per_pass = args.photons_per_pass.unwrap_or(params.photons_per_pass);
    params.time_budget = args.time_budget;
    params.seed = args.seed;
    params.alpha = args.alpha.unwrap_or(params.alpha);
    params.initial_radius = args.radius.unwrap_or(params.initial_radius);
    params.spp = args.spp;
    params.direct = match args.direct {
        DirectChoice::Explicit => DirectMode::Explicit,
        DirectChoice::Photons => DirectMode::Photons,
    };
    params.direct_samples = args.direct_samples;
    params.validate("command line")?;
    if args.frame > 1 {
        bail!("--frame = {}: a scene has frames 0 and 1 only", args.frame);
    }
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure = {}: must be a positive number", args.exposure);
    }
    let paths = OutputPaths::new(&args.output)?;

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let bar = progress_bar(&params);
    let mut backend: Box<dyn Backend + Send> = match args.backend {
        BackendChoice::Cpu => Box::new(CpuBackend::new()),
        BackendChoice::Wgpu => {
            let b = WgpuBackend::new().context("the wgpu backend cannot start")?;
            eprintln!("wgpu adapter: {}", b.adapter_name());
            Box::new(b)
        }
    };
    let outcome = pool.install(|| {
        render(
            backend.as_mut(),
            &scene,
            args.frame,
            &params,
            &mut |p: Progress, _: &mut dyn Backend| {
                bar.set_position(u64::from(p.pass));
                bar.set_message(format!("{:.1}s", p.elapsed));
            },
        )
    })?;
    bar.finish_and_clear();

    outcome.image.write_exr(&paths.exr)?;
    outcome.image.write_png(&paths.png, args.exposure)?;
    let json = serde_json::to_string_pretty(&outcome.report)?;
    std::fs::write(&paths.json, json)
        .with_context(|| format!("{}: cannot write report", paths.json.display()))?;
    let r = &outcome.report;
    println!(
        "{}: {} passes, {} photons emitted, {} deposited, {:.2}s -> {}, {}, {}",
        r.scene,
        r.passes,
        r.photons_emitted,
        r.photons_deposited,
        r.times.total,
        paths.exr.display(),
        paths.png.display(),
        paths.json.display()
    );
    if let Some(e) = outcome.error {
        bail!("render stopped early (the image holds the passes before it): {e}");
    }
    Ok(())
}

/// The three files a render writes, side by side.
struct OutputPaths {
    exr: PathBuf,
    png: PathBuf,
    json: PathBuf,
}

impl OutputPaths {
    /// Checks the folder exists (creating it) before hours of rendering, not after.
    fn new(output: &Path) -> Result<Self> {
        if output.extension().and_then(|e| e.to_str()) != Some("exr") {
            bail!("-o {}: the output must be an .exr file", output.display());
        }
        if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("-o {}: cannot create its folder", output.display()))?;
        }
        Ok(Self {
            exr: output.to_path_buf(),
            png: output.with_extension("png"),
            json: output.with_extension("json"),
        })
    }
}

fn progress_bar(params: &RenderParams) -> ProgressBar {
    let bar = if params.passes == u32::MAX {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(u64::from(params.passes))
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} pass {pos}/{len} {bar:30} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}
