//! Distances between an image and a reference: what every error report measures.
//!
//! All are relative to the reference's mean value, so scenes of any brightness compare on one
//! axis: the pixel relative RMSE (the noise and bias a viewer sees), the same over the means of
//! square blocks of pixels (noise averages out within a block, bias and missing light do not),
//! and the ratio of the means (energy gained or lost).

use crate::image::Image;

/// Root-mean-square difference over all pixels and channels.
///
/// Panics if the images differ in size: comparing mismatched renders is a caller bug.
pub fn rmse(image: &Image, reference: &Image) -> f64 {
    assert_same_size(image, reference);
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| squared_error(a, b))
        .sum();
    (sum / (image.pixels.len() * 3).max(1) as f64).sqrt()
}

/// [`rmse`] divided by the reference's mean value: scale-free, so scenes of any brightness
/// compare on one axis. Zero when both images are black.
pub fn relative_rmse(image: &Image, reference: &Image) -> f64 {
    rmse(image, reference) / error_scale(reference)
}

/// [`relative_rmse`] split by a pixel mask: the parts from pixels outside and inside `mask`,
/// both over the whole image's pixel count and mean, so their squares sum to the whole's.
///
/// Panics if the images or the mask differ in size, as [`rmse`] does.
pub fn relative_rmse_parts(image: &Image, reference: &Image, mask: &[bool]) -> (f64, f64) {
    assert!(
        (image.width, image.height) == (reference.width, reference.height)
            && mask.len() == reference.pixels.len(),
        "rmse parts of images or a mask of different sizes"
    );
    let mut sums = [0.0f64; 2];
    for ((a, b), &inside) in image.pixels.iter().zip(&reference.pixels).zip(mask) {
        sums[usize::from(inside)] += squared_error(a, b);
    }
    let count = (reference.pixels.len() * 3).max(1) as f64;
    let scale = error_scale(reference);
    let part = |sum: f64| (sum / count).sqrt() / scale;
    (part(sums[0]), part(sums[1]))
}

/// [`relative_rmse`] of the two images averaged over `block` x `block` squares (partial
/// blocks at the right and bottom edges average what they cover).
///
/// Per-pixel noise shrinks by the block's pixel count, so this reads the errors that stay when
/// noise averages out: bias, blur, missing or extra light.
pub fn block_relative_rmse(image: &Image, reference: &Image, block: u32) -> f64 {
    assert_same_size(image, reference);
    relative_rmse(&block_means(image, block), &block_means(reference, block))
}

/// Mean of `image` over `block` x `block` squares: one pixel per square.
pub fn block_means(image: &Image, block: u32) -> Image {
    let block = block.max(1);
    let (bw, bh) = (image.width.div_ceil(block), image.height.div_ceil(block));
    let mut sums = vec![[0.0f64; 4]; (bw * bh) as usize];
    for y in 0..image.height {
        for x in 0..image.width {
            let s = &mut sums[((y / block) * bw + x / block) as usize];
            let p = image.at(x, y);
            for c in 0..3 {
                s[c] += f64::from(p[c]);
            }
            s[3] += 1.0;
        }
    }
    Image {
        width: bw,
        height: bh,
        pixels: sums
            .iter()
            .map(|s| [0, 1, 2].map(|c| (s[c] / s[3].max(1.0)) as f32))
            .collect(),
    }
}

/// Mean of the image over all pixels and channels.
pub fn mean_value(image: &Image) -> f64 {
    image
        .pixels
        .iter()
        .flatten()
        .map(|v| f64::from(*v))
        .sum::<f64>()
        / (image.pixels.len() * 3).max(1) as f64
}

/// `mean(image) / mean(reference)`: 1 when no energy is gained or lost (1 for two black
/// images, infinite for light where the reference is black).
pub fn mean_ratio(image: &Image, reference: &Image) -> f64 {
    assert_same_size(image, reference);
    let (a, b) = (mean_value(image), mean_value(reference));
    if b > 0.0 {
        a / b
    } else if a == 0.0 {
        1.0
    } else {
        f64::INFINITY
    }
}

