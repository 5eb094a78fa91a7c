//! `ppm render`, `ppm reference` and `ppm compare`: one image, its truth, and the distance
//! between two images.

use crate::cli::interrupt::{self, Interrupted};
use crate::cli::options::{BackendChoice, RenderOptions, check_frame, spp_bar};
use crate::convergence;
use crate::driver::checkpoint::RenderState;
use crate::driver::{
    Budget, Observer, ObserverResult, Progress, Renderer, Resume, Schedule, Stoppable, run_from,
};
use crate::reference::{ReferenceBudget, Truth, render_reference_shard, variance_path};
use crate::report::RenderReport;
use crate::shard::Shard;
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use ppm_core::image::Image;
use ppm_core::limits::{MemoryBudget, check_reference_memory};
use ppm_core::params::{MoveParams, RenderParams};
use scenes::file::image::ImageFiles;
use scenes::file::output::{check_writable_folder, write_bytes};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Built-in scene name (see `ppm scenes`) or path to a scene file: TOML, Mitsuba 3 (.xml)
    /// or pbrt-v4 (.pbrt).
    scene: String,
    /// Backend that runs the passes: cpu, wgpu, or another registered one (`ppm backends`).
    #[arg(long, default_value = "cpu")]
    backend: BackendChoice,
    #[command(flatten)]
    options: RenderOptions,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Render shard I of N (0-based): an independent run with its own seed (derived from
    /// --seed and I), which `ppm merge` averages with the others by their iterations.
    #[arg(long, value_parser = Shard::parse)]
    shard: Option<Shard>,
    /// Keep the render's whole state in this folder (every --checkpoint-every seconds, on
    /// Ctrl-C or SIGTERM, and at the end), to continue it later with --resume.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Seconds of rendering between checkpoints.
    #[arg(long, default_value_t = 60.0, requires = "checkpoint")]
    checkpoint_every: f64,
    /// Continue the render whose state this folder holds, bit for bit as if it had never
    /// stopped (same scene, settings and backend; --passes and --time-budget count the whole
    /// render, the part before included).
    #[arg(long)]
    resume: Option<PathBuf>,
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

pub fn render(args: RenderArgs) -> Result<()> {
    interrupt::install()?;
    let scene = crate::load_scene(&args.scene)?;
    let mut params = args.options.params(&scene, None)?;
    if let Some(shard) = args.shard {
        params.seed = shard.seed(params.seed);
    }
    check_frame(args.frame)?;
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure = {}: must be a positive number", args.exposure);
    }
    let paths = OutputPaths::new(&args.output)?;
    let pool = thread_pool(args.threads)?;
    let bar = progress_bar(&params);
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every > 0.0) {
        bail!(
            "--checkpoint-every = {}: must be a positive number of seconds",
            args.checkpoint_every
        );
    }
    if let Some(dir) = &args.checkpoint {
        output_folder(dir, &format!("--checkpoint {}", dir.display()))?;
    }
    let read = std::time::Instant::now();
    let resumed = match &args.resume {
        Some(dir) => Some(RenderState::read(dir)?),
        None => None,
    };
    if let Some(state) = &resumed {
        eprintln!(
            "resume: {} iterations, {:.1} MB of slots read in {:.0} ms",
            state.report.passes,
            state.slots as f64 * size_of::<ppm_core::layout::HitPoint>() as f64 / 1e6,
            read.elapsed().as_secs_f64() * 1e3
        );
    }
    let mut backend = args.backend.start()?;
    let (done, before) = resumed
        .as_ref()
        .map_or((0, 0.0), |s| (s.report.passes, s.seconds));
    let budget = Budget {
        iterations: Some(match params.passes {
            u32::MAX => u32::MAX,
            n => n.saturating_sub(done),
        }),
        seconds: params.time_budget.map(|t| (t - before).max(0.0)),
    };
    let mut progress = Progressing {
        bar: &bar,
        checkpoint: args.checkpoint.clone().map(|dir| Checkpointing {
            dir,
            every: args.checkpoint_every,
            last: 0.0,
            before,
        }),
    };
    eprintln!(
        "rendering {} ({}) on {}: {}x{}{}",
        scene.name,
        params.estimator.name(),
        backend.name(),
        params.width,
        params.height,
        match &args.resume {
            Some(dir) => format!(", resuming {} after {done} iterations", dir.display()),
            None => String::new(),
        }
    );
    let outcome = pool.install(|| {
        let mut observer = Stoppable {
            observer: &mut progress,
            stop: &interrupt::requested,
        };
        let resume = match (&resumed, &args.resume) {
            (Some(state), Some(dir)) => Some(Resume { state, dir }),
            _ => None,
        };
        run_from(
            backend.as_mut(),
            &scene,
            &params,
            &MoveParams::default(),
            &Schedule::frame(args.frame, budget),
            &mut observer,
            resume,
        )
    })?;
    bar.finish_and_clear();

    let mut report = outcome.report.clone();
    report.shard = args.shard;
    write_render(outcome.image.clone(), report, &paths, args.exposure)?;
    let r = &outcome.report;
    println!(
        "{} ({}): {} iterations, {} photons emitted, {} deposited, {:.2}s -> {}, {}, {}",
        r.scene,
        params.estimator.name(),
        r.passes,
        r.photons_emitted,
        r.photons_deposited,
        r.times.total,
        paths.exr.display(),
        paths.png.display(),
        paths.json.display()
    );
    if let Some(e) = outcome.error {
        bail!("render stopped early (the image holds the iterations before it): {e}");
    }
    if outcome.stopped {
        return Err(Interrupted(format!(
            "the image holds the {} iterations completed ({})",
            r.passes,
            paths.exr.display()
        ))
        .into());
    }
    Ok(())
}

