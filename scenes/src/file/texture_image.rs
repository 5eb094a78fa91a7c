//! Texture images read from files: 8-bit formats (TGA, PNG, JPEG, BMP) through the `image`
//! crate, decoded from their encoding to linear values, and EXR (already linear) through
//! `exr`; both become a [`Texture`], reduced in size where the image is larger than the
//! backends keep.

use crate::file::limits::{TEXTURE_FILE_LIMIT, check_file_size};
use glam::Vec3;
use ppm_core::image::srgb_decode;
use ppm_core::scene::{Texture, TextureFilter};
use std::path::Path;

/// How an 8-bit image's values map to linear ones (pbrt-v4's `encoding`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Encoding {
    /// The sRGB curve (the default for 8-bit images).
    Srgb,
    /// Value / 255.
    Linear,
    /// (value / 255) to the power `gamma`.
    Gamma(f32),
}

/// What a scene file says about an image texture besides its file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageOptions {
    /// The 8-bit encoding (ignored for EXR, which is linear).
    pub encoding: Encoding,
    /// Factor on every texel.
    pub scale: f32,
    /// Whether texels become `1 - value` (after the scale, as pbrt-v4).
    pub invert: bool,
    /// Lookup filter.
    pub filter: TextureFilter,
}

impl Default for ImageOptions {
    fn default() -> Self {
        Self {
            encoding: Encoding::Srgb,
            scale: 1.0,
            invert: false,
            filter: TextureFilter::Bilinear,
        }
    }
}

/// Reads `path` as a texture; the error names the file and what is wrong.
pub fn read_texture(path: &Path, options: ImageOptions) -> Result<Texture, String> {
    let name = path.display().to_string();
    let fail = |e: String| format!("cannot read texture {name}: {e}");
    check_file_size(path, TEXTURE_FILE_LIMIT).map_err(fail)?;
    let finish = |c: Vec3| {
        let c = c * options.scale;
        if options.invert {
            (Vec3::ONE - c).max(Vec3::ZERO)
        } else {
            c
        }
    };
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        let image = read_exr_any(path).map_err(fail)?;
        let w = image.width;
        return Texture::from_fn(&name, image.width, image.height, options.filter, |x, y| {
            finish(Vec3::from(image.pixels[(y * w + x) as usize]))
        });
    }
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| fail(e.to_string()))?
        .with_guessed_format()
        .map_err(|e| fail(e.to_string()))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(TEXTURE_FILE_LIMIT);
    reader.limits(limits);
    let rgb = reader
        .decode()
        .map_err(|e| fail(e.to_string()))?
        .into_rgb8();
    let decode = |v: u8| {
        let x = f32::from(v) / 255.0;
        match options.encoding {
            Encoding::Srgb => srgb_decode(x),
            Encoding::Linear => x,
            Encoding::Gamma(g) => x.powf(g),
        }
    };
    let table: Vec<f32> = (0..=255u8).map(decode).collect();
    Texture::from_fn(&name, rgb.width(), rgb.height(), options.filter, |x, y| {
        let p = rgb.get_pixel(x, y).0;
        finish(Vec3::new(
            table[p[0] as usize],
            table[p[1] as usize],
            table[p[2] as usize],
        ))
    })
}

/// An EXR's RGB channels at whatever size it has.
fn read_exr_any(path: &Path) -> Result<ppm_core::image::Image, String> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| e.to_string())?;
    let size = meta
        .headers
        .first()
        .ok_or("the file holds no image layer")?
        .layer_size;
    crate::file::image::read_exr(path, size.width() as u32, size.height() as u32)
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::file::image::ImageFiles;
    use ppm_core::image::Image;

    #[test]
    fn eight_bit_images_decode_to_linear_rows_from_the_top() {
        let dir = std::env::temp_dir().join(format!("ppm-texture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 2x1: white on the left, sRGB 128 grey on the right.
        let png = dir.join("t.png");
        crate::file::image::write_png_rgb(&png, &[255, 255, 255, 128, 128, 128], 2, 1).unwrap();
        let t = read_texture(&png, ImageOptions::default()).unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        let right = ppm_core::scene::unpack_texel(t.texels[1]).x;
        assert!((right - 0.2158605).abs() < 1e-3, "{right}");
        let linear = ImageOptions {
            encoding: Encoding::Linear,
            invert: true,
            ..Default::default()
        };
        let t = read_texture(&png, linear).unwrap();
        assert_eq!(ppm_core::scene::unpack_texel(t.texels[0]), Vec3::ZERO);
        // An EXR with a NaN texel is refused with the texel named.
        let mut image = Image::new(2, 2);
        image.pixels[3] = [0.5, f32::NAN, 0.5];
        let exr = dir.join("nan.exr");
        image.write_exr(&exr).unwrap();
        let err = read_texture(&exr, ImageOptions::default()).unwrap_err();
        assert!(err.contains("nan.exr") && err.contains("(1, 1)"), "{err}");
        let err = read_texture(&dir.join("missing.tga"), ImageOptions::default()).unwrap_err();
        assert!(err.contains("missing.tga"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
