//! The ground truth of every error report: an image from any renderer, or the project's own
//! unbiased path tracer ([`path_tracer`]) rendered progressively and cached on disk
//! ([`cache`]), with the variance of each pixel's mean so that the truth's own noise is known.

pub mod cache;
pub mod path_tracer;
pub mod sampler;

use crate::clock::Stopwatch;
use crate::driver::pass_params::RAY_EPSILON_RELATIVE;
use crate::shard::Shard;
use backend_cpu::trace::SceneData;
use glam::Vec3;
use path_tracer::PathTracer;
use ppm_core::compile::CompiledScene;
use ppm_core::image::Image;
use ppm_core::metrics::reference_noise;
use rayon::prelude::*;
use sampler::BATCHES;
use scenes::file::image::{ImageError, ImageFiles};
use serde::Serialize;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// How long a reference renders: whichever limit comes first (at least one is set).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReferenceBudget {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Seconds.
    pub seconds: Option<f64>,
}

/// A path-traced image with the variance of each pixel's mean.
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    /// Mean radiance per pixel.
    pub image: Image,
    /// Variance of each pixel's mean, per channel: its sample variance over the sample count.
    pub variance: Image,
    /// Samples per pixel taken.
    pub spp: u32,
    /// Seconds spent.
    pub seconds: f64,
    /// Why the render stopped before its budget, if it did (a non-finite sample).
    pub error: Option<String>,
    /// The caller stopped the render (Ctrl-C) before its budget was spent.
    pub interrupted: bool,
}

impl ReferenceImage {
    /// The relative RMSE this reference is expected to have against the truth.
    pub fn noise(&self) -> f64 {
        reference_noise(&self.image, &self.variance)
    }

    /// The summary written beside the image, of the rows of `shard`.
    pub fn summary(&self, scene: &str, frame: u32, seed: u32, shard: Shard) -> ReferenceSummary {
        let rows = (0..self.image.height)
            .filter(|&y| shard.owns_row(y))
            .count() as u64;
        let samples = u64::from(self.spp) * u64::from(self.image.width) * rows;
        ReferenceSummary {
            renderer: "ppm reference (path tracer with next-event estimation and MIS)",
            scene: scene.to_owned(),
            frame,
            width: self.image.width,
            height: self.image.height,
            seed,
            spp: self.spp,
            seconds: self.seconds,
            samples_per_second: samples as f64 / self.seconds.max(1e-9),
            max_bounces: path_tracer::MAX_BOUNCES,
            relative_noise: reference_noise(
                &shard_rows(&self.image, shard),
                &shard_rows(&self.variance, shard),
            ),
            error: self.error.clone(),
            interrupted: self.interrupted,
            shard: (!shard.is_whole()).then_some(shard),
            merged_from: Vec::new(),
        }
    }

    /// Writes `path` (the mean, EXR), its PNG preview, its variance ([`variance_path`]) and
    /// `summary` as JSON beside it.
    pub fn write(&self, path: &Path, summary: &ReferenceSummary) -> Result<(), ImageError> {
        self.image.write_exr(path)?;
        self.image.write_png(&path.with_extension("png"), 1.0)?;
        self.variance.write_exr(&variance_path(path))?;
        let json = serde_json::to_string_pretty(summary).expect("a summary serialises");
        scenes::file::output::write_bytes(&path.with_extension("json"), json).map_err(|e| {
            ImageError::Write {
                path: path.with_extension("json").display().to_string(),
                reason: e.to_string(),
            }
        })
    }
}

/// The rows of `image` that `shard` renders, as an image of their own (the zero rows of the
/// other shards would dilute any mean taken over the whole).
fn shard_rows(image: &Image, shard: Shard) -> Image {
    let w = image.width as usize;
    let pixels: Vec<[f32; 3]> = (0..image.height)
        .filter(|&y| shard.owns_row(y))
        .flat_map(|y| image.pixels[y as usize * w..][..w].iter().copied())
        .collect();
    Image {
        width: image.width,
        height: (pixels.len() / w.max(1)) as u32,
        pixels,
    }
}

