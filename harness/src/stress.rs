//! Runs the stress family on a backend and checks what must hold on every case: finite
//! fields, `tau >= 0`, `0 < r2 <= r2_initial`, `n >= 0`, a finite image, and the case's
//! closed form where it has one.

use crate::diff::OTHER_SEED_OFFSET;
use crate::diff::independent::{IndependentReport, TileMeans, compare_at, tile_means};
use crate::driver::schedule::EachIteration;
use crate::driver::{Budget, Progress, Renderer, Schedule, run};
use ppm_core::image::Image;
use ppm_core::params::MoveParams;
use ppm_core::passes::{Backend, BackendError};
use scenes::stress::{Expected, MoveStress, StressCase, StressSetup};
use serde::Serialize;
use std::time::Instant;

/// The extremes seen over a case's hit points.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Worst {
    /// Largest flux channel.
    pub max_tau: f32,
    /// Smallest flux channel (must not be negative).
    pub min_tau: f32,
    /// Smallest `r2 / r2_initial` (must stay above 0).
    pub min_r2_ratio: f32,
    /// Largest `r2 / r2_initial` (must not exceed 1).
    pub max_r2_ratio: f32,
    /// Largest count.
    pub max_n: f32,
    /// Mean radiance of the image over all pixels and channels.
    pub mean_radiance: f64,
}

/// One case on one backend.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// Case name.
    pub case: String,
    /// Backend name.
    pub backend: String,
    /// Whether every check held.
    pub passed: bool,
    /// `pass`, `refused: ...` (an accepted clear error), or what failed.
    pub verdict: String,
    /// Extremes of the fields.
    pub worst: Worst,
    /// Seconds the case took.
    pub seconds: f64,
}

/// Renders a moving case: frame 0, a compensated move, then as many iterations again.
fn render_move(
    backend: &mut dyn Backend,
    setup: &StressSetup,
    m: MoveStress,
) -> Result<Image, String> {
    let moves = MoveParams {
        compensation_passes: 2,
        region_photons: m.region_photons,
        ..MoveParams::default()
    };
    let budget = Budget::iterations(setup.params.passes);
    let schedule = Schedule::after_move(budget, m.mode, budget);
    let outcome = run(
        backend,
        &setup.scene,
        &setup.params,
        &moves,
        &schedule,
        &mut (),
    )
    .map_err(|e| e.to_string())?;
    match outcome.error {
        Some(e) => Err(e.to_string()),
        None => Ok(outcome.image),
    }
}

/// Renders a static case, seeding its state after the first iteration when it has one.
fn render_still(
    backend: &mut dyn Backend,
    setup: &StressSetup,
) -> Result<(Image, Option<BackendError>), String> {
    let mut seeding = EachIteration(|at: &Progress, r: &mut Renderer| {
        if let (1, Some(seed)) = (at.iterations, setup.seed) {
            let b = r.backend();
            let mut hps = b.read_hit_points()?;
            hps.iter_mut().filter(|h| h.is_valid()).for_each(seed);
            b.write_hit_points(&hps)?;
        }
        Ok(())
    });
    let schedule = Schedule::frame(0, Budget::iterations(setup.params.passes));
    let outcome = run(
        backend,
        &setup.scene,
        &setup.params,
        &MoveParams::default(),
        &schedule,
        &mut seeding,
    )
    .map_err(|e| format!("seeding the state failed: {e}"))?;
    Ok((outcome.image, outcome.error))
}

/// Runs `case` on `backend`.
pub fn run_case(backend: &mut dyn Backend, case: &StressCase) -> CaseResult {
    let start = Instant::now();
    let setup = (case.build)();
    let mut result = CaseResult {
        case: case.name.to_owned(),
        backend: backend.name().to_owned(),
        passed: false,
        verdict: String::new(),
        worst: Worst::default(),
        seconds: 0.0,
    };
    let outcome = setup
        .params
        .validate(case.name)
        .map_err(|e| e.to_string())
        .and_then(|()| match setup.moves {
            Some(m) => render_move(backend, &setup, m).map(|image| (image, None)),
            None => render_still(backend, &setup),
        });
    let verdict =
        match outcome {
            Err(e) => Err(format!("render failed: {e}")),
            Ok((image, error)) => match error {
                Some(
                    e @ (BackendError::NonFinite { .. } | BackendError::NonFinitePhoton { .. }),
                ) if setup.expected == Expected::FiniteOrRefused => Ok(format!("refused: {e}")),
                Some(e) => Err(format!("pass error: {e}")),
                None => check(backend, &setup, &image, &mut result.worst),
            },
        };
    result.passed = verdict.is_ok();
    result.verdict = verdict.unwrap_or_else(|e| format!("FAIL: {e}"));
    result.seconds = start.elapsed().as_secs_f64();
    result
}

