//! Options shared by several commands, and the one place they become render settings.

use crate::cli::interrupt::{self, Interrupted};
use crate::reference::Truth;
use crate::reference::cache::{ReferenceError, ReferenceRequest, cached_reference};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use ppm_core::limits::{MemoryBudget, check_deposits, check_reference_memory, check_render_memory};
use ppm_core::params::{DirectMode, Estimator, MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::Scene;
use std::path::PathBuf;

/// A backend named on the command line: one of the registry's ([`crate::registry`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BackendChoice(pub String);

impl BackendChoice {
    /// The backend, started; a wgpu backend names its adapter on stderr, since the same
    /// command runs on a GPU or on lavapipe.
    pub fn start(&self) -> Result<Box<dyn Backend + Send>> {
        let mut backend = super::registry()
            .start(&self.0)
            .with_context(|| format!("the {} backend cannot start", self.0))?;
        if let Some(wgpu) = backend
            .as_any_mut()
            .and_then(|b| b.downcast_mut::<backend_wgpu::WgpuBackend>())
        {
            eprintln!("wgpu adapter: {}", wgpu.adapter_name());
        }
        Ok(backend)
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.0
    }
}

impl std::str::FromStr for BackendChoice {
    type Err = String;

    /// A registered name; the error lists them.
    fn from_str(name: &str) -> Result<Self, String> {
        let names = super::registry().names();
        match names.contains(&name) {
            true => Ok(Self(name.to_owned())),
            false => Err(format!(
                "no backend called '{name}' (registered: {})",
                names.join(", ")
            )),
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum DirectChoice {
    /// Shadow rays; photons skip their first surface (the thesis).
    Explicit,
    /// Photons carry direct light too (classic PPM).
    Photons,
}

/// How a scene is rendered: every option defaults to the scene's setting or the estimator's.
#[derive(clap::Args)]
pub struct RenderOptions {
    /// Progressive estimator: sppm (consistent; the default) or ppm (the thesis's fixed hit
    /// points). Default: the scene's.
    #[arg(long, value_parser = clap::value_parser!(Estimator))]
    pub estimator: Option<Estimator>,
    /// Image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Iterations, one photon pass each (default: the scene's; unbounded when only
    /// --time-budget is given).
    #[arg(long)]
    pub passes: Option<u32>,
    /// Photons emitted per pass (default: the scene's).
    #[arg(long)]
    pub photons_per_pass: Option<u32>,
    /// Stop iterating after this many seconds of rendering.
    #[arg(long)]
    pub time_budget: Option<f64>,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Fraction of new photons kept per pass, in (0, 1) (default: the scene's).
    #[arg(long)]
    pub alpha: Option<f32>,
    /// Initial gather radius in scene units, not squared (default: the scene's).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Eye samples (slots) per pixel; with ppm, 1 goes through the pixel centre.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Where direct light comes from.
    #[arg(long, value_enum, default_value = "explicit")]
    pub direct: DirectChoice,
    /// Shadow-ray samples per visible point: per iteration with sppm (default 1), once per
    /// frame with ppm (default 16).
    #[arg(long)]
    pub direct_samples: Option<u32>,
}

impl RenderOptions {
    /// The settings for `scene`; `size` is the image size when the options give none
    /// (otherwise the scene's own).
    pub fn params(&self, scene: &Scene, size: Option<(u32, u32)>) -> Result<RenderParams> {
        let mut p = RenderParams::for_scene(scene);
        let (w, h) = size.unwrap_or((p.width, p.height));
        p.estimator = self.estimator.unwrap_or(p.estimator);
        p.width = self.width.unwrap_or(w);
        p.height = self.height.unwrap_or(h);
        p.passes = match (self.passes, self.time_budget) {
            (Some(n), _) => n,
            (None, Some(_)) => u32::MAX,
            (None, None) => p.passes,
        };
        p.photons_per_pass = self.photons_per_pass.unwrap_or(p.photons_per_pass);
        p.time_budget = self.time_budget;
        p.seed = self.seed;
        p.alpha = self.alpha.unwrap_or(p.alpha);
        p.initial_radius = self.radius.unwrap_or(p.initial_radius);
        p.spp = self.spp;
        p.direct = match self.direct {
            DirectChoice::Explicit => DirectMode::Explicit,
            DirectChoice::Photons => DirectMode::Photons,
        };
        p.direct_samples = self
            .direct_samples
            .unwrap_or(p.estimator.default_direct_samples());
        p.validate("command line")?;
        check_render_memory(&p, scene, &MemoryBudget::detect())?;
        Ok(p)
    }
}

/// Settings of the passes that follow a move.
#[derive(clap::Args)]
pub struct MoveOptions {
    /// Compensation passes per move (and as many positive region passes).
    #[arg(long, default_value_t = 4)]
    pub compensation_passes: u32,
    /// Photons per compensation or region pass.
    #[arg(long, default_value_t = 65_536)]
    pub region_photons: u32,
    /// Half-angle of the guided photons' cone, degrees.
    #[arg(long, default_value_t = 10.0)]
    pub cone_deg: f32,
    /// Difference passes per move in difference mode (each a negative and a positive pass
    /// of the ordinary photon count).
    #[arg(long, default_value_t = 8)]
    pub difference_passes: u32,
    /// Local mode's correction photons per pose at most, in ordinary passes' worth (traced
    /// as one pass): a move uses one pass per 64 iterations since the last move, at least one.
    #[arg(long, default_value_t = 8)]
    pub correction_passes: u32,
    /// Local mode gathers a one-pass correction within at least this many initial radii (0:
    /// each slot's own radius); a correction of P passes' worth within this times P^(-1/6).
    #[arg(long, default_value_t = 3.0)]
    pub correction_radii: f32,
}

impl MoveOptions {
    /// The settings, checked; `render` are those of the ordinary passes around the moves.
    pub fn params(&self, scene: &Scene, render: &RenderParams) -> Result<MoveParams> {
        let p = MoveParams {
            compensation_passes: self.compensation_passes,
            region_photons: self.region_photons,
            cone_deg: self.cone_deg,
            difference_passes: self.difference_passes,
            correction_passes: self.correction_passes,
            correction_radii: self.correction_radii,
            ..MoveParams::default()
        };
        p.validate("command line")?;
        let budget = MemoryBudget::detect();
        check_deposits(
            p.region_photons,
            "region_photons",
            "--region-photons",
            render,
            scene,
            &budget,
        )?;
        // Local mode traces its correction as one pass of this many photons per pose.
        let correction = u64::from(render.photons_per_pass) * u64::from(p.correction_passes);
        let Ok(correction) = u32::try_from(correction) else {
            bail!(
                "--correction-passes = {}: {} passes' worth of {} photons exceed 2^32 photons in one pass",
                p.correction_passes,
                p.correction_passes,
                render.photons_per_pass
            );
        };
        check_deposits(
            correction,
            "photons_per_pass * correction_passes",
            "--correction-passes",
            render,
            scene,
            &budget,
        )?;
        Ok(p)
    }
}

/// Where an error report takes its truth from.
#[derive(clap::Args)]
pub struct TruthOptions {
    /// Reference image to measure against: an EXR from any renderer, of the rendered size
    /// with R, G and B channels (a NAME.var.exr beside it gives its noise). Default: the
    /// project's reference path tracer, cached in --cache.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Folder of cached path-traced references (file names are hashes of every setting that
    /// changes the image).
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
}

/// Seed of cached references: apart from the renders they judge, which start at seed 0.
const REFERENCE_SEED: u32 = 0x5eed;

impl TruthOptions {
    /// The truth of `scene` at `frame` and the size of `params`: `--reference FILE.exr`, or
    /// the cached path-traced reference.
    pub fn truth(&self, scene: &Scene, frame: u32, params: &RenderParams) -> Result<Truth> {
        if let Some(path) = &self.reference {
            let truth = Truth::from_exr(path, params.width, params.height)
                .context("--reference: the image cannot serve as the truth")?;
            eprintln!("reference: {}", truth.source);
            return Ok(truth);
        }
        if self.reference_spp == 0 {
            bail!("--reference-spp = 0: must be at least 1");
        }
        check_reference_memory(params.width, params.height, &MemoryBudget::detect())?;
        let request = ReferenceRequest {
            frame,
            width: params.width,
            height: params.height,
            spp: self.reference_spp,
            seed: REFERENCE_SEED,
        };
        let bar = spp_bar(Some(self.reference_spp));
        let truth = cached_reference(&self.cache, scene, &request, &mut |spp, s| {
            bar.set_position(u64::from(spp));
            bar.set_message(format!("{s:.1}s"));
            interrupt::flow()
        });
        bar.finish_and_clear();
        let truth = match truth {
            Err(e @ ReferenceError::Interrupted { .. }) => {
                return Err(Interrupted(e.to_string()).into());
            }
            other => other?,
        };
        eprintln!("reference: {}", truth.source);
        Ok(truth)
    }
}

/// A progress bar over reference samples per pixel (a spinner when unbounded).
pub fn spp_bar(spp: Option<u32>) -> ProgressBar {
    let bar = match spp {
        Some(n) => ProgressBar::new(u64::from(n)),
        None => ProgressBar::new_spinner(),
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} reference spp {pos}/{len} {bar:30} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// Checks `--frame`.
pub fn check_frame(frame: u32) -> Result<()> {
    if frame > 1 {
        bail!("--frame = {frame}: a scene has frames 0 and 1 only");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed, TestRunner};

    /// The numeric options of a render and of its moves, as `ppm animate` takes them.
    #[derive(Parser)]
    struct Probe {
        #[command(flatten)]
        render: RenderOptions,
        #[command(flatten)]
        moves: MoveOptions,
    }

    const OPTIONS: &[&str] = &[
        "--width",
        "--height",
        "--passes",
        "--photons-per-pass",
        "--time-budget",
        "--seed",
        "--alpha",
        "--radius",
        "--spp",
        "--direct-samples",
        "--compensation-passes",
        "--region-photons",
        "--cone-deg",
        "--difference-passes",
        "--correction-passes",
        "--correction-radii",
    ];

    /// Values at the edges of what the options' types hold, and past them.
    const VALUES: &[&str] = &[
        "0",
        "-0",
        "1",
        "-1",
        "0.5",
        "3",
        "NaN",
        "inf",
        "-inf",
        "1e20",
        "1e-30",
        "1e38",
        "4294967295",
        "4294967296",
        "18446744073709551616",
        "",
        "x",
    ];

    /// Any mix of one to four numeric options with extreme values: parsing and validation
    /// never panic, and a refusal names one of the options given.
    #[test]
    fn numeric_options_never_panic_and_refusals_name_the_option() {
        let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
        let picks = prop::collection::vec((0..OPTIONS.len(), 0..VALUES.len()), 1..5);
        let config = Config {
            cases: 2000,
            failure_persistence: None,
            rng_seed: RngSeed::Fixed(7),
            ..Config::default()
        };
        let (accepted, refused) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
        TestRunner::new(config)
            .run(&picks, |picks| {
                let args: Vec<String> = std::iter::once("probe".to_owned())
                    .chain(
                        picks
                            .iter()
                            .map(|&(o, v)| format!("{}={}", OPTIONS[o], VALUES[v])),
                    )
                    .collect();
                let names = |message: &str| {
                    picks.iter().any(|&(o, _)| {
                        let name = OPTIONS[o].trim_start_matches("--");
                        message.contains(name) || message.contains(&name.replace('-', "_"))
                    })
                };
                let checked = Probe::try_parse_from(&args)
                    .map_err(anyhow::Error::from)
                    .and_then(|probe| {
                        let params = probe.render.params(&scene, Some((256, 256)))?;
                        probe.moves.params(&scene, &params)
                    });
                match checked {
                    Ok(_) => accepted.set(accepted.get() + 1),
                    Err(e) => {
                        let message = format!("{e:#}");
                        prop_assert!(names(&message), "{args:?}: {message}");
                        refused.set(refused.get() + 1);
                    }
                }
                Ok(())
            })
            .unwrap();
        let (accepted, refused) = (accepted.get(), refused.get());
        eprintln!("options: {accepted} accepted, {refused} refused");
        assert!(accepted > 0 && refused > 0);
    }
}
