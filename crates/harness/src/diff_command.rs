//! `ppm diff`: renders one seeded scene on the CPU (reference) and wgpu backends, prints the
//! comparison as a table, writes `diff.json` and a heat map, and fails when they disagree.

use crate::diff::history::{HistoryRow, pixel_history};
use crate::diff::independent::{self, IndependentReport, TileMeans, tile_means};
use crate::diff::record;
use crate::diff::same_seed::{self, SameSeedReport};
use crate::render::render;
use anyhow::{Context, Result, bail};
use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use ppm_core::params::RenderParams;
use ppm_core::passes::Backend;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What to compare.
#[derive(Clone, Copy, Debug)]
pub enum DiffMode {
    /// Hit point by hit point, one seed.
    SameSeed,
    /// Statistically, `runs` seeds per backend.
    Independent {
        /// Runs per backend.
        runs: u32,
    },
    /// One pixel's history on both backends.
    Pixel {
        /// Column.
        x: u32,
        /// Row.
        y: u32,
    },
}

/// A `ppm diff` request.
#[derive(Clone, Debug)]
pub struct DiffRequest {
    /// Scene name or file.
    pub scene: String,
    /// Photon passes.
    pub passes: u32,
    /// Photons per pass.
    pub photons_per_pass: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Seed.
    pub seed: u32,
    /// Mode.
    pub mode: DiffMode,
    /// Output folder.
    pub output: PathBuf,
}

/// Runs the request; `Err` when the backends disagree or cannot run.
pub fn run(req: &DiffRequest) -> Result<()> {
    let scene = crate::load_scene(&req.scene)?;
    let mut params = RenderParams::for_scene(&scene);
    params.passes = req.passes;
    params.photons_per_pass = req.photons_per_pass;
    params.width = req.width;
    params.height = req.height;
    params.seed = req.seed;
    params.validate("command line")?;
    if let DiffMode::Pixel { x, y } = req.mode
        && (x >= params.width || y >= params.height)
    {
        bail!(
            "--pixel {x},{y}: outside the {}x{} image",
            params.width,
            params.height
        );
    }
    std::fs::create_dir_all(&req.output)
        .with_context(|| format!("-o {}: cannot create", req.output.display()))?;
    let mut cpu = CpuBackend::new();
    let mut gpu = WgpuBackend::new().context("the wgpu backend cannot start")?;
    eprintln!("wgpu adapter: {}", gpu.adapter_name());
    match req.mode {
        DiffMode::SameSeed => {
            let a = record(&mut cpu, &scene, 0, &params)?;
            let b = record(&mut gpu, &scene, 0, &params)?;
            let report = same_seed::compare(&a, &b, &params, 10);
            print!("{}", format_same_seed(&report));
            write_outputs(req, &report, &same_seed::heat(&a.image, &b.image))?;
            if !report.agree {
                bail!("the backends disagree (same seed)");
            }
        }
        DiffMode::Independent { runs } => {
            let a = runs_of(&mut cpu, &scene, &params, runs, 0)?;
            let b = runs_of(&mut gpu, &scene, &params, runs, OTHER_SEED_OFFSET)?;
            let report = independent::compare(("cpu", &a), ("wgpu", &b), &params, 10);
            print!("{}", format_independent(&report));
            write_outputs(req, &report, &independent::heat(&a, &b, &params))?;
            if !report.agree {
                bail!("the backends disagree (independent seeds)");
            }
        }
        DiffMode::Pixel { x, y } => {
            let a = record(&mut cpu, &scene, 0, &params)?;
            let b = record(&mut gpu, &scene, 0, &params)?;
            let rows = pixel_history(&[&a, &b], &params, x, y);
            print!("{}", format_history(&rows));
            std::fs::write(
                req.output.join("history.json"),
                serde_json::to_string_pretty(&rows)?,
            )?;
        }
    }
    Ok(())
}

/// Seed offset of the compared backend's runs: far from the reference's, so no run of one
/// shares a seed with a run of the other.
pub const OTHER_SEED_OFFSET: u32 = 1000;

/// `runs` renders with seeds `params.seed + offset + k`, reduced to tile means.
pub fn runs_of(
    backend: &mut dyn Backend,
    scene: &ppm_core::scene::Scene,
    params: &RenderParams,
    runs: u32,
    offset: u32,
) -> Result<Vec<TileMeans>> {
    let mut out = Vec::new();
    for k in 0..runs {
        let mut p = params.clone();
        p.seed = params.seed.wrapping_add(offset + k);
        let outcome = render(backend, scene, 0, &p, &mut |_, _| {})?;
        if let Some(e) = outcome.error {
            return Err(e.into());
        }
        out.push(tile_means(&outcome.image, &backend.read_hit_points()?, &p));
    }
    Ok(out)
}