/// What a reference's JSON file says about it.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceSummary {
    /// What rendered it.
    pub renderer: &'static str,
    /// Scene name.
    pub scene: String,
    /// Frame (0 before the scene's moves, 1 after).
    pub frame: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Seed.
    pub seed: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seconds of rendering.
    pub seconds: f64,
    /// Paths per second.
    pub samples_per_second: f64,
    /// Longest path.
    pub max_bounces: u32,
    /// Expected relative RMSE of the image against the truth (its own noise).
    pub relative_noise: f64,
    /// Why it stopped early, if it did.
    pub error: Option<String>,
    /// It was stopped (Ctrl-C) before its budget was spent: it holds the rounds completed.
    pub interrupted: bool,
    /// The rows it holds, when it is a shard (`ppm reference --shard I/N`): the others are
    /// zero until `ppm merge` joins it with the rest.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// The shard files it was merged from, if it was.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<String>,
}

/// Where the variance of the reference at `path` is stored: `NAME.var.exr` beside `NAME.exr`.
pub fn variance_path(path: &Path) -> PathBuf {
    path.with_extension("var.exr")
}

/// [`render_reference_shard`] of the whole image.
pub fn render_reference(
    compiled: &CompiledScene,
    seed: u32,
    budget: ReferenceBudget,
    on_round: &mut dyn FnMut(u32, f64) -> ControlFlow<()>,
) -> ReferenceImage {
    render_reference_shard(compiled, seed, budget, Shard::WHOLE, on_round)
}

/// Renders the rows of `shard` of `compiled` by path tracing until `budget` is spent, in rounds of one sample per
/// batch ([`sampler::BATCHES`]) per pixel, so a sample count is rounded up to a multiple of
/// it; `on_round(spp, seconds)` is called after each round, and ends the render there when
/// it breaks (a Ctrl-C).
///
/// Each pixel sums its own samples in order, so the result depends neither on the thread
/// count nor on the shard: a shard's rows are those rows of the whole image, bit for bit, and
/// the rows it does not own stay zero. A non-finite sample stops the render: the complete
/// rounds before it are returned, with the pixel and sample named in `error`.
pub fn render_reference_shard(
    compiled: &CompiledScene,
    seed: u32,
    budget: ReferenceBudget,
    shard: Shard,
    on_round: &mut dyn FnMut(u32, f64) -> ControlFlow<()>,
) -> ReferenceImage {
    let scene = SceneData::new(compiled);
    let camera = &compiled.camera;
    let tracer = PathTracer {
        scene: &scene,
        camera,
        // Relative to the extent, as the passes' offsets (no gather radius caps it here).
        ray_epsilon: RAY_EPSILON_RELATIVE * compiled.extent,
    };
    let (width, height) = (camera.width, camera.height);
    let mut sums = vec![BatchSums::default(); width as usize * height as usize];
    let rows: Vec<u32> = (0..height).filter(|&y| shard.owns_row(y)).collect();
    let clock = Stopwatch::start();
    let mut spp = 0;
    let mut error = None;
    let mut interrupted = false;
    while budget.spp.is_none_or(|n| spp < n) && budget.seconds.is_none_or(|s| clock.seconds() < s) {
        // The shard's rows, one after another: every pixel of them traces its samples.
        let round: Vec<[Vec3; BATCHES as usize]> = (0..rows.len() * width as usize)
            .into_par_iter()
            .with_min_len(16)
            .map(|i| {
                let (x, y) = (i as u32 % width, rows[i / width as usize]);
                std::array::from_fn(|b| tracer.sample(seed, x, y, spp + b as u32))
            })
            .collect();
        let bad = round
            .iter()
            .enumerate()
            .find_map(|(p, ls)| ls.iter().position(|l| !l.is_finite()).map(|b| (p, b)));
        if let Some((i, b)) = bad {
            let (x, y) = (i as u32 % width, rows[i / width as usize]);
            error = Some(format!(
                "sample {} of pixel ({x}, {y}) is not finite: {}",
                spp + b as u32,
                round[i][b]
            ));
            break;
        }
        let mut owned: Vec<&mut [BatchSums]> = sums
            .chunks_mut(width as usize)
            .enumerate()
            .filter(|(y, _)| shard.owns_row(*y as u32))
            .map(|(_, row)| row)
            .collect();
        owned
            .par_iter_mut()
            .zip(round.par_chunks(width as usize))
            .for_each(|(row, samples)| {
                for (acc, ls) in row.iter_mut().zip(samples) {
                    for (batch, l) in acc.0.iter_mut().zip(ls) {
                        for c in 0..3 {
                            batch[c] += f64::from(l[c]);
                        }
                    }
                }
            });
        spp += BATCHES;
        let spent = budget.spp.is_some_and(|n| spp >= n);
        if on_round(spp, clock.seconds()).is_break() && !spent {
            interrupted = true;
            break;
        }
    }
    let (image, variance) = mean_and_variance(&sums, width, height, spp / BATCHES);
    ReferenceImage {
        image,
        variance,
        spp,
        seconds: clock.seconds(),
        error,
        interrupted,
    }
}

