//! `ppm view`: a window that shows the progressive image as it converges and lets the user move
//! objects (moves nobody planned, in any mode) and watch the light follow. Passes run on a
//! render thread ([`worker`]); the window ([`app`]) draws the panes ([`display`]) and the
//! panel ([`panel`]). `--script` plays a path file for tests and demos.

mod app;
mod display;
mod panel;
mod worker;

use crate::cli::interrupt::{self, Interrupted};
use crate::cli::options::{BackendChoice, MoveOptions, RenderOptions};
use crate::cli::render::{OutputPaths, output_folder, thread_pool};
use anyhow::{Context, Result, bail};
use ppm_core::params::MoveMode;
use scenes::file::path::load_script_file;
use std::path::PathBuf;
use winit::event_loop::EventLoop;

#[derive(clap::Args)]
pub struct ViewArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Backend that runs the passes. With wgpu, the image goes from the resolve pass to the
    /// screen on the device.
    #[arg(long, default_value = "cpu")]
    backend: BackendChoice,
    /// How the render follows a move.
    #[arg(long, default_value = "local", value_parser = clap::value_parser!(MoveMode))]
    mode: MoveMode,
    /// Two modes side by side on the same moves, time shared fairly (e.g. restart,local).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(MoveMode), conflicts_with = "mode")]
    compare: Vec<MoveMode>,
    #[command(flatten)]
    options: RenderOptions,
    #[command(flatten)]
    moves: MoveOptions,
    /// Worker threads of the CPU backend (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Exposure of the display and of the PNGs written (the EXR is always linear).
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// A path file to play: moves, camera steps (`camera = { eye = [...], look_at = [...] }`)
    /// and screenshot steps (`screenshot = true`).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Write the presented frame as PNG at every screenshot step and at exit.
    #[arg(long)]
    screenshot_dir: Option<PathBuf>,
    /// Start with the heat map of each move's resets shown (H toggles it).
    #[arg(long)]
    heat_map: bool,
    /// Close the window after the script's last step.
    #[arg(long, requires = "script")]
    exit_after: bool,
    /// Where the render is written on save (S), on close, and at exit (EXR, with PNG and
    /// JSON beside it; with --compare, NAME-MODE.exr per pane). Default: out/view-SCENE.exr.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn view(args: ViewArgs) -> Result<()> {
    interrupt::install()?;
    let scene = crate::load_scene(&args.scene)?;
    if args.options.passes.is_some() || args.options.time_budget.is_some() {
        bail!(
            "--passes / --time-budget: ppm view renders until its window closes; to stop after \
             a number of iterations, play a --script with --exit-after"
        );
    }
    let params = args.options.params(&scene, None)?;
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure = {}: must be a positive number", args.exposure);
    }
    let modes = match args.compare.len() {
        0 => vec![args.mode],
        2 => args.compare.clone(),
        n => bail!("--compare: {n} modes given; compare two, e.g. --compare restart,local"),
    };
    let moves = args.moves.params(&scene, &params)?;
    let script = match &args.script {
        Some(path) => Some(load_script_file(path, &scene)?),
        None => None,
    };
    let base = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/view-{}.exr", file_stem(&scene.name))));
    let outputs = match modes.len() {
        1 => vec![OutputPaths::new(&base)?],
        _ => modes
            .iter()
            .map(|m| {
                let stem = base.file_stem().and_then(|s| s.to_str()).unwrap_or("view");
                OutputPaths::new(&base.with_file_name(format!("{stem}-{}.exr", m.name())))
            })
            .collect::<Result<_>>()?,
    };
    if let Some(dir) = &args.screenshot_dir {
        output_folder(dir, &format!("--screenshot-dir {}", dir.display()))?;
    }
    check_display()?;
    let pool = thread_pool(args.threads)?;
    let event_loop = EventLoop::<worker::UiEvent>::with_user_event()
        .build()
        .map_err(|e| anyhow::anyhow!("{}", no_display(&e.to_string())))?;
    let mut app = app::App::new(app::AppSetup {
        plan: worker::Plan {
            modes,
            scene,
            params,
            moves,
            script,
            exit_after: args.exit_after,
            outputs,
            exposure: args.exposure,
            heat_map: args.heat_map,
        },
        backend: args.backend,
        screenshot_dir: args.screenshot_dir,
        pool,
        proxy: event_loop.create_proxy(),
    });
    event_loop
        .run_app(&mut app)
        .context("the window's event loop failed")?;
    app.finish()?;
    if interrupt::requested() {
        return Err(Interrupted("the render was written as it stood".to_owned()).into());
    }
    Ok(())
}

/// A scene name as a file name: anything but letters, digits, `-` and `_` becomes `_`.
fn file_stem(name: &str) -> String {
    name.chars()
        .map(
            |c| match c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                true => c,
                false => '_',
            },
        )
        .collect()
}

/// Refuses, before anything opens, to run without a display, naming what is missing and what
/// to do instead.
fn check_display() -> Result<()> {
    let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
        bail!(
            "{}",
            no_display("neither DISPLAY nor WAYLAND_DISPLAY is set")
        );
    }
    Ok(())
}

fn no_display(why: &str) -> String {
    format!(
        "ppm view needs a display, and cannot open one: {why}. Without a screen, run it under \
         a virtual X server (`xvfb-run -a ppm view ...`, Debian's xvfb package), or render \
         headless: `ppm render` for an image, `ppm animate --path FILE` for moves"
    )
}
