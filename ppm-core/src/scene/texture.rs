//! Image textures: a material's colour read from an image through the surface's texture
//! coordinates (docs/materials.md, "Textures").
//!
//! Conventions are pbrt-v4's, so that its scenes render as it renders them: `(s, t) = scale *
//! uv + offset`, the image repeats, `t = 0` is the image's bottom row, and a bilinear lookup
//! weighs the four texel centres around the point. Texels are linear RGB held as half
//! floats, two words per texel, in the form both backends read ([`pack_texel`]): the CPU and
//! the GPU look up the same numbers.

use glam::{Vec2, Vec3};

/// How a lookup combines texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureFilter {
    /// The four nearest texel centres, weighted by distance (pbrt's "bilinear").
    Bilinear,
    /// The texel the point falls in (a checkerboard's hard edges).
    Nearest,
}

/// An image that scales a material's colour, wrapped by repetition.
#[derive(Clone, PartialEq)]
pub struct Texture {
    /// Where it came from (file name or procedural description), for messages.
    pub name: String,
    /// Width in texels, at least 1.
    pub width: u32,
    /// Height in texels, at least 1.
    pub height: u32,
    /// Row-major from the top row, [`pack_texel`]ed.
    pub texels: Vec<[u32; 2]>,
    /// Lookup filter.
    pub filter: TextureFilter,
    /// `(s, t) = scale * uv + offset`.
    pub scale: Vec2,
    /// See `scale`.
    pub offset: Vec2,
}

impl std::fmt::Debug for Texture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Texture({}, {}x{})", self.name, self.width, self.height)
    }
}

/// Largest width or height kept: a larger image is reduced (box filter) until it fits, since
/// no render resolves more and both backends hold every texel ([`Texture::from_fn`]).
pub const MAX_TEXTURE_SIDE: u32 = 4096;

impl Texture {
    /// A texture of `width * height` linear RGB texels, rows from the top
    /// ([`Texture::from_fn`]).
    pub fn from_linear(
        name: &str,
        width: u32,
        height: u32,
        texels: &[Vec3],
        filter: TextureFilter,
    ) -> Result<Self, String> {
        if texels.len() != width as usize * height as usize {
            return Err(format!(
                "texture '{name}': {width}x{height} texels expected, {} given",
                texels.len()
            ));
        }
        Self::from_fn(name, width, height, filter, |x, y| {
            texels[(y * width + x) as usize]
        })
    }

    /// A texture of `width * height` linear RGB texels, `texel(x, y)` from the top row.
    /// Values above 1 are clamped to 1 (a reflectance cannot exceed it; pbrt clamps the
    /// same way); a texel that is negative or not finite is refused, with its position. An
    /// image wider or taller than [`MAX_TEXTURE_SIDE`] is reduced by averaging square
    /// blocks of a power of two texels, read once each: no copy at full size is made.
    pub fn from_fn(
        name: &str,
        width: u32,
        height: u32,
        filter: TextureFilter,
        texel: impl Fn(u32, u32) -> Vec3,
    ) -> Result<Self, String> {
        if width == 0 || height == 0 {
            return Err(format!("texture '{name}': {width}x{height} texels (empty)"));
        }
        let mut block = 1u32;
        while width.div_ceil(block) > MAX_TEXTURE_SIDE || height.div_ceil(block) > MAX_TEXTURE_SIDE
        {
            block *= 2;
        }
        let (w, h) = (width.div_ceil(block), height.div_ceil(block));
        let mut texels = Vec::with_capacity(w as usize * h as usize);
        for by in 0..h {
            for bx in 0..w {
                let mut sum = Vec3::ZERO;
                let mut count = 0.0f32;
                for y in by * block..((by + 1) * block).min(height) {
                    for x in bx * block..((bx + 1) * block).min(width) {
                        let t = texel(x, y);
                        if !t.is_finite() || t.min_element() < 0.0 {
                            return Err(format!(
                                "texture '{name}': texel ({x}, {y}) is {t} (texels must be finite and non-negative)"
                            ));
                        }
                        sum += t.min(Vec3::ONE);
                        count += 1.0;
                    }
                }
                texels.push(pack_texel(sum / count));
            }
        }
        Ok(Self {
            name: name.to_string(),
            width: w,
            height: h,
            texels,
            filter,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
        })
    }

    /// A `uscale x vscale` checkerboard of `even` and `odd` squares over the unit square, as
    /// pbrt-v4's 2D `checkerboard`: the square `(floor s + floor t)` even is `even`.
    pub fn checkerboard(even: Vec3, odd: Vec3, scale: Vec2) -> Result<Self, String> {
        // Two by two texels over two squares each way; rows from the top, where t is 1.
        let texels = [odd, even, even, odd];
        let mut texture = Self::from_linear(
            &format!("checkerboard {even} / {odd}"),
            2,
            2,
            &texels,
            TextureFilter::Nearest,
        )?;
        texture.scale = scale * 0.5;
        Ok(texture)
    }

