//! `ppm`: render the canonical scenes, list them, and (later) compare backends.

use anyhow::{Context, Result, bail};
use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use clap::{Parser, Subcommand, ValueEnum};
use harness::dynamic::{DynamicParams, Mode, Progressive};
use harness::error_report::{self, ErrorSettings};
use harness::render::{Progress, render};
use indicatif::{ProgressBar, ProgressStyle};
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::passes::{Backend, DynamicBackend};
use ppm_core::scene::ExportOptions;
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
    /// Render a scene's move as an animation, carrying the light from frame to frame.
    Animate(AnimateArgs),
    /// Measurement reports.
    #[command(subcommand)]
    Report(ReportCommand),
    /// Run the stress family (extreme scales, powers, geometry) and check every invariant.
    Stress(StressArgs),
    /// Write a scene for Mitsuba 3 or pbrt-v4 (scene file and PLY meshes), to check us
    /// against another renderer.
    Export(ExportArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum ExportFormat {
    /// Mitsuba 3 XML.
    Mitsuba,
    /// pbrt-v4.
    Pbrt,
}

#[derive(clap::Args)]
struct ExportArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Scene format to write.
    #[arg(long, value_enum)]
    format: ExportFormat,
    /// Samples per pixel the other renderer takes.
    #[arg(long, default_value_t = 1024)]
    spp: u32,
    /// Image width (default: the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (default: the scene's).
    #[arg(long)]
    height: Option<u32>,
    /// Folder to write the scene file and its meshes into.
    #[arg(short, long)]
    output: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
enum StressBackends {
    /// The CPU backend.
    Cpu,
    /// The wgpu backend.
    Wgpu,
    /// Both, one after the other.
    Both,
}

#[derive(clap::Args)]
struct StressArgs {
    /// Backends to run.
    #[arg(long, value_enum, default_value = "cpu")]
    backend: StressBackends,
    /// Run only this case (see the table for names).
    #[arg(long)]
    case: Option<String>,
    /// JSON report.
    #[arg(short, long, default_value = "out/stress.json")]
    output: PathBuf,
}

#[derive(Subcommand)]
enum ReportCommand {
    /// Relative RMSE against a from-scratch render of the new pose, over time, per mode.
    ErrorVsTime(ErrorArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeChoice {
    /// Start over on every frame (plain PPM).
    Restart,
    /// The thesis's compensation photons (point light, raw counts, unweighted guides).
    Thesis,
    /// Ours: compensation from the whole area light, weighted counts and guides.
    Area,
    /// Ours, unbiased: every light path traced in both poses; the difference compensates.
    Difference,
}

impl From<ModeChoice> for Mode {
    fn from(m: ModeChoice) -> Self {
        match m {
            ModeChoice::Restart => Mode::Restart,
            ModeChoice::Thesis => Mode::Thesis,
            ModeChoice::Area => Mode::Area,
            ModeChoice::Difference => Mode::Difference,
        }
    }
}

#[derive(clap::Args)]
struct DynamicArgs {
    /// Built-in scene name or path to a TOML scene file (its `[[moves]]` define the motion).
    scene: String,
    /// Backend.
    #[arg(long, value_enum, default_value = "cpu")]
    backend: BackendChoice,
    /// Image width.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// Photons per ordinary pass (default: the scene's).
    #[arg(long)]
    photons_per_pass: Option<u32>,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Shadow rays per hit point (their noise is fixed per frame: keep it below the error
    /// being measured).
    #[arg(long, default_value_t = 64)]
    direct_samples: u32,
    /// Compensation passes per move (and as many positive region passes).
    #[arg(long, default_value_t = 4)]
    compensation_passes: u32,
    /// Photons per compensation or region pass.
    #[arg(long, default_value_t = 65_536)]
    region_photons: u32,
    /// Half-angle of the guided photons' cone, degrees.
    #[arg(long, default_value_t = 10.0)]
    cone_deg: f32,
    /// Difference passes per move in difference mode (each a negative and a positive pass
    /// of the ordinary photon count).
    #[arg(long, default_value_t = 8)]
    difference_passes: u32,
}

impl DynamicArgs {
    fn dynamic(&self) -> DynamicParams {
        DynamicParams {
            compensation_passes: self.compensation_passes,
            region_photons: self.region_photons,
            cone_deg: self.cone_deg,
            difference_passes: self.difference_passes,
            ..DynamicParams::default()
        }
    }
}

#[derive(clap::Args)]
struct AnimateArgs {
    #[command(flatten)]
    common: DynamicArgs,
    /// Steps from frame 0 to frame 1 (the scene's move cut into equal parts).
    #[arg(long, default_value_t = 8)]
    steps: u32,
    /// How each step is handled.
    #[arg(long, value_enum, default_value = "area")]
    mode: ModeChoice,
    /// Seconds of passes per frame.
    #[arg(long, default_value_t = 2.0)]
    time_per_frame: f64,
    /// Output folder: frame-NNN.exr, .png and .json.
    #[arg(short, long)]
    output: PathBuf,
}

#[derive(clap::Args)]
struct ErrorArgs {
    #[command(flatten)]
    common: DynamicArgs,
    /// Seconds of ordinary passes on frame 0 before the move.
    #[arg(long, default_value_t = 10.0)]
    warmup: f64,
    /// Seconds measured after the move.
    #[arg(long, default_value_t = 8.0)]
    seconds: f64,
    /// Photon passes of the from-scratch reference of frame 1 (cached).
    #[arg(long, default_value_t = 400)]
    reference_passes: u32,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    cache: PathBuf,
    /// Output folder: error-vs-time.csv, .json and .png.
    #[arg(short, long)]
    output: PathBuf,
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
    /// Built-in scene name (see `ppm scenes`) or path to a scene file: TOML, Mitsuba 3 (.xml)
    /// or pbrt-v4 (.pbrt).
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
        Command::Animate(args) => run_animate(args),
        Command::Report(ReportCommand::ErrorVsTime(args)) => run_error_report(args),
        Command::Stress(args) => run_stress(args),
        Command::Export(args) => run_export(args),
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

/// The backend a dynamic command asked for.
fn dynamic_backend(choice: BackendChoice) -> Result<Box<dyn DynamicBackend>> {
    Ok(match choice {
        BackendChoice::Cpu => Box::new(CpuBackend::new()),
        BackendChoice::Wgpu => {
            let b = WgpuBackend::new().context("the wgpu backend cannot start")?;
            eprintln!("wgpu adapter: {}", b.adapter_name());
            Box::new(b)
        }
    })
}

/// The scene and render settings of a dynamic command.
fn dynamic_setup(a: &DynamicArgs) -> Result<(ppm_core::scene::Scene, RenderParams)> {
    let scene = harness::load_scene(&a.scene)?;
    if scene.moves.is_empty() {
        bail!(
            "{}: the scene has no [[moves]]: nothing to animate",
            a.scene
        );
    }
    let mut params = RenderParams::for_scene(&scene);
    params.width = a.width;
    params.height = a.height;
    params.photons_per_pass = a.photons_per_pass.unwrap_or(params.photons_per_pass);
    params.seed = a.seed;
    params.direct_samples = a.direct_samples;
    params.validate("command line")?;
    Ok((scene, params))
}

fn run_animate(args: AnimateArgs) -> Result<()> {
    let (scene, params) = dynamic_setup(&args.common)?;
    if args.steps == 0 {
        bail!("--steps = 0: must be at least 1");
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("-o {}: cannot create", args.output.display()))?;
    let mode = Mode::from(args.mode);
    let mut backend = dynamic_backend(args.common.backend)?;
    let features = ppm_core::compile::compile_scene(&scene, params.width, params.height).features;
    let left_out = harness::report::left_out(&features, &params, false);
    let mut render = Progressive::start(
        backend.as_mut(),
        scene.at_time(0.0),
        &params,
        &args.common.dynamic(),
    )?;
    for step in 0..=args.steps {
        let start = std::time::Instant::now();
        let moved = if step == 0 {
            None
        } else {
            Some(render.move_to(scene.at_time(step as f32 / args.steps as f32), mode)?)
        };
        let mut passes = 0;
        while start.elapsed().as_secs_f64() < args.time_per_frame {
            if step == 0 {
                render.ordinary_pass()?
            } else {
                render.step()?
            };
            passes += 1;
        }
        let image = render.resolve()?;
        let stem = args.output.join(format!("frame-{step:03}"));
        image.write_exr(&stem.with_extension("exr"))?;
        image.write_png(&stem.with_extension("png"), 1.0)?;
        let report = serde_json::json!({
            "scene": scene.name, "frame": step, "steps": args.steps, "mode": mode,
            "passes": passes, "seconds": start.elapsed().as_secs_f64(), "move": moved,
            "photons": render.counts, "left_out": left_out,
        });
        std::fs::write(
            stem.with_extension("json"),
            serde_json::to_string_pretty(&report)?,
        )?;
        println!(
            "frame {step}: {passes} passes, {:.2}s -> {}",
            start.elapsed().as_secs_f64(),
            stem.with_extension("exr").display()
        );
    }
    Ok(())
}

fn run_error_report(args: ErrorArgs) -> Result<()> {
    let (scene, params) = dynamic_setup(&args.common)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("-o {}: cannot create", args.output.display()))?;
    let settings = ErrorSettings {
        params,
        dynamic: args.common.dynamic(),
        warmup_seconds: args.warmup,
        seconds: args.seconds,
        reference_passes: args.reference_passes,
    };
    let mut backend = dynamic_backend(args.common.backend)?;
    let cached = error_report::reference_path(&args.cache, &scene, &settings);
    eprintln!("reference: {}", cached.display());
    let truth = error_report::reference(backend.as_mut(), &scene, &settings, &cached)
        .map_err(|e| anyhow::anyhow!("reference render: {e}"))?;
    eprintln!("finding the pixels the move resets");
    let reset = error_report::reset_pixels(backend.as_mut(), &scene, &settings)?;
    let mut runs = Vec::new();
    for mode in Mode::ALL {
        eprintln!("measuring {}", mode.name());
        runs.push(error_report::run_mode(
            backend.as_mut(),
            &scene,
            mode,
            &settings,
            &truth,
            &reset,
        )?);
    }
    eprintln!("measuring the perfect-compensation bound");
    let perfect = error_report::perfect_compensation(
        backend.as_mut(),
        &scene,
        &settings,
        &truth,
        &reset,
        runs.iter()
            .find(|r| r.mode == Mode::Restart)
            .context("the restart run is missing")?,
    )?;
    let target = error_report::restart_final_error(&runs);
    let perfect_time = target.and_then(|t| error_report::time_to_reach(&perfect, t));
    let triangles = scene.triangle_count();
    let out = &args.output;
    std::fs::write(out.join("error-vs-time.csv"), error_report::csv(&runs))?;
    let json = serde_json::json!({ "scene": scene.name, "settings": settings, "runs": runs,
        "reset_pixels": reset.iter().filter(|&&r| r).count(),
        "perfect_compensation": perfect,
        "seconds_to_restart_error": error_report::time_to_restart_error(&runs),
        "perfect_seconds_to_restart_error": perfect_time });
    std::fs::write(
        out.join("error-vs-time.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    error_report::chart(&out.join("error-vs-time"), &scene.name, &runs, &perfect)?;
    print!("{}", error_report::tables(&runs, triangles));
    let reached = error_report::time_to_restart_error(&runs)
        .into_iter()
        .map(|(mode, t)| (mode.name(), t))
        .chain([("perfect", perfect_time)]);
    for (name, t) in reached {
        match t {
            Some(t) => println!("{name:<10} reaches restart's final error after {t:.2}s"),
            None => println!(
                "{name:<10} does not reach restart's final error within {:.1}s",
                args.seconds
            ),
        }
    }
    println!("wrote {}", out.display());
    Ok(())
}

fn run_export(args: ExportArgs) -> Result<()> {
    if args.frame > 1 {
        bail!("--frame = {}: a scene has frames 0 and 1 only", args.frame);
    }
    if args.spp == 0 {
        bail!("--spp = 0: must be at least 1");
    }
    let mut scene = harness::load_scene(&args.scene)?.at_frame(args.frame);
    for (option, value, size) in [
        ("--width", args.width, &mut scene.camera.width),
        ("--height", args.height, &mut scene.camera.height),
    ] {
        match value {
            Some(0) => bail!("{option} = 0: must be at least 1"),
            Some(v) => *size = v,
            None => {}
        }
    }
    let options = ExportOptions {
        samples_per_pixel: args.spp,
        frame: args.frame,
    };
    let export = match args.format {
        ExportFormat::Mitsuba => ppm_core::scene::mitsuba::export_mitsuba(&scene, &options),
        ExportFormat::Pbrt => ppm_core::scene::pbrt::export_pbrt(&scene, &options),
    };
    let path = export.write(&args.output)?;
    println!(
        "{}: frame {}, {} meshes, {} triangles -> {}",
        scene.name,
        args.frame,
        export.meshes.len(),
        scene.triangle_count(),
        path.display()
    );
    println!("not expressed exactly (also listed in the file):");
    for note in &export.notes {
        println!("- {note}");
    }
    Ok(())
}

fn run_stress(args: StressArgs) -> Result<()> {
    let cases: Vec<&scenes::stress::StressCase> = match &args.case {
        Some(name) => vec![scenes::stress::stress_case(name).with_context(|| {
            let names: Vec<&str> = scenes::stress::STRESS.iter().map(|c| c.name).collect();
            format!("--case {name}: no such case (cases: {})", names.join(", "))
        })?],
        None => scenes::stress::STRESS.iter().collect(),
    };
    let mut backends: Vec<Box<dyn DynamicBackend>> = Vec::new();
    if matches!(args.backend, StressBackends::Cpu | StressBackends::Both) {
        backends.push(Box::new(CpuBackend::new()));
    }
    if matches!(args.backend, StressBackends::Wgpu | StressBackends::Both) {
        let b = WgpuBackend::new().context("the wgpu backend cannot start")?;
        eprintln!("wgpu adapter: {}", b.adapter_name());
        backends.push(Box::new(b));
    }
    let mut results = Vec::new();
    for case in cases {
        for backend in &mut backends {
            results.push(harness::stress::run_case(backend.as_mut(), case));
        }
    }
    print!("{}", harness::stress::table(&results));
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&args.output, serde_json::to_string_pretty(&results)?)
        .with_context(|| format!("{}: cannot write", args.output.display()))?;
    let failed = results.iter().filter(|r| !r.passed).count();
    if failed > 0 {
        bail!("{failed} of {} stress runs failed", results.len());
    }
    println!(
        "all {} stress runs passed; wrote {}",
        results.len(),
        args.output.display()
    );
    Ok(())
}
