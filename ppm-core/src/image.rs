//! Linear RGB images: EXR output (exact floats), a tone-mapped PNG preview, and error metrics.

use crate::output::write_bytes;
use std::io;
use std::path::Path;
use thiserror::Error;

/// Why an image could not be written or read.
#[derive(Debug, Error)]
pub enum ImageError {
    /// Writing failed.
    #[error("{path}: cannot write image: {reason}")]
    Write {
        /// Target file.
        path: String,
        /// What went wrong.
        reason: String,
    },
    /// Reading failed, or the file is not the image the caller needs.
    #[error("{path}: cannot read image: {reason}")]
    Read {
        /// Source file.
        path: String,
        /// What went wrong.
        reason: String,
    },
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

    /// Writes a linear float EXR (RGB, f32), atomically.
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        use exr::prelude::{SpecificChannels, Vec2, WritableImage};
        let w = self.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = self.pixels[y * w + x];
            (p[0], p[1], p[2])
        });
        let image = exr::prelude::Image::from_channels((w, self.height as usize), channels);
        let mut encoded = io::Cursor::new(Vec::new());
        image
            .write()
            .to_buffered(&mut encoded)
            .map_err(io::Error::other)
            .and_then(|()| write_bytes(path, encoded.into_inner()))
            .map_err(|e| ImageError::Write {
                path: path.display().to_string(),
                reason: e.to_string(),
            })
    }

    /// Reads the RGB channels of an EXR written by any renderer, refusing it (before its
    /// pixels are read, so a huge file allocates nothing) unless it is `width` x `height`
    /// and has R, G and B channels.
    pub fn read_exr(path: &Path, width: u32, height: u32) -> Result<Image, ImageError> {
        let err = |reason: String| ImageError::Read {
            path: path.display().to_string(),
            reason,
        };
        let meta =
            exr::meta::MetaData::read_from_file(path, false).map_err(|e| err(e.to_string()))?;
        let header = meta
            .headers
            .first()
            .ok_or_else(|| err("the file holds no image layer".into()))?;
        let size = header.layer_size;
        if (size.width(), size.height()) != (width as usize, height as usize) {
            return Err(err(format!(
                "it is {}x{} pixels, the image it is compared with is {width}x{height}",
                size.width(),
                size.height()
            )));
        }
        let names: Vec<String> = header
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        if let Some(missing) = ["R", "G", "B"]
            .into_iter()
            .find(|c| !names.iter().any(|n| n == c))
        {
            return Err(err(format!(
                "it has no {missing} channel (channels: {})",
                names.join(", ")
            )));
        }
        let read = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |res, _| Image::new(res.width() as u32, res.height() as u32),
            |img: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let w = img.width as usize;
                img.pixels[pos.y() * w + pos.x()] = [r, g, b]
            },
        )
        .map_err(|e| err(e.to_string()))?;
        Ok(read.layer_data.channel_data.pixels)
    }

    /// Writes an 8-bit sRGB PNG preview: radiance times `exposure`, clamped, sRGB-encoded;
    /// atomically.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flatten()
            .map(|v| (srgb_encode(v * exposure) * 255.0 + 0.5) as u8)
            .collect();
        write_png_rgb(path, &bytes, self.width, self.height).map_err(|e| ImageError::Write {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
    }
}

/// Writes 8-bit RGB `rgb` (`width * height * 3` bytes) as a PNG file, atomically.
pub fn write_png_rgb(path: &Path, rgb: &[u8], width: u32, height: u32) -> io::Result<()> {
    let mut encoded = Vec::new();
    let mut encoder = png::Encoder::new(&mut encoded, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(io::Error::other)?;
    writer.write_image_data(rgb).map_err(io::Error::other)?;
    writer.finish().map_err(io::Error::other)?;
    write_bytes(path, encoded)
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(Image::read_exr(&path, 3, 2).unwrap(), a);
        let wrong = Image::read_exr(&path, 4, 2).unwrap_err().to_string();
        assert!(
            wrong.ends_with(
                "cannot read image: it is 3x2 pixels, the image it is compared with is 4x2"
            ),
            "{wrong}"
        );
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
