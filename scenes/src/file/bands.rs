//! Colours as spectra that a spectral renderer turns back into our RGB.
//!
//! pbrt-v4 (always) and Mitsuba 3's spectral variants turn an RGB colour into a smooth
//! spectrum, and a product of smooth spectra is not the product of the colours: our Cornell
//! box's red wall, rendered so, keeps a sixth of its blue. A colour constant within three
//! bands of wavelengths multiplies band by band as RGB channels do, and a light whose
//! spectrum inside each band lights one sRGB channel alone (`LIGHT`) makes each band read
//! back as that channel. Bands: blue 360-437.5 and 447.5-497.5 nm, green 497.5-577.5 nm,
//! red 437.5-447.5 and 577.5-830 nm (the sRGB blue channel is negative at every wavelength
//! above 514.5 nm, so red takes a violet sliver to cancel it). `scripts/spectral-bands.py`
//! designs `LIGHT`; docs/other-renderers.md measures the result in Mitsuba 3.
//!
//! Spectra are written as (wavelength nm, value) points of a piecewise linear function,
//! stepping within a thousandth of a nanometre at cell edges, which lie on half nanometres
//! so that pbrt-v4, which samples a light's spectrum at the nearest whole nanometre, steps
//! where the colours do.

use glam::Vec3;
use ppm_core::scene::Scene;

/// How an export writes its colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colours {
    /// RGB triples: exact for an RGB renderer (Mitsuba 3's `scalar_rgb`).
    Rgb,
    /// Band spectra (this module): for a spectral renderer.
    Bands,
}

impl Colours {
    /// The band spectrum an export writes for a reflectance, or `None` where it writes RGB:
    /// with RGB colours, and for a grey, which both renderers make a flat spectrum, exact
    /// (Mitsuba also refuses a spectrum that is zero everywhere).
    pub fn reflectance(self, colour: Vec3) -> Option<Vec<(f32, f32)>> {
        (self == Colours::Bands && colour.min_element() != colour.max_element())
            .then(|| reflectance(colour))
    }

    /// The band spectrum an export writes for a light's radiance, or `None` where it writes
    /// RGB: with RGB colours, and for no light at all.
    pub fn illuminant(self, radiance: Vec3) -> Option<Vec<(f32, f32)>> {
        (self == Colours::Bands && radiance != Vec3::ZERO).then(|| illuminant(radiance))
    }

    /// The note an export's header carries where band colours meet texture images, which
    /// stay RGB and which `renderer` turns into smooth spectra.
    pub fn texture_note(self, scene: &Scene, renderer: &str) -> Option<String> {
        (self == Colours::Bands && scene.materials.iter().any(|m| m.texture.is_some())).then(|| {
            format!(
                "texture images stay RGB, which {renderer} turns into smooth spectra: a \
                 textured colour's products with other colours are not ours"
            )
        })
    }
}

/// Number of cells, each 5 nm but the first and last (2.5 nm).
const CELLS: usize = 95;

/// Shortest and longest wavelength both renderers sample.
const LAMBDA_MIN: f32 = 360.0;
const LAMBDA_MAX: f32 = 830.0;

/// Width of a step between cells, in nm.
const STEP: f32 = 1e-3;

