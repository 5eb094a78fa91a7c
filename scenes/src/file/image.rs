//! Image files: a linear float EXR (exact floats) any renderer reads, a tone-mapped PNG
//! preview, and the EXR of another renderer read back as a truth.

use crate::file::output::write_bytes;
use ppm_core::image::{Image, srgb_encode};
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

/// Writing an image to files.
pub trait ImageFiles {
    /// Writes a linear float EXR (RGB, f32), atomically.
    fn write_exr(&self, path: &Path) -> Result<(), ImageError>;
    /// Writes an 8-bit sRGB PNG preview: radiance times `exposure`, clamped, sRGB-encoded;
    /// atomically.
    fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError>;
}

impl ImageFiles for Image {
    fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        use exr::prelude::{SpecificChannels, Vec2, WritableImage};
        let w = self.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = self.pixels[y * w + x];
            (p[0], p[1], p[2])
        });
        // Tiles in increasing order, however the parallel compressor finishes them: the same
        // image always makes the same bytes (merged shards compare equal to one run's file).
        let encoding = exr::prelude::Encoding {
            line_order: exr::prelude::LineOrder::Increasing,
            ..exr::prelude::Encoding::FAST_LOSSLESS
        };
        let image = exr::prelude::Image::from_encoded_channels(
            (w, self.height as usize),
            encoding,
            channels,
        );
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

    fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
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

/// Reads the RGB channels of an EXR written by any renderer, refusing it (before its
/// pixels are read, so a huge file allocates nothing) unless it is `width` x `height`
/// and has R, G and B channels.
pub fn read_exr(path: &Path, width: u32, height: u32) -> Result<Image, ImageError> {
    let err = |reason: String| ImageError::Read {
        path: path.display().to_string(),
        reason,
    };
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| err(e.to_string()))?;
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
        assert_eq!(read_exr(&path, 3, 2).unwrap(), a);
        let wrong = read_exr(&path, 4, 2).unwrap_err().to_string();
        assert!(
            wrong.ends_with(
                "cannot read image: it is 3x2 pixels, the image it is compared with is 4x2"
            ),
            "{wrong}"
        );
        a.write_png(&dir.join("a.png"), 1.0).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }
}
