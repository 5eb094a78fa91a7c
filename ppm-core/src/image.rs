//! Linear RGB images, as passes resolve them and reports measure them. Their files (EXR,
//! PNG) are written and read by `scenes::file::image`.

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

    /// The luminance of the brightest pixel (0 for a black or empty image): how far a
    /// render's highlights stray from the truth's.
    pub fn brightest(&self) -> f32 {
        self.pixels
            .iter()
            .map(|&p| crate::update::luminance(p))
            .fold(0.0, f32::max)
    }

    /// Whether every channel of every pixel is finite.
    pub fn is_finite(&self) -> bool {
        self.pixels.iter().flatten().all(|v| v.is_finite())
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

/// The linear value of an sRGB-encoded one in [0, 1] (the inverse of [`srgb_encode`]).
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_is_monotonic_and_clamped() {
        assert_eq!(srgb_encode(-1.0), 0.0);
        assert_eq!(srgb_encode(f32::NAN), 0.0);
        assert_eq!(srgb_encode(5.0), 1.0);
        assert!(srgb_encode(0.2) < srgb_encode(0.21));
    }

    #[test]
    fn the_brightest_pixel_is_weighed_by_luminance() {
        let mut image = Image::new(2, 1);
        assert_eq!(image.brightest(), 0.0);
        // Blue carries the least luminance: the green pixel is the brighter.
        image.pixels = vec![[0.0, 0.0, 2.0], [0.0, 1.0, 0.0]];
        approx::assert_relative_eq!(image.brightest(), 0.7152);
    }
}
