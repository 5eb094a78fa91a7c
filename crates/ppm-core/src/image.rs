//! Linear RGB images: EXR output (exact floats), a tone-mapped PNG preview, and error metrics.

use std::path::Path;
use thiserror::Error;

/// Why an image could not be written.
#[derive(Debug, Error)]
#[error("{path}: cannot write image: {reason}")]
pub struct ImageError {
    /// Target file.
    pub path: String,
    /// What went wrong.
    pub reason: String,
}

/// A linear-RGB float image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y`.
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean of each channel over the rectangle `x0..x1` by `y0..y1`.
    pub fn mean_in(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for y in y0..y1 {
            for x in x0..x1 {
                let p = self.at(x, y);
                for c in 0..3 {
                    sum[c] += f64::from(p[c]);
                }
            }
        }
        let count = f64::from((x1 - x0) * (y1 - y0)).max(1.0);
        sum.map(|s| s / count)
    }

    /// Whether every channel of every pixel is finite.
    pub fn is_finite(&self) -> bool {
        self.pixels.iter().flatten().all(|v| v.is_finite())
    }

    /// Writes a linear float EXR (RGB, f32).
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        let w = self.width as usize;
        exr::prelude::write_rgb_file(path, w, self.height as usize, |x, y| {
            let p = self.pixels[y * w + x];
            (p[0], p[1], p[2])
        })
        .map_err(|e| ImageError {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
    }

    /// Writes an 8-bit sRGB PNG preview: radiance times `exposure`, clamped, sRGB-encoded.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
        let err = |reason: String| ImageError {
            path: path.display().to_string(),
            reason,
        };
        let file = std::fs::File::create(path).map_err(|e| err(e.to_string()))?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flatten()
            .map(|v| (srgb_encode(v * exposure) * 255.0 + 0.5) as u8)
            .collect();
        let mut writer = encoder.write_header().map_err(|e| err(e.to_string()))?;
        writer
            .write_image_data(&bytes)
            .map_err(|e| err(e.to_string()))
    }
}

/// The sRGB transfer function of a linear value, clamped to [0, 1]; NaN maps to 0.
pub fn srgb_encode(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else if v >= 1.0 {
        1.0
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Root-mean-square difference over all pixels and channels.
///
/// Panics if the images differ in size: comparing mismatched renders is a caller bug.
pub fn rmse(image: &Image, reference: &Image) -> f64 {
    assert_eq!(
        (image.width, image.height),
        (reference.width, reference.height),
        "rmse of images of different sizes"
    );
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

/// Squared difference of two pixels, summed over the channels.
fn squared_error(a: &[f32; 3], b: &[f32; 3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
        .sum()
}

/// What relative errors divide by: the reference's mean value, or 1 for a black reference.
fn error_scale(reference: &Image) -> f64 {
    let mean: f64 = reference
        .pixels
        .iter()
        .flatten()
        .map(|v| f64::from(*v))
        .sum::<f64>()
        / (reference.pixels.len() * 3).max(1) as f64;
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

    #[test]
    fn exr_round_trips_exact_floats() {
        let dir = std::env::temp_dir().join(format!("ppm-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut a = Image::new(3, 2);
        a.pixels[4] = [0.25, 1e-7, 3.0e4];
        let path = dir.join("a.exr");
        a.write_exr(&path).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
            |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * 3 + pos.x()] = [r, g, b]
            },
        )
        .unwrap();
        assert_eq!(read.layer_data.channel_data.pixels, a.pixels);
        a.write_png(&dir.join("a.png"), 1.0).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn srgb_is_monotonic_and_clamped() {
        assert_eq!(srgb_encode(-1.0), 0.0);
        assert_eq!(srgb_encode(f32::NAN), 0.0);
        assert_eq!(srgb_encode(5.0), 1.0);
        assert!(srgb_encode(0.2) < srgb_encode(0.21));
    }
}
