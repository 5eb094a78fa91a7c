//! Comparing two backends on one seeded scene: hit point by hit point with the same seed
//! ([`same_seed`]), statistically with independent seeds ([`independent`]), and one pixel's
//! history pass by pass ([`history`]).

pub mod history;
pub mod independent;
pub mod same_seed;

use crate::render::{Progress, render};
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::params::RenderParams;
use ppm_core::passes::{Backend, BackendError};
use ppm_core::scene::Scene;

/// A render with the hit-point buffer read back after every pass.
pub struct Recording {
    /// Backend name.
    pub backend: String,
    /// `passes[0]` after direct light, `passes[k]` after photon pass k.
    pub passes: Vec<Vec<HitPoint>>,
    /// The resolved image.
    pub image: Image,
}

/// Renders `scene` on `backend`, keeping every pass's hit points (for diagnosis, not speed).
pub fn record(
    backend: &mut dyn Backend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
) -> Result<Recording, BackendError> {
    let mut passes = Vec::new();
    let mut failure = None;
    let outcome = render(
        backend,
        scene,
        frame,
        params,
        &mut |_: Progress, b: &mut dyn Backend| match b.read_hit_points() {
            Ok(hps) => passes.push(hps),
            Err(e) => failure = failure.take().or(Some(e)),
        },
    )?;
    if let Some(e) = failure.or(outcome.error) {
        return Err(e);
    }
    Ok(Recording {
        backend: backend.name().to_owned(),
        passes,
        image: outcome.image,
    })
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
