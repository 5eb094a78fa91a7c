//! Comparing two backends on one seeded scene: hit point by hit point with the same seed
//! ([`same_seed`]), statistically with independent seeds ([`independent`]), and one pixel's
//! history pass by pass ([`history`]).

pub mod history;
pub mod independent;
pub mod same_seed;

use crate::driver::schedule::EachIteration;
use crate::driver::{Budget, RunError, Schedule, run};
use independent::{TileMeans, tile_means};
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::DynamicBackend;
use ppm_core::scene::Scene;

/// A render with the slot buffer read back after every iteration.
pub struct Recording {
    /// Backend name.
    pub backend: String,
    /// `passes[k]` after iteration `k + 1`.
    pub passes: Vec<Vec<HitPoint>>,
    /// The resolved image.
    pub image: Image,
}

/// Renders `scene` at `frame` for `params.passes` iterations on `backend`, keeping every
/// iteration's slots (for diagnosis, not speed).
pub fn record(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
) -> Result<Recording, RunError> {
    let mut passes = Vec::new();
    let mut observer = EachIteration(|_: &_, r: &mut crate::driver::Renderer| {
        passes.push(r.backend().read_hit_points()?);
        Ok(())
    });
    let schedule = Schedule::frame(frame, Budget::iterations(params.passes));
    let outcome = run(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        &mut observer,
    )?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    Ok(Recording {
        backend: backend.name().to_owned(),
        passes,
        image: outcome.image,
    })
}

/// Seed offset of the compared backend's runs: far from the reference's, so no run of one
/// shares a seed with a run of the other.
pub const OTHER_SEED_OFFSET: u32 = 1000;

/// `runs` renders of frame 0 for `params.passes` iterations with seeds
/// `params.seed + offset + k`, reduced to tile means.
pub fn runs_of(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    params: &RenderParams,
    runs: u32,
    offset: u32,
) -> Result<Vec<TileMeans>, RunError> {
    let mut out = Vec::new();
    for k in 0..runs {
        let mut p = params.clone();
        p.seed = params.seed.wrapping_add(offset + k);
        let schedule = Schedule::frame(0, Budget::iterations(p.passes));
        let outcome = run(
            backend,
            scene,
            &p,
            &MoveParams::default(),
            &schedule,
            &mut (),
        )?;
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