    /// The texture's colour at texture coordinates `uv`.
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        sample(&gpu_texture(self), &self.texels, uv)
    }
}

/// A texel as the backends hold it: red and green as half floats in the first word (red in
/// the low 16 bits), blue in the low half of the second.
pub fn pack_texel(c: Vec3) -> [u32; 2] {
    let h = |x: f32| u32::from(half_bits(x));
    [h(c.x) | (h(c.y) << 16), h(c.z)]
}

/// [`pack_texel`]'s inverse, exact.
pub fn unpack_texel(t: [u32; 2]) -> Vec3 {
    let f = |bits: u32| half_to_f32(bits as u16);
    Vec3::new(f(t[0] & 0xffff), f(t[0] >> 16), f(t[1] & 0xffff))
}

/// `x` (finite, in [0, 1]) as the nearest IEEE half float.
fn half_bits(x: f32) -> u16 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    if exponent < -24 {
        return 0;
    }
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    // Half floats keep 10 mantissa bits above 2^-14, fewer below (subnormals).
    let shift = if exponent < -14 {
        13 + (-14 - exponent)
    } else {
        13
    } as u32;
    let mut m = mantissa >> shift;
    let rest = mantissa & ((1 << shift) - 1);
    let halfway = 1 << (shift - 1);
    if rest > halfway || (rest == halfway && m & 1 == 1) {
        m += 1;
    }
    if exponent < -14 {
        m as u16
    } else {
        // The carry of a rounded-up mantissa moves into the exponent, as it should.
        ((((exponent + 15) as u32) << 10) + (m - 0x400)) as u16
    }
}

/// An IEEE half float's value (in [0, 1]: no infinity or NaN), built from its bits as
/// `half_to_f32` in textures.wgsl.
fn half_to_f32(h: u16) -> f32 {
    let exponent = u32::from(h >> 10) & 0x1f;
    let mantissa = u32::from(h & 0x3ff);
    if exponent == 0 {
        return mantissa as f32 * 2f32.powi(-24);
    }
    f32::from_bits(((exponent + 112) << 23) | (mantissa << 13))
}

/// A texture's header as the backends read it; `first` is left for the caller to place.
pub(crate) fn gpu_texture(t: &Texture) -> crate::layout::GpuTexture {
    crate::layout::GpuTexture {
        first: 0,
        width: t.width,
        height: t.height,
        nearest: u32::from(t.filter == TextureFilter::Nearest),
        scale: t.scale.into(),
        offset: t.offset.into(),
    }
}