/// The light's spectrum per cell and unit of its band's channel: inside each band it gives
/// that sRGB channel 1 and the others 0 (to 2e-11), Mitsuba 3's way of turning a spectrum
/// into colour (the CIE 1931 observer over its constant 106.7503, the integral of y-bar
/// within 0.1%), as flat as that allows. Printed by `scripts/spectral-bands.py`.
#[rustfmt::skip]
const LIGHT: [f32; CELLS] = [
    3.7115293, 3.712585, 3.7136352, 3.7153604, 3.7180843, 3.7225442,
    3.7310605, 3.7447925, 3.766534, 3.7924402, 3.8323083, 3.8698223,
    3.8595855, 3.6839514, 3.2535188, 2.5245838, 0.13042429, 0.10267715,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.8504561, 4.680774, 4.558053, 3.349135,
    2.233744, 1.253932, 0.53109026, 0.11099725, 0.0, 0.0,
    0.0, 0.12175405, 0.43731457, 0.8529874, 1.3576396, 1.937673,
    2.5746467, 3.246245, 0.27213868, 0.38188666, 0.4888898, 0.58754545,
    0.6724565, 0.74232566, 0.79449123, 0.8297125, 0.8496012, 0.85654986,
    0.85445917, 0.84751457, 0.8373619, 0.82530034, 0.8127787, 0.80118805,
    0.7909406, 0.782239, 0.77534556, 0.7703361, 0.766709, 0.76378894,
    0.7615891, 0.76007766, 0.7590714, 0.7583537, 0.7578387, 0.7574668,
    0.75719935, 0.7570103, 0.7568752, 0.75677794, 0.75670934, 0.75666183,
    0.75662977, 0.756608, 0.75659275, 0.75658196, 0.75657433, 0.7565689,
    0.7565651, 0.7565624, 0.7565605, 0.75655913, 0.7565582, 0.7565575,
    0.75655705, 0.7565567, 0.75655645, 0.7565563, 0.75655603,
];

/// Cell `i`'s edges, in nm.
fn cell(i: usize) -> (f32, f32) {
    let edge = |j: usize| match j {
        0 => LAMBDA_MIN,
        CELLS => LAMBDA_MAX,
        j => 357.5 + 5.0 * j as f32,
    };
    (edge(i), edge(i + 1))
}

/// The channel (0 red, 1 green, 2 blue) whose band holds cell `i`.
fn band(i: usize) -> usize {
    let lo = cell(i).0;
    if (437.5..447.5).contains(&lo) || lo >= 577.5 {
        0
    } else if (497.5..577.5).contains(&lo) {
        1
    } else {
        2
    }
}

/// Luminance (CIE Y) of a linear sRGB colour: what pbrt-v4 divides a light's spectrum by
/// (`SpectrumToPhotometric`), so its `scale` must be this to keep the light's colour.
pub fn luminance(rgb: Vec3) -> f32 {
    rgb.dot(Vec3::new(0.212_672_9, 0.715_152_2, 0.072_175))
}

/// A reflectance (or any colour multiplied along a path: a conductor's `eta` and `k`) as
/// a band spectrum.
pub fn reflectance(rgb: Vec3) -> Vec<(f32, f32)> {
    points(|i| rgb[band(i)])
}

/// A radiance as a band spectrum that Mitsuba 3 renders as `rgb`; pbrt-v4 needs
/// [`luminance`] as its scale besides.
pub fn illuminant(rgb: Vec3) -> Vec<(f32, f32)> {
    points(|i| rgb[band(i)] * LIGHT[i])
}

/// Points of the piecewise constant function with `value(i)` in cell `i`, a step at each
/// edge where the value changes.
fn points(value: impl Fn(usize) -> f32) -> Vec<(f32, f32)> {
    let mut out = vec![(LAMBDA_MIN, value(0))];
    for i in 1..CELLS {
        let (prev, next) = (value(i - 1), value(i));
        if prev != next {
            let edge = cell(i).0;
            out.push((edge - STEP, prev));
            out.push((edge, next));
        }
    }
    out.push((LAMBDA_MAX, value(CELLS - 1)));
    out
}

/// The colour a band spectrum written by [`reflectance`] holds, or `None` when `points`
/// is not one (another spectrum: a spectral renderer's own colour, which we do not read).
pub fn read_reflectance(points: &[(f32, f32)]) -> Option<Vec3> {
    read(points, |_| 1.0)
}

/// The radiance a band spectrum written by [`illuminant`] holds, as Mitsuba 3 renders it;
/// `None` when `points` is not one.
pub fn read_illuminant(points: &[(f32, f32)]) -> Option<Vec3> {
    read(points, |i| LIGHT[i])
}

