//! `ppm diff`: renders one seeded scene on the CPU (reference) and wgpu backends, prints the
//! comparison as a table, writes `diff.json` and a heat map, and fails when they disagree.

use crate::render::output_folder;
use anyhow::{Context, Result, bail};
use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use harness::diff::history::{self, pixel_history};
use harness::diff::independent;
use harness::diff::same_seed;
use harness::diff::{OTHER_SEED_OFFSET, record, runs_of};
use ppm_core::limits::{MemoryBudget, check_render_memory};
use ppm_core::params::{Estimator, RenderParams};
use scenes::file::image::ImageFiles;
use scenes::file::output::write_bytes;
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
    let scene = harness::load_scene(&args.scene)?;
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
    params.validate("command line")?;
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
    let mut cpu = CpuBackend::new();
    let mut gpu = WgpuBackend::new().context("the wgpu backend cannot start")?;
    eprintln!("wgpu adapter: {}", gpu.adapter_name());
    if let Some((x, y)) = args.pixel {
        let a = record(&mut cpu, &scene, 0, &params)?;
        let b = record(&mut gpu, &scene, 0, &params)?;
        let rows = pixel_history(&[&a, &b], &params, x, y);
        print!("{}", history::format(&rows));
        write_bytes(
            &args.output.join("history.json"),
            serde_json::to_string_pretty(&rows)?,
        )?;
    } else if args.independent {
        let a = runs_of(&mut cpu, &scene, &params, args.runs, 0)?;
        let b = runs_of(&mut gpu, &scene, &params, args.runs, OTHER_SEED_OFFSET)?;
        let report = independent::compare(("cpu", &a), ("wgpu", &b), &params, 10);
        print!("{}", independent::format(&report));
        write_outputs(&args, &report, &independent::heat(&a, &b, &params))?;
        if !report.agree {
            bail!("the backends disagree (independent seeds)");
        }
    } else {
        let a = record(&mut cpu, &scene, 0, &params)?;
        let b = record(&mut gpu, &scene, 0, &params)?;
        let report = same_seed::compare(&a, &b, &params, 10);
        print!("{}", same_seed::format(&report));
        write_outputs(&args, &report, &same_seed::heat(&a.image, &b.image))?;
        if !report.agree {
            bail!("the backends disagree (same seed)");
        }
    }
    Ok(())
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