/// The relative RMSE a reference is expected to have against the truth, from the variance
/// of its per-pixel means (`variance`, per channel): `sqrt(mean variance) / mean(reference)`.
///
/// An image measured against such a reference reads
/// `sqrt(its true error^2 + this^2)` in expectation: this is the floor no image gets below.
pub fn reference_noise(reference: &Image, variance: &Image) -> f64 {
    assert_same_size(reference, variance);
    mean_value(variance).max(0.0).sqrt() / error_scale(reference)
}

fn assert_same_size(a: &Image, b: &Image) {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "metrics of images of different sizes"
    );
}

/// Squared difference of two pixels, summed over the channels.
fn squared_error(a: &[f32; 3], b: &[f32; 3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
        .sum()
}

/// What relative errors divide by: the reference's mean value, or 1 for a black reference.
fn error_scale(reference: &Image) -> f64 {
    let mean = mean_value(reference);
    if mean > 0.0 { mean } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rmse_parts_split_the_error_by_mask() {
        let reference = Image {
            pixels: vec![[1.0; 3]; 4],
            width: 2,
            height: 2,
        };
        let mut image = reference.clone();
        image.pixels[0] = [2.0; 3];
        image.pixels[3] = [3.0; 3];
        let mask = [true, false, false, false];
        let (outside, inside) = relative_rmse_parts(&image, &reference, &mask);
        assert_relative_eq!(inside, (1.0f64 / 4.0).sqrt(), epsilon = 1e-12);
        assert_relative_eq!(outside, (4.0f64 / 4.0).sqrt(), epsilon = 1e-12);
        let whole = relative_rmse(&image, &reference);
        assert_relative_eq!(outside.hypot(inside), whole, epsilon = 1e-12);
    }

    #[test]
    fn rmse_of_a_constant_offset_is_the_offset() {
        let mut a = Image::new(4, 3);
        let mut b = Image::new(4, 3);
        a.pixels.iter_mut().for_each(|p| *p = [1.5; 3]);
        b.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
        assert_relative_eq!(rmse(&a, &b), 0.5, epsilon = 1e-12);
        assert_relative_eq!(relative_rmse(&a, &b), 0.5, epsilon = 1e-12);
        assert_eq!(rmse(&b, &b), 0.0);
    }

    /// Noise that averages to zero within each block vanishes from the block metric; a bias
    /// stays, at its full size.
    #[test]
    fn block_metric_keeps_bias_and_drops_noise_that_cancels_in_a_block() {
        let reference = Image {
            pixels: vec![[1.0; 3]; 16],
            width: 4,
            height: 4,
        };
        let mut noisy = reference.clone();
        for (i, p) in noisy.pixels.iter_mut().enumerate() {
            let (x, y) = (i % 4, i / 4);
            *p = [if (x + y) % 2 == 0 { 1.5 } else { 0.5 }; 3];
        }
        assert_relative_eq!(relative_rmse(&noisy, &reference), 0.5, epsilon = 1e-12);
        assert_relative_eq!(
            block_relative_rmse(&noisy, &reference, 2),
            0.0,
            epsilon = 1e-12
        );
        let biased = Image {
            pixels: vec![[1.1; 3]; 16],
            ..reference.clone()
        };
        assert_relative_eq!(
            block_relative_rmse(&biased, &reference, 2),
            0.1,
            epsilon = 1e-6
        );
        assert_relative_eq!(mean_ratio(&biased, &reference), 1.1, epsilon = 1e-6);
    }

    #[test]
    fn partial_blocks_average_what_they_cover() {
        let image = Image {
            pixels: (0..15).map(|i| [i as f32; 3]).collect(),
            width: 5,
            height: 3,
        };
        let means = block_means(&image, 4);
        assert_eq!((means.width, means.height), (2, 1));
        // Columns 4 of rows 0..3: values 4, 9, 14.
        assert_relative_eq!(means.pixels[1][0], 9.0);
    }

    #[test]
    fn reference_noise_is_the_root_mean_variance_over_the_mean() {
        let reference = Image {
            pixels: vec![[2.0; 3]; 4],
            width: 2,
            height: 2,
        };
        let variance = Image {
            pixels: vec![[0.04; 3]; 4],
            ..reference.clone()
        };
        assert_relative_eq!(reference_noise(&reference, &variance), 0.1, epsilon = 1e-6);
    }
}
