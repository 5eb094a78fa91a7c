//! The `ppm` command: render the canonical scenes, measure them against the truth, move them,
//! and compare backends. [`main`] runs it with the backends of a [`Registry`]: the `ppm`
//! binary passes [`Registry::in_tree`], a crate with a backend of its own adds it.

/// Report lines on stdout. A reader that stops early (`ppm ... | head`) closes it; a render
/// must not panic there, before or after writing its files: what it cannot show is dropped.
macro_rules! println {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// [`println!`] without the newline.
macro_rules! print {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

mod diff;
mod export;
mod interrupt;
mod merge;
mod moving;
mod options;
mod render;
mod reports;
mod stress;
mod view;

use crate::registry::Registry;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::process::ExitCode;
use std::sync::OnceLock;

/// The backends this run of the command knows ([`main`] sets it before parsing).
static REGISTRY: OnceLock<Registry> = OnceLock::new();

/// The registry [`main`] was given.
fn registry() -> &'static Registry {
    REGISTRY.get_or_init(Registry::in_tree)
}

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
    Render(render::RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// List the backends this `ppm` can run (`--backend NAME`).
    Backends,
    /// Render the ground truth with the unbiased reference path tracer (CPU).
    Reference(render::ReferenceArgs),
    /// Join the shards of a reference (bit for bit one run) or of a render (averaged).
    Merge(merge::MergeArgs),
    /// Measure an image against a reference image (EXR files from any renderer).
    Compare(render::CompareArgs),
    /// Render one seeded scene on the CPU and wgpu backends and compare them.
    Diff(diff::DiffArgs),
    /// Render a scene's move as an animation, carrying the light from frame to frame.
    Animate(moving::AnimateArgs),
    /// Measurement reports.
    #[command(subcommand)]
    Report(ReportCommand),
    /// Run the stress family (extreme scales, powers, geometry) and check every invariant.
    Stress(stress::StressArgs),
    /// Open a window on a progressive render: drag objects and watch the light follow.
    View(view::ViewArgs),
    /// Write a scene for Mitsuba 3 or pbrt-v4 (scene file and PLY meshes), to check us
    /// against another renderer.
    Export(export::ExportArgs),
}

#[derive(Subcommand)]
enum ReportCommand {
    /// Error against the truth of the new pose over time after a move, per mode.
    ErrorVsTime(moving::ErrorArgs),
    /// Error against the truth over time of a render from scratch.
    Convergence(reports::ConvergenceArgs),
}

/// Parses the command line and runs the command with `registry`'s backends; the exit code
/// says how it ended (an interrupted render has its own, after writing what it rendered).
pub fn main(registry: Registry) -> ExitCode {
    if REGISTRY.set(registry).is_err() {
        eprintln!("error: the ppm command runs once per process");
        return ExitCode::FAILURE;
    }
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<interrupt::Interrupted>() => {
            eprintln!("{e:#}");
            ExitCode::from(interrupt::EXIT_INTERRUPTED)
        }
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
        Command::Backends => {
            for e in registry().entries() {
                println!("{:<14} {}", e.name, e.about);
            }
            Ok(())
        }
        Command::Render(args) => render::render(args),
        Command::Reference(args) => render::reference(args),
        Command::Compare(args) => render::compare(args),
        Command::Merge(args) => merge::merge(args),
        Command::Diff(args) => diff::run(args),
        Command::Animate(args) => moving::animate(args),
        Command::Report(ReportCommand::ErrorVsTime(args)) => moving::error_vs_time(args),
        Command::Report(ReportCommand::Convergence(args)) => reports::convergence(args),
        Command::Stress(args) => stress::run(args),
        Command::Export(args) => export::export(args),
        Command::View(args) => view::view(args),
    }
}