/// The colour of texture `header`, whose texels start at `texels[header.first]`, at `uv`:
/// the rule `texture_sample` in textures.wgsl follows step for step.
pub fn sample(header: &crate::layout::GpuTexture, texels: &[[u32; 2]], uv: Vec2) -> Vec3 {
    let st = Vec2::from(header.scale) * uv + Vec2::from(header.offset);
    // Repeat, then flip t: t = 0 is the bottom row.
    let s = fraction(st.x);
    let t = 1.0 - fraction(st.y);
    let (w, h) = (header.width, header.height);
    let texel = |x: u32, y: u32| unpack_texel(texels[(header.first + y * w + x) as usize]);
    // Finite coordinates put s in [0, 1]; the clamps keep every index in range whatever
    // rounding or an infinite coordinate did.
    let x = s * w as f32;
    let y = t * h as f32;
    if header.nearest != 0 {
        return texel(index(x, w), index(y, h));
    }
    let (x, y) = (x - 0.5, y - 0.5);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let (x0, y0) = (wrap(x.floor(), w), wrap(y.floor(), h));
    let (x1, y1) = ((x0 + 1) % w, (y0 + 1) % h);
    let top = texel(x0, y0) * (1.0 - fx) + texel(x1, y0) * fx;
    let bottom = texel(x0, y1) * (1.0 - fx) + texel(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// `x - floor(x)`, in [0, 1]; 0 for a coordinate that is not finite (whose fraction is NaN),
/// so that it still reads a texel.
fn fraction(x: f32) -> f32 {
    let f = x - x.floor();
    if (0.0..=1.0).contains(&f) { f } else { 0.0 }
}

/// `floor(x)` as an index in `0 .. n`, for `x` in `[0, n]` (anything else clamped).
fn index(x: f32, n: u32) -> u32 {
    (x.max(0.0) as u32).min(n - 1)
}

/// The texel column or row `i` (a whole number in `[-1, n]`) wraps to, in `0 .. n`.
fn wrap(i: f32, n: u32) -> u32 {
    if i < 0.0 {
        n - 1
    } else {
        (i as u32).min(n) % n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_near(a: Vec3, b: Vec3) {
        assert!((a - b).abs().max_element() < 1e-6, "{a} != {b}");
    }

    #[test]
    fn half_floats_round_to_nearest_and_unpack_exactly() {
        for x in [0.0, 1.0, 0.5, 0.1, 1e-3, 1e-5, 6.0e-8, 0.999_9, 0.214_041] {
            let back = unpack_texel(pack_texel(Vec3::splat(x))).x;
            // Half floats carry 11 significant bits above 2^-14, an absolute 2^-24 below.
            assert!(
                (back - x).abs() <= (x * 2f32.powi(-11)).max(2f32.powi(-25)),
                "{x} -> {back}"
            );
        }
        // Every half float in [0, 1] survives the round trip bit for bit.
        for bits in 0u16..=0x3c00 {
            let x = half_to_f32(bits);
            assert_eq!(half_bits(x), bits, "{x}");
        }
    }

    fn ramp() -> Texture {
        // 4x2: red grows to the right, green is 1 on the top row.
        let texels: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i % 4) as f32 / 4.0, if i < 4 { 1.0 } else { 0.0 }, 0.5))
            .collect();
        Texture::from_linear("ramp", 4, 2, &texels, TextureFilter::Bilinear).unwrap()
    }

    #[test]
    fn bilinear_lookup_weighs_texel_centres_with_t_up() {
        let t = ramp();
        // Texel centres: s = (x + 0.5) / 4, t = 1 - (y + 0.5) / 2.
        assert_near(t.lookup(Vec2::new(0.125, 0.75)), Vec3::new(0.0, 1.0, 0.5));
        assert_near(t.lookup(Vec2::new(0.625, 0.25)), Vec3::new(0.5, 0.0, 0.5));
        // Half-way between two columns and between the rows.
        assert_near(t.lookup(Vec2::new(0.25, 0.5)), Vec3::new(0.125, 0.5, 0.5));
        // The left edge blends the last column in (repetition), and whole periods change nothing.
        assert_near(t.lookup(Vec2::new(0.0, 0.75)), Vec3::new(0.375, 1.0, 0.5));
        assert_near(
            t.lookup(Vec2::new(-3.0, 5.75)),
            t.lookup(Vec2::new(0.0, 0.75)),
        );
    }

    #[test]
    fn lookups_stay_in_range_for_any_coordinate() {
        let t = ramp();
        for uv in [
            Vec2::new(1e30, -1e30),
            Vec2::new(f32::INFINITY, 0.5),
            Vec2::new(f32::NAN, 0.5),
            Vec2::new(1.0 - f32::EPSILON / 4.0, 1.0),
        ] {
            let c = t.lookup(uv);
            assert!(c.max_element() <= 1.0, "{uv}: {c}");
        }
    }

    #[test]
    fn checkerboard_follows_pbrt_parity() {
        let (even, odd) = (Vec3::ONE, Vec3::ZERO);
        let c = Texture::checkerboard(even, odd, Vec2::new(4.0, 2.0)).unwrap();
        for (u, v) in [(0.1, 0.1), (0.3, 0.1), (0.1, 0.6), (0.9, 0.9), (0.6, 0.2)] {
            let st = Vec2::new(u * 4.0, v * 2.0);
            let parity = (st.x.floor() + st.y.floor()) as i32 % 2;
            let expected = if parity == 0 { even } else { odd };
            assert_eq!(c.lookup(Vec2::new(u, v)), expected, "uv ({u}, {v})");
        }
    }

    #[test]
    fn bad_texels_are_named_and_large_images_are_halved() {
        let mut texels = vec![Vec3::splat(0.5); 6];
        texels[4] = Vec3::new(0.1, f32::NAN, 0.2);
        let err =
            Texture::from_linear("wall.exr", 3, 2, &texels, TextureFilter::Bilinear).unwrap_err();
        assert!(err.contains("wall.exr") && err.contains("(1, 1)"), "{err}");
        let big = vec![Vec3::splat(2.0); (MAX_TEXTURE_SIDE as usize + 1) * 3];
        let t = Texture::from_linear(
            "wide",
            MAX_TEXTURE_SIDE + 1,
            3,
            &big,
            TextureFilter::Bilinear,
        )
        .unwrap();
        assert_eq!((t.width, t.height), (MAX_TEXTURE_SIDE / 2 + 1, 2));
        // 16k x 16k of one colour: read through the closure, never held at full size.
        let huge = Texture::from_fn("huge", 16384, 16384, TextureFilter::Bilinear, |_, _| {
            Vec3::new(0.25, 0.5, 0.75)
        })
        .unwrap();
        assert_eq!(
            (huge.width, huge.height),
            (MAX_TEXTURE_SIDE, MAX_TEXTURE_SIDE)
        );
        assert_eq!(unpack_texel(huge.texels[12345]), Vec3::new(0.25, 0.5, 0.75));
        assert_eq!(unpack_texel(t.texels[0]), Vec3::ONE, "clamped to 1");
    }
}