/// The progress bar, and the checkpoints when asked for.
struct Progressing<'a> {
    bar: &'a ProgressBar,
    checkpoint: Option<Checkpointing>,
}

/// Where and how often checkpoints are written.
struct Checkpointing {
    dir: PathBuf,
    /// Seconds of rendering between two.
    every: f64,
    /// Seconds of this run at the last one.
    last: f64,
    /// Seconds rendered before this run (a resumed render's).
    before: f64,
}

impl Checkpointing {
    /// Writes the state `seconds` into this run; says how large it was and how long it took.
    fn write(
        &mut self,
        renderer: &mut Renderer,
        seconds: f64,
        bar: &ProgressBar,
    ) -> ObserverResult {
        let t = std::time::Instant::now();
        let state = renderer.snapshot(self.before + seconds)?;
        state.write(&self.dir)?;
        self.last = seconds;
        bar.suspend(|| {
            eprintln!(
                "checkpoint: {} iterations, {:.1} MB of slots in {:.0} ms -> {}",
                state.report.passes,
                state.slots as f64 * size_of::<ppm_core::layout::HitPoint>() as f64 / 1e6,
                t.elapsed().as_secs_f64() * 1e3,
                self.dir.display()
            )
        });
        Ok(())
    }
}

impl Observer for Progressing<'_> {
    fn iteration(&mut self, at: &Progress, renderer: &mut Renderer) -> ObserverResult {
        self.bar.set_position(u64::from(at.iterations));
        self.bar.set_message(format!("{:.1}s", at.seconds));
        match &mut self.checkpoint {
            // An interrupt stops the run after this iteration: keep its state first.
            Some(c) if at.seconds - c.last >= c.every || interrupt::requested() => {
                c.write(renderer, at.seconds, self.bar)
            }
            _ => Ok(()),
        }
    }

    fn step_done(&mut self, at: &Progress, renderer: &mut Renderer) -> ObserverResult {
        match &mut self.checkpoint {
            Some(c) => c.write(renderer, at.seconds, self.bar),
            None => Ok(()),
        }
    }
}