/// Reads `points` at each cell's centre as `rgb[band] * shape(cell)`: the colour, when
/// every cell agrees with it.
fn read(points: &[(f32, f32)], shape: impl Fn(usize) -> f32) -> Option<Vec3> {
    let ordered = points.windows(2).all(|w| w[0].0 < w[1].0);
    let covers = points.first()?.0 <= LAMBDA_MIN && points.last()?.0 >= LAMBDA_MAX;
    // Colours and radiances are never negative.
    if !ordered || !covers || points.iter().any(|p| !(p.1.is_finite() && p.1 >= 0.0)) {
        return None;
    }
    let at = |lambda: f32| {
        let j = points
            .partition_point(|p| p.0 <= lambda)
            .clamp(1, points.len() - 1);
        let ((l0, v0), (l1, v1)) = (points[j - 1], points[j]);
        v0 + (v1 - v0) * ((lambda - l0) / (l1 - l0)).clamp(0.0, 1.0)
    };
    // Each band's colour from its cell of largest shape (the best conditioned), then the
    // value within two ulps of it that reproduces every cell of the band as written (a
    // quotient alone is an ulp off one time in four; what is written is exact).
    let mut rgb = Vec3::ZERO;
    for k in 0..3 {
        let cells: Vec<usize> = (0..CELLS).filter(|&i| band(i) == k).collect();
        let i = *cells
            .iter()
            .max_by(|&&a, &&b| shape(a).total_cmp(&shape(b)))?;
        let (lo, hi) = cell(i);
        let q = at(0.5 * (lo + hi)) / shape(i);
        let reproduces = |c: f32| {
            cells.iter().all(|&j| {
                let (lo, hi) = cell(j);
                c * shape(j) == at(0.5 * (lo + hi))
            })
        };
        rgb[k] = [
            q,
            q.next_up(),
            q.next_down(),
            q.next_up().next_up(),
            q.next_down().next_down(),
        ]
        .into_iter()
        .find(|&c| reproduces(c))
        .unwrap_or(q);
    }
    let agrees = (0..CELLS).all(|i| {
        let (lo, hi) = cell(i);
        let expected = rgb[band(i)] * shape(i);
        (at(0.5 * (lo + hi)) - expected).abs() <= 1e-4 * expected.abs().max(1e-3)
    });
    agrees.then_some(rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_read_back_as_written() {
        for rgb in [
            Vec3::new(0.63, 0.065, 0.05),
            Vec3::new(17.0, 12.0, 4.0),
            Vec3::ZERO,
            Vec3::new(0.0, 1.0, 0.0),
        ] {
            let r = read_reflectance(&reflectance(rgb)).unwrap();
            let l = read_illuminant(&illuminant(rgb)).unwrap();
            assert!((r - rgb).abs().max_element() <= 1e-6 * rgb.max_element().max(1.0));
            assert!((l - rgb).abs().max_element() <= 1e-4 * rgb.max_element().max(1.0));
        }
    }

    /// Radiances come back bit for bit through the decimal text a file holds, so that a
    /// scene exported and read again is the same scene.
    #[test]
    fn radiances_read_back_bit_for_bit() {
        let mut state = 12345u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..2000 {
            let rgb = Vec3::new(uniform(), uniform(), uniform()) * 50.0;
            let text: Vec<(f32, f32)> = illuminant(rgb)
                .iter()
                .map(|(l, v)| {
                    (
                        l.to_string().parse().unwrap(),
                        v.to_string().parse().unwrap(),
                    )
                })
                .collect();
            assert_eq!(read_illuminant(&text), Some(rgb));
        }
    }

    #[test]
    fn other_spectra_are_not_read_as_colours() {
        let smooth = [(360.0, 0.2), (600.0, 0.5), (830.0, 0.7)];
        assert_eq!(read_reflectance(&smooth), None);
        // A reflectance is not a light, nor short of the visible range.
        let rgb = Vec3::new(0.63, 0.065, 0.05);
        assert_eq!(read_illuminant(&reflectance(rgb)), None);
        assert_eq!(read_reflectance(&reflectance(rgb)[1..]), None);
        let negative: Vec<_> = illuminant(rgb).iter().map(|&(l, v)| (l, -v)).collect();
        assert_eq!(read_illuminant(&negative), None);
    }
}