/// One pixel's sums of the samples of each batch, per channel.
#[derive(Clone, Copy, Debug, Default)]
struct BatchSums([[f64; 3]; BATCHES as usize]);

/// Per-pixel means, and variances of the means from the spread of the batch means (each
/// batch an independent estimate of `per_batch` samples).
fn mean_and_variance(
    sums: &[BatchSums],
    width: u32,
    height: u32,
    per_batch: u32,
) -> (Image, Image) {
    let mut mean = Image::new(width, height);
    let mut variance = Image::new(width, height);
    if per_batch == 0 {
        return (mean, variance);
    }
    let (n, k) = (f64::from(per_batch), f64::from(BATCHES));
    for (i, s) in sums.iter().enumerate() {
        for c in 0..3 {
            let batch_means = s.0.map(|b| b[c] / n);
            let m = batch_means.iter().sum::<f64>() / k;
            let spread = batch_means.iter().map(|b| (b - m).powi(2)).sum::<f64>();
            mean.pixels[i][c] = m as f32;
            variance.pixels[i][c] = (spread / (k * (k - 1.0))) as f32;
        }
    }
    (mean, variance)
}

/// The image an error report measures against.
#[derive(Clone, Debug)]
pub struct Truth {
    /// The reference image.
    pub image: Image,
    /// Variance of its pixels' means, when known (path-traced references store it).
    pub variance: Option<Image>,
    /// Where it came from, for reports.
    pub source: String,
}

impl Truth {
    /// The reference's own expected relative RMSE against the truth, when its variance is known.
    pub fn noise(&self) -> Option<f64> {
        self.variance
            .as_ref()
            .map(|v| reference_noise(&self.image, v))
    }

    /// Reads a reference EXR from any renderer, refusing it unless it is `width` x `height`
    /// with R, G and B channels; a variance file beside it ([`variance_path`]) is read too.
    pub fn from_exr(path: &Path, width: u32, height: u32) -> Result<Self, ImageError> {
        let image = scenes::file::image::read_exr(path, width, height)?;
        let var = variance_path(path);
        let variance = if var.is_file() {
            Some(scenes::file::image::read_exr(&var, width, height)?)
        } else {
            None
        };
        Ok(Self {
            image,
            variance,
            source: path.display().to_string(),
        })
    }
}

impl From<(&ReferenceImage, String)> for Truth {
    fn from((r, source): (&ReferenceImage, String)) -> Self {
        Self {
            image: r.image.clone(),
            variance: Some(r.variance.clone()),
            source,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Batch means alternating 1 and 3 (two samples each): mean 2, spread of the batch
    /// means 1 per batch, so the variance of their average is `8 / (8 * 7)`.
    #[test]
    fn variance_of_the_mean_comes_from_the_spread_of_the_batch_means() {
        let mut sums = BatchSums::default();
        for (b, batch) in sums.0.iter_mut().enumerate() {
            *batch = [if b % 2 == 0 { 2.0 } else { 6.0 }; 3];
        }
        let (mean, var) = mean_and_variance(&[sums], 1, 1, 2);
        assert_eq!(mean.pixels[0], [2.0; 3]);
        assert_relative_eq!(var.pixels[0][0], 1.0 / 7.0, epsilon = 1e-7);
    }
}
