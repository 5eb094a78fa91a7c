//! `ppm report convergence`: a render from scratch against the truth over time.

use crate::cli::interrupt::{self, Interrupted};
use crate::cli::options::{BackendChoice, RenderOptions, TruthOptions, check_frame};
use crate::cli::render::output_folder;
use crate::convergence;
use anyhow::{Result, bail};
use scenes::file::output::write_bytes;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ConvergenceArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Backend that runs the passes: cpu, wgpu, or another registered one (`ppm backends`).
    #[arg(long, default_value = "cpu")]
    backend: BackendChoice,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 1)]
    frame: u32,
    /// Seconds of rendering measured.
    #[arg(long, default_value_t = 32.0)]
    seconds: f64,
    #[command(flatten)]
    options: RenderOptions,
    #[command(flatten)]
    truth: TruthOptions,
    /// Output folder: convergence.csv, .json and .png.
    #[arg(short, long)]
    output: PathBuf,
}

/// Times at which the table printed on the terminal shows a measurement.
const SHOWN_SECONDS: [f64; 10] = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0];

pub fn convergence(args: ConvergenceArgs) -> Result<()> {
    interrupt::install()?;
    let scene = crate::load_scene(&args.scene)?;
    check_frame(args.frame)?;
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        bail!("--seconds = {}: must be a positive number", args.seconds);
    }
    let params = args.options.params(&scene, Some((256, 256)))?;
    let out = &args.output;
    output_folder(out, &format!("-o {}", out.display()))?;
    let truth = args.truth.truth(&scene, args.frame, &params)?;
    let mut backend = args.backend.start()?;
    eprintln!(
        "rendering {} ({}) for {}s",
        scene.name,
        params.estimator.name(),
        args.seconds
    );
    let (points, report) = convergence::run_from_scratch(
        backend.as_mut(),
        &scene,
        args.frame,
        &params,
        args.seconds,
        &truth,
        &interrupt::requested,
    )?;
    let noise = truth.noise();
    let from = args.seconds / 8.0;
    let slope = convergence::fitted_slope(&points, from);
    write_bytes(&out.join("convergence.csv"), convergence::csv(&points))?;
    let json = serde_json::json!({
        "scene": scene.name, "frame": args.frame, "backend": report.backend,
        "params": params, "reference": truth.source, "reference_noise": noise,
        "fitted_slope": slope, "slope_from_seconds": from,
        "points": points, "interrupted": report.interrupted, "report": report,
    });
    write_bytes(
        &out.join("convergence.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let title = format!(
        "{} frame {}, {}, {}",
        scene.name,
        args.frame,
        params.estimator.name(),
        report.backend
    );
    convergence::chart(&out.join("convergence"), &title, &points, noise)?;
    println!(
        "{:>9} {:>7} {:>10} {:>10} {:>8}",
        "seconds", "iters", "pixel", "8x8", "mean"
    );
    for t in SHOWN_SECONDS
        .into_iter()
        .filter(|&t| t <= args.seconds * 1.05)
    {
        let nearest = points
            .iter()
            .min_by(|a, b| (a.seconds - t).abs().total_cmp(&(b.seconds - t).abs()));
        if let Some(p) = nearest.filter(|p| (p.seconds / t - 1.0).abs() < 0.1) {
            println!(
                "{:>9.2} {:>7} {:>10.4} {:>10.4} {:>8.4}",
                p.seconds, p.passes, p.rel_rmse, p.block_rel_rmse, p.mean_ratio
            );
        }
    }
    if let Some(last) = points.last() {
        println!(
            "final: {:.2}s, {} iterations: pixel {:.4}, 8x8 {:.4}, mean ratio {:.4}",
            last.seconds, last.passes, last.rel_rmse, last.block_rel_rmse, last.mean_ratio
        );
    }
    match noise {
        Some(n) => println!("reference noise (relative rmse floor): {n:.4}"),
        None => println!("reference noise unknown (no variance beside the reference)"),
    }
    if let Some(s) = slope {
        println!("fitted slope of log error against log time (from {from:.1}s): {s:.3}");
    }
    println!("wrote {}", out.display());
    if report.interrupted {
        return Err(Interrupted(format!(
            "the {} measurements taken are in {}",
            points.len(),
            out.display()
        ))
        .into());
    }
    Ok(())
}