/// Writes a render's three files: the EXR, its PNG preview at `exposure`, and the JSON report.
/// Non-finite pixels are written as zero and counted in the report.
pub fn write_render(
    mut image: Image,
    mut report: RenderReport,
    paths: &OutputPaths,
    exposure: f32,
) -> Result<()> {
    for p in image.pixels.iter_mut().flatten().filter(|v| !v.is_finite()) {
        *p = 0.0;
        report.non_finite_pixels_zeroed += 1;
    }
    image.write_exr(&paths.exr)?;
    image.write_png(&paths.png, exposure)?;
    let json = serde_json::to_string_pretty(&report)?;
    write_bytes(&paths.json, json)
        .with_context(|| format!("{}: cannot write report", paths.json.display()))
}

/// The three files a render writes, side by side.
pub struct OutputPaths {
    pub exr: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
}

impl OutputPaths {
    /// Checks before hours of rendering, not after, that the three files can be written:
    /// see [`output_folder`]; none of them may be a folder.
    pub fn new(output: &Path) -> Result<Self> {
        if output.extension().and_then(|e| e.to_str()) != Some("exr") {
            bail!("-o {}: the output must be an .exr file", output.display());
        }
        let paths = Self {
            exr: output.to_path_buf(),
            png: output.with_extension("png"),
            json: output.with_extension("json"),
        };
        let parent = output.parent().unwrap_or(Path::new(""));
        output_folder(parent, &format!("-o {}", output.display()))?;
        for path in [&paths.exr, &paths.png, &paths.json] {
            if path.is_dir() {
                bail!(
                    "-o {}: {} is a folder, and would not be replaced by a file",
                    output.display(),
                    path.display()
                );
            }
        }
        Ok(paths)
    }
}

/// Makes `dir` ready for outputs before anything renders: created when missing (as `mkdir
/// -p` would: `-o out/x.exr` works in a fresh checkout, and a typo shows in the path
/// printed at the end), then probed by creating a file in it, so that a read-only folder or
/// file system is refused now. `option` names it in errors (`-o out/x.exr`).
pub fn output_folder(dir: &Path, option: &str) -> Result<()> {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{option}: cannot create the folder {}", dir.display()))?;
    check_writable_folder(dir).with_context(|| {
        format!(
            "{option}: cannot write files in {} (nothing was rendered)",
            dir.display()
        )
    })
}

/// Most worker threads `--threads` may ask for: rayon starts all of them at once, each with
/// its own stack, and threads beyond the cores only take turns; 1024 is beyond the cores of
/// any machine this runs on, and a larger number is a typo, not a setting.
const MAX_THREADS: usize = 1024;

pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    match threads {
        Some(0) => bail!("--threads = 0: must be at least 1 (leave it out for one per core)"),
        Some(n) if n > MAX_THREADS => bail!(
            "--threads = {n}: at most {MAX_THREADS} (this machine has {} cores; leave it out \
             for one per core)",
            std::thread::available_parallelism().map_or(1, |c| c.get())
        ),
        _ => {}
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")
}

