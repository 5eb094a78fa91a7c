//! `ppm render`, `ppm reference` and `ppm compare`: one image, its truth, and the distance
//! between two images.

use crate::interrupt::{self, Interrupted};
use crate::options::{BackendChoice, RenderOptions, check_frame, spp_bar};
use anyhow::{Context, Result, bail};
use harness::convergence;
use harness::driver::schedule::EachIteration;
use harness::driver::{Budget, Progress, Renderer, Schedule, Stoppable, run};
use harness::reference::{ReferenceBudget, Truth, render_reference, variance_path};
use harness::report::RenderReport;
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
    /// Backend that runs the passes.
    #[arg(long, value_enum, default_value = "cpu")]
    backend: BackendChoice,
    #[command(flatten)]
    options: RenderOptions,
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

pub fn render(args: RenderArgs) -> Result<()> {
    interrupt::install()?;
    let scene = harness::load_scene(&args.scene)?;
    let params = args.options.params(&scene, None)?;
    check_frame(args.frame)?;
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure = {}: must be a positive number", args.exposure);
    }
    let paths = OutputPaths::new(&args.output)?;
    let pool = thread_pool(args.threads)?;
    let bar = progress_bar(&params);
    let mut backend = args.backend.start()?;
    let budget = Budget {
        iterations: Some(params.passes),
        seconds: params.time_budget,
    };
    let mut progress = EachIteration(|at: &Progress, _: &mut Renderer| {
        bar.set_position(u64::from(at.iterations));
        bar.set_message(format!("{:.1}s", at.seconds));
        Ok(())
    });
    eprintln!(
        "rendering {} ({}) on {}: {}x{}",
        scene.name,
        params.estimator.name(),
        backend.name(),
        params.width,
        params.height
    );
    let outcome = pool.install(|| {
        let mut observer = Stoppable {
            observer: &mut progress,
            stop: &interrupt::requested,
        };
        run(
            backend.as_mut(),
            &scene,
            &params,
            &MoveParams::default(),
            &Schedule::frame(args.frame, budget),
            &mut observer,
        )
    })?;
    bar.finish_and_clear();

    write_render(
        outcome.image.clone(),
        outcome.report.clone(),
        &paths,
        args.exposure,
    )?;
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
    let scene = harness::load_scene(&args.scene)?;
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
    let compiled = ppm_core::compile::compile_scene(&scene.at_frame(args.frame), width, height);
    eprintln!(
        "rendering the reference of {} at {width}x{height}",
        scene.name
    );
    let bar = spp_bar(budget.spp);
    let reference = pool.install(|| {
        render_reference(&compiled, args.seed, budget, &mut |spp, s| {
            bar.set_position(u64::from(spp));
            bar.set_message(format!("{s:.1}s"));
            interrupt::flow()
        })
    });
    bar.finish_and_clear();
    let summary = reference.summary(&scene.name, args.frame, args.seed);
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
        let heat = harness::diff::same_seed::heat(&truth.image, &image);
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
