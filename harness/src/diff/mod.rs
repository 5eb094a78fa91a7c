//! Comparing two backends on one seeded scene: hit point by hit point with the same seed
//! ([`same_seed`]), statistically with independent seeds ([`independent`]), and one pixel's
//! history pass by pass ([`history`]).

pub mod history;
pub mod independent;
pub mod same_seed;

use crate::driver::checkpoint::RenderState;
use crate::driver::schedule::{Observer, ObserverResult, Progress};
use crate::driver::{Budget, MoveReport, Renderer, Resume, RunError, Schedule, run, run_from};
use independent::{TileMeans, tile_means};
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::Scene;

/// A render with the slot buffer read back after every iteration and every move.
pub struct Recording {
    /// Backend name.
    pub backend: String,
    /// The slots after each of the render's steps, in order: `passes[k]` after step `k + 1`.
    pub passes: Vec<Vec<HitPoint>>,
    /// What each step of `passes` was: `iteration` or `move`.
    pub steps: Vec<&'static str>,
    /// The resolved image.
    pub image: Image,
}

/// Renders `scene` at `frame` for `params.passes` iterations on `backend`, keeping every
/// iteration's slots (for diagnosis, not speed).
pub fn record(
    backend: &mut dyn Backend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
) -> Result<Recording, RunError> {
    let schedule = Schedule::frame(frame, Budget::iterations(params.passes));
    record_schedule(backend, scene, params, &MoveParams::default(), &schedule)
}

/// Runs `schedule` on `backend`, keeping the slots after every iteration and every move:
/// two backends that move alike can be compared step by step, moves included.
pub fn record_schedule(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    moves: &MoveParams,
    schedule: &Schedule,
) -> Result<Recording, RunError> {
    record_schedule_from(backend, scene, params, moves, schedule, None)
}

/// [`record_schedule`] from a saved state ([`state_after`]) when `resume` gives one: the
/// steps recorded are those after it.
pub fn record_schedule_from(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    moves: &MoveParams,
    schedule: &Schedule,
    resume: Option<Resume>,
) -> Result<Recording, RunError> {
    /// Reads the slots back after each iteration and move.
    struct Keep {
        passes: Vec<Vec<HitPoint>>,
        steps: Vec<&'static str>,
    }
    impl Observer for Keep {
        fn iteration(&mut self, _: &Progress, r: &mut Renderer) -> ObserverResult {
            self.passes.push(r.backend().read_hit_points()?);
            self.steps.push("iteration");
            Ok(())
        }
        fn moved(&mut self, _: &Progress, _: &MoveReport, r: &mut Renderer) -> ObserverResult {
            self.passes.push(r.backend().read_hit_points()?);
            self.steps.push("move");
            Ok(())
        }
    }
    let mut keep = Keep {
        passes: Vec::new(),
        steps: Vec::new(),
    };
    let outcome = run_from(backend, scene, params, moves, schedule, &mut keep, resume)?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    Ok(Recording {
        backend: backend.name().to_owned(),
        passes: keep.passes,
        steps: keep.steps,
        image: outcome.image,
    })
}

/// The state of a still render of `scene` on `backend` after `iterations` iterations: what
/// `ppm diff --save-state` keeps just before two backends part, and `--replay` starts both
/// from.
pub fn state_after(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    iterations: u32,
) -> Result<RenderState, RunError> {
    /// Takes the state when the render step ends.
    struct Take(Option<RenderState>);
    impl Observer for Take {
        fn step_done(&mut self, at: &Progress, r: &mut Renderer) -> ObserverResult {
            self.0 = Some(r.snapshot(at.seconds)?);
            Ok(())
        }
    }
    let mut take = Take(None);
    let schedule = Schedule::frame(0, Budget::iterations(iterations));
    let outcome = run(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        &mut take,
    )?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    Ok(take.0.expect("a render step ends with step_done"))
}

/// Seed offset of the compared backend's runs: far from the reference's, so no run of one
/// shares a seed with a run of the other.
pub const OTHER_SEED_OFFSET: u32 = 1000;

/// `runs` renders of frame 0 for `params.passes` iterations with seeds
/// `params.seed + offset + k`, reduced to tile means.
pub fn runs_of(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    runs: u32,
    offset: u32,
) -> Result<Vec<TileMeans>, RunError> {
    let schedule = Schedule::frame(0, Budget::iterations(params.passes));
    runs_of_schedule(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        runs,
        offset,
    )
}

/// `runs` runs of `schedule` with seeds `params.seed + offset + k`, reduced to tile means
/// of the last pose.
pub fn runs_of_schedule(
    backend: &mut dyn Backend,
    scene: &Scene,
    params: &RenderParams,
    moves: &MoveParams,
    schedule: &Schedule,
    runs: u32,
    offset: u32,
) -> Result<Vec<TileMeans>, RunError> {
    let mut out = Vec::new();
    for k in 0..runs {
        let mut p = params.clone();
        p.seed = params.seed.wrapping_add(offset + k);
        let outcome = run(backend, scene, &p, moves, schedule, &mut ())?;
        if let Some(e) = outcome.error {
            return Err(e.into());
        }
        out.push(tile_means(&outcome.image, &backend.read_hit_points()?, &p));
    }
    Ok(out)
}

/// Pixel coordinates `(x, y)` of a hit-point slot.
pub fn slot_pixel(slot: usize, params: &RenderParams) -> (u32, u32) {
    let pixel = (slot / params.spp as usize) as u32;
    (pixel % params.width, pixel / params.width)
}

/// Luminance (Rec. 709 weights) of linear RGB.
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
}

/// A heat map (red = disagreement) as a float image: `values` per pixel, in [0, inf).
pub fn heat_map(width: u32, height: u32, values: &[f64]) -> Image {
    Image {
        width,
        height,
        pixels: values.iter().map(|&v| [v as f32, 0.0, 0.0]).collect(),
    }
}