fn progress_bar(params: &RenderParams) -> ProgressBar {
    let bar = if params.passes == u32::MAX {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(u64::from(params.passes))
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} iteration {pos}/{len} {bar:30} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

#[derive(clap::Args)]
pub struct ReferenceArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// A path file (objects and camera moved from frame 0): render the pose at its end, the
    /// truth of `ppm report error-vs-time --path FILE`.
    #[arg(long, conflicts_with = "frame")]
    path: Option<PathBuf>,
    /// Image width (default: the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (default: the scene's).
    #[arg(long)]
    height: Option<u32>,
    /// Samples per pixel, rounded up to a multiple of 8 (default 1024; unbounded when only
    /// --time-budget is given).
    #[arg(long)]
    spp: Option<u32>,
    /// Stop after this many seconds.
    #[arg(long)]
    time_budget: Option<f64>,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Render only the rows y with y % N == I (0-based), exactly as one run of the whole
    /// image renders them; `ppm merge` joins the N shards into that run, bit for bit.
    #[arg(long, value_parser = Shard::parse)]
    shard: Option<Shard>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Output EXR; the PNG preview, the variance (NAME.var.exr) and a JSON summary are
    /// written beside it.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn reference(args: ReferenceArgs) -> Result<()> {
    interrupt::install()?;
    let scene = crate::load_scene(&args.scene)?;
    check_frame(args.frame)?;
    let width = args.width.unwrap_or(scene.camera.width);
    let height = args.height.unwrap_or(scene.camera.height);
    if width == 0 || height == 0 {
        bail!("--width {width} --height {height}: the image must be at least 1x1");
    }
    if args.spp == Some(0) {
        bail!("--spp = 0: must be at least 1");
    }
    check_reference_memory(width, height, &MemoryBudget::detect())?;
    if let Some(t) = args.time_budget
        && !(t.is_finite() && t > 0.0)
    {
        bail!("--time-budget = {t}: must be a positive number of seconds");
    }
    let budget = ReferenceBudget {
        spp: args.spp.or(args.time_budget.is_none().then_some(1024)),
        seconds: args.time_budget,
    };
    let paths = OutputPaths::new(&args.output)?;
    let pool = thread_pool(args.threads)?;
    let posed = match &args.path {
        Some(file) => scenes::file::path::load_path_file(file, &scene)?.final_pose(&scene),
        None => scene.at_frame(args.frame),
    };
    let compiled = ppm_core::compile::compile_scene(&posed, width, height);
    eprintln!(
        "rendering the reference of {} at {width}x{height}",
        scene.name
    );
    let bar = spp_bar(budget.spp);
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let reference = pool.install(|| {
        render_reference_shard(&compiled, args.seed, budget, shard, &mut |spp, s| {
            bar.set_position(u64::from(spp));
            bar.set_message(format!("{s:.1}s"));
            interrupt::flow()
        })
    });
    bar.finish_and_clear();
    let summary = reference.summary(&scene.name, args.frame, args.seed, shard);
    reference.write(&paths.exr, &summary)?;
    println!(
        "{}: {} spp in {:.2}s ({:.3e} paths/s), expected relative error {:.4} -> {}",
        scene.name,
        summary.spp,
        summary.seconds,
        summary.samples_per_second,
        summary.relative_noise,
        paths.exr.display()
    );
    if let Some(e) = reference.error {
        bail!("the path tracer stopped early (the image holds the samples before it): {e}");
    }
    if reference.interrupted {
        return Err(Interrupted(format!(
            "the image holds the {} samples per pixel completed ({})",
            summary.spp,
            paths.exr.display()
        ))
        .into());
    }
    Ok(())
}

#[derive(clap::Args)]
pub struct CompareArgs {
    /// The image measured.
    image: PathBuf,
    /// The reference it is measured against (a NAME.var.exr beside it gives its noise).
    reference: PathBuf,
    /// Also write a heat map of the difference (red: per-pixel luminance difference over the
    /// reference's mean luminance, full at 10%) as EXR and PNG.
    #[arg(long)]
    heatmap: Option<PathBuf>,
}

pub fn compare(args: CompareArgs) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_file(&args.reference, false)
        .with_context(|| format!("{}: cannot read", args.reference.display()))?;
    let size = meta
        .headers
        .first()
        .map(|h| h.layer_size)
        .with_context(|| format!("{}: no image layer", args.reference.display()))?;
    let (width, height) = (size.width() as u32, size.height() as u32);
    let truth = Truth::from_exr(&args.reference, width, height)?;
    let image = scenes::file::image::read_exr(&args.image, width, height)?;
    let p = convergence::measure(&image, &truth, 0.0, 0);
    if let Some(path) = &args.heatmap {
        let heat = crate::diff::same_seed::heat(&truth.image, &image);
        heat.write_exr(&path.with_extension("exr"))?;
        heat.write_png(&path.with_extension("png"), 10.0)?;
    }
    println!(
        "{width}x{height}: pixel relative rmse {:.5}, 8x8 block relative rmse {:.5}, mean ratio {:.5}",
        p.rel_rmse, p.block_rel_rmse, p.mean_ratio
    );
    match (truth.noise(), p.rel_rmse_corrected) {
        (Some(n), Some(c)) => {
            println!("reference noise {n:.5}; pixel relative rmse without it {c:.5}")
        }
        _ => println!(
            "reference noise unknown (no {} beside it)",
            variance_path(&args.reference).display()
        ),
    }
    Ok(())
}
