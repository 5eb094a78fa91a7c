//! Resolve (docs/algorithm.md 1.5): pixel = mean over its slots of `direct / iterations + L`, the
//! throughput already folded into both.

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
                .map(|hp| {
                    Vec3::from(hp.direct_mean()) + Vec3::from(radiance(hp.tau, hp.r2, hp.emitted))
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
