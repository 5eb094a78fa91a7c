//! Resolve (ALGORITHM.md 1.5): pixel = mean over its slots of `throughput * (direct + L)`.

use glam::Vec3;
use ppm_core::image::Image;
use ppm_core::layout::{HitPoint, ResolveParams};
use ppm_core::update::radiance;
use rayon::prelude::*;

/// The image of the current statistics.
pub fn resolve_main(params: &ResolveParams, hit_points: &[HitPoint]) -> Image {
    let spp = params.spp as usize;
    let pixels = hit_points
        .par_chunks(spp)
        .map(|slots| {
            let sum = slots
                .iter()
                .filter(|hp| hp.is_valid())
                .map(|hp| {
                    let indirect = Vec3::from(radiance(hp.tau, hp.r2, hp.emitted));
                    Vec3::from(hp.throughput) * (Vec3::from(hp.direct) + indirect)
                })
                .fold(Vec3::ZERO, |a, b| a + b);
            (sum / spp as f32).into()
        })
        .collect();
    Image {
        width: params.width,
        height: params.height,
        pixels,
    }
}