fn write_outputs(
    req: &DiffRequest,
    report: &impl serde::Serialize,
    heat: &ppm_core::image::Image,
) -> Result<()> {
    std::fs::write(
        req.output.join("diff.json"),
        serde_json::to_string_pretty(report)?,
    )?;
    heat.write_exr(&req.output.join("heatmap.exr"))?;
    // Full red at a 10% difference (same seed) or at p = 1e-10 (independent: -log10 p = 10).
    let scale = if matches!(req.mode, DiffMode::SameSeed) {
        10.0
    } else {
        0.1
    };
    heat.write_png(&req.output.join("heatmap.png"), scale)?;
    println!("wrote {}", req.output.display());
    Ok(())
}

/// The same-seed table.
pub fn format_same_seed(r: &SameSeedReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "same seed: {} (reference) vs {}, {} hit-point slots",
        r.reference, r.other, r.slots
    );
    let _ = writeln!(
        s,
        "tolerance: relative {:e}; required share per field {:.1}%",
        r.relative_tolerance,
        100.0 * r.required_share
    );
    let _ = writeln!(
        s,
        "{:<8} {:>12} {:>16}",
        "field", "within tol.", "worst relative"
    );
    for f in &r.fields {
        let _ = writeln!(
            s,
            "{:<8} {:>11.4}% {:>16.3e}",
            f.field,
            100.0 * f.share,
            f.worst_relative
        );
    }
    let _ = writeln!(
        s,
        "all fields: {:.4}%   image relative RMSE: {:.3e}",
        100.0 * r.all_fields_share,
        r.image_relative_rmse
    );
    if !r.first_divergence.is_empty() {
        let passes: Vec<String> = r
            .first_divergence
            .iter()
            .map(|p| format!("pass {}: {}", p.pass, p.hit_points))
            .collect();
        let _ = writeln!(s, "first divergence: {}", passes.join(", "));
    }
    if !r.worst.is_empty() {
        let _ = writeln!(
            s,
            "{:>6} {:>6} {:<6} {:>14} {:>14} {:>10} {:>6}",
            "x", "y", "field", "reference", "other", "relative", "from"
        );
        for w in &r.worst {
            let _ = writeln!(
                s,
                "{:>6} {:>6} {:<6} {:>14.6e} {:>14.6e} {:>10.3e} {:>6}",
                w.x, w.y, w.field, w.reference, w.other, w.relative, w.first_pass
            );
        }
    }
    let _ = writeln!(s, "verdict: {}", if r.agree { "agree" } else { "DISAGREE" });
    s
}

/// The independent-seed table.
pub fn format_independent(r: &IndependentReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "independent seeds: {} vs {}, {} runs each",
        r.reference, r.other, r.runs
    );
    let _ = writeln!(
        s,
        "{} tile tests (Welch t, Holm-corrected), false-alarm rate {}: {} rejected, smallest p {:.3e}",
        r.tests, r.alpha, r.rejected, r.min_p
    );
    let _ = writeln!(
        s,
        "{:>5} {:>5} {:<11} {:>13} {:>13} {:>9} {:>10}",
        "tx", "ty", "quantity", "reference", "other", "t", "p"
    );
    for t in &r.worst {
        let _ = writeln!(
            s,
            "{:>5} {:>5} {:<11} {:>13.5e} {:>13.5e} {:>9.3} {:>10.3e}{}",
            t.tile_x,
            t.tile_y,
            t.quantity,
            t.reference_mean,
            t.other_mean,
            t.t,
            t.p,
            if t.rejected { "  rejected" } else { "" }
        );
    }
    let _ = writeln!(s, "verdict: {}", if r.agree { "agree" } else { "DISAGREE" });
    s
}

/// The pixel-history table.
pub fn format_history(rows: &[HistoryRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>4} {:<6} {:>2} {:<34} {:<24} {:>10} {:>11} flux",
        "pass", "back", "s", "position", "normal", "n", "r2"
    );
    for r in rows {
        let v3 = |v: [f32; 3]| format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2]);
        if !r.valid {
            let _ = writeln!(
                s,
                "{:>4} {:<6} {:>2} (no hit point)",
                r.pass, r.backend, r.sample
            );
            continue;
        }
        let _ = writeln!(
            s,
            "{:>4} {:<6} {:>2} {:<34} {:<24} {:>10.3} {:>11.5e} {:.5e} {:.5e} {:.5e}",
            r.pass,
            r.backend,
            r.sample,
            v3(r.position),
            format!("{:.3} {:.3} {:.3}", r.normal[0], r.normal[1], r.normal[2]),
            r.n,
            r.r2,
            r.flux[0],
            r.flux[1],
            r.flux[2]
        );
    }
    s
}