fn check(
    backend: &mut dyn Backend,
    setup: &StressSetup,
    image: &Image,
    worst: &mut Worst,
) -> Result<String, String> {
    let hps = backend.read_hit_points().map_err(|e| e.to_string())?;
    let r2_initial = setup.params.initial_radius * setup.params.initial_radius;
    *worst = Worst {
        min_tau: f32::INFINITY,
        min_r2_ratio: f32::INFINITY,
        ..Worst::default()
    };
    for (i, hp) in hps.iter().enumerate() {
        let fields = hp
            .tau
            .iter()
            .chain(&hp.direct)
            .chain([&hp.r2, &hp.n, &hp.emitted]);
        if let Some(v) = fields.clone().find(|v| !v.is_finite()) {
            return Err(format!("hit point {i}: non-finite value {v}"));
        }
        let ratio = hp.r2 / r2_initial;
        worst.max_tau = hp.tau.iter().copied().fold(worst.max_tau, f32::max);
        worst.min_tau = hp.tau.iter().copied().fold(worst.min_tau, f32::min);
        worst.min_r2_ratio = worst.min_r2_ratio.min(ratio);
        worst.max_r2_ratio = worst.max_r2_ratio.max(ratio);
        worst.max_n = worst.max_n.max(hp.n);
        if hp.tau.iter().any(|t| *t < 0.0) {
            return Err(format!("hit point {i}: negative flux {:?}", hp.tau));
        }
        if !(hp.r2 > 0.0 && hp.r2 <= r2_initial) {
            return Err(format!(
                "hit point {i}: r2 = {} outside (0, {r2_initial}]",
                hp.r2
            ));
        }
        if hp.n < 0.0 {
            return Err(format!("hit point {i}: n = {}", hp.n));
        }
    }
    if worst.min_tau == f32::INFINITY {
        // No hit point at all (an empty view): nothing to bound.
        worst.min_tau = 0.0;
        worst.min_r2_ratio = 0.0;
    }
    if !image.is_finite() {
        return Err("the image is not finite".into());
    }
    let count = (image.pixels.len() * 3).max(1) as f64;
    worst.mean_radiance = image
        .pixels
        .iter()
        .flatten()
        .map(|v| f64::from(*v))
        .sum::<f64>()
        / count;
    if let Expected::Radiance {
        radiance,
        tolerance,
    } = setup.expected
    {
        let error = (worst.mean_radiance / f64::from(radiance) - 1.0).abs();
        if error > f64::from(tolerance) {
            return Err(format!(
                "mean radiance {:.6e} is {:.2}% off the closed form {radiance:e} (tolerance {:.0}%)",
                worst.mean_radiance,
                100.0 * error,
                100.0 * tolerance
            ));
        }
    }
    Ok("pass".into())
}

/// Runs of each backend in the agreement test.
pub const AGREEMENT_RUNS: u32 = 4;

/// Tile means of one run of `case` with `seed`, or `None` when the case refused (allowed at
/// the f32 limit, and then nothing to compare).
fn sample(
    backend: &mut dyn Backend,
    case: &StressCase,
    seed: u32,
) -> Result<Option<TileMeans>, String> {
    let mut setup = (case.build)();
    setup.params.seed = seed;
    let image = match setup.moves {
        Some(m) => render_move(backend, &setup, m)?,
        None => match render_still(backend, &setup)? {
            (_, Some(_)) if setup.expected == Expected::FiniteOrRefused => return Ok(None),
            (_, Some(e)) => return Err(e.to_string()),
            (image, None) => image,
        },
    };
    let hps = backend.read_hit_points().map_err(|e| e.to_string())?;
    Ok(Some(tile_means(&image, &hps, &setup.params)))
}

/// Whether two backends agree on `case` by the independent-seed test (Welch t per tile and
/// quantity, Holm-corrected at `alpha`), each rendering it [`AGREEMENT_RUNS`] times.
pub fn agreement(
    reference: &mut dyn Backend,
    other: &mut dyn Backend,
    case: &StressCase,
    alpha: f64,
) -> Result<Option<IndependentReport>, String> {
    let runs = |b: &mut dyn Backend, offset: u32| -> Result<Option<Vec<TileMeans>>, String> {
        let mut out = Vec::new();
        for k in 0..AGREEMENT_RUNS {
            match sample(b, case, offset + k)? {
                Some(t) => out.push(t),
                None => return Ok(None),
            }
        }
        Ok(Some(out))
    };
    let (Some(a), Some(b)) = (runs(reference, 0)?, runs(other, OTHER_SEED_OFFSET)?) else {
        return Ok(None);
    };
    let params = (case.build)().params;
    Ok(Some(compare_at(
        (reference.name(), &a),
        (other.name(), &b),
        &params,
        3,
        alpha,
    )))
}

/// The results as a table.
pub fn table(results: &[CaseResult]) -> String {
    let mut s = format!(
        "{:<22} {:<5} {:>10} {:>10} {:>10} {:>10} {:>10} {:>11} {:>7}  verdict\n",
        "case", "back", "max tau", "min tau", "min r2/r0", "max r2/r0", "max n", "mean L", "time"
    );
    for r in results {
        let w = &r.worst;
        s.push_str(&format!(
            "{:<22} {:<5} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e} {:>11.4e} {:>6.2}s  {}\n",
            r.case, r.backend, w.max_tau, w.min_tau, w.min_r2_ratio, w.max_r2_ratio, w.max_n, w.mean_radiance, r.seconds, r.verdict
        ));
    }
    s
}
