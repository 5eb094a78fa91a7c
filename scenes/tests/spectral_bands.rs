//! The band spectra `ppm export` writes for spectral renderers come back as our RGB colours
//! under the CIE 1931 observer, as Mitsuba 3 and pbrt-v4 integrate it, products included.

use glam::{DVec3, Vec3};
use scenes::file::bands;

/// XYZ to linear sRGB (D65), as both renderers convert.
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.240479, -1.537150, -0.498535],
    [-0.969256, 1.875991, 0.041556],
    [0.055648, -0.204043, 1.057311],
];

/// The CIE 1931 2-degree observer at every whole nanometre from 360 to 830.
fn observer() -> Vec<(f64, DVec3)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/cie1931.csv");
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            (v[0], DVec3::new(v[1], v[2], v[3]))
        })
        .collect()
}

/// A piecewise linear spectrum at `lambda`.
fn eval(points: &[(f32, f32)], lambda: f64) -> f64 {
    let j = points
        .partition_point(|p| f64::from(p.0) <= lambda)
        .clamp(1, points.len() - 1);
    let ((l0, v0), (l1, v1)) = (points[j - 1], points[j]);
    let t = ((lambda - f64::from(l0)) / f64::from(l1 - l0)).clamp(0.0, 1.0);
    f64::from(v0) + (f64::from(v1) - f64::from(v0)) * t
}

fn to_srgb(xyz: DVec3) -> DVec3 {
    let m = XYZ_TO_SRGB;
    DVec3::new(
        m[0][0] * xyz.x + m[0][1] * xyz.y + m[0][2] * xyz.z,
        m[1][0] * xyz.x + m[1][1] * xyz.y + m[1][2] * xyz.z,
        m[2][0] * xyz.x + m[2][1] * xyz.y + m[2][2] * xyz.z,
    )
}

/// What Mitsuba 3 divides XYZ by (1 / `MI_CIE_Y_NORMALIZATION`): a flat spectrum of 1 has
/// Y = 1.001 there.
const MITSUBA_Y_INTEGRAL: f64 = 106.750_259_399_414_06;

/// XYZ of a light seen after bounces off `reflectances`: the observer interpolated between
/// whole nanometres, integrated in 0.1-nm steps, the light read at the wavelength
/// `light_at` gives for each.
fn xyz(light: Vec3, reflectances: &[Vec3], light_at: fn(f64) -> f64) -> DVec3 {
    let cie = observer();
    let emitted = bands::illuminant(light);
    let reflected: Vec<_> = reflectances
        .iter()
        .map(|&r| bands::reflectance(r))
        .collect();
    let mut xyz = DVec3::ZERO;
    for step in 0..4700 {
        let lambda = 360.05 + 0.1 * f64::from(step);
        let i = (lambda - 360.0) as usize;
        let t = lambda - cie[i].0;
        let cmf = cie[i].1 * (1.0 - t) + cie[i + 1].1 * t;
        let s = eval(&emitted, light_at(lambda))
            * reflected.iter().map(|r| eval(r, lambda)).product::<f64>();
        xyz += cmf * s * 0.1;
    }
    xyz
}

/// The colour as Mitsuba 3 develops it: over [`MITSUBA_Y_INTEGRAL`].
fn mitsuba_colour(light: Vec3, reflectances: &[Vec3]) -> DVec3 {
    to_srgb(xyz(light, reflectances, |lambda| lambda) / MITSUBA_Y_INTEGRAL)
}

/// The colour as pbrt-v4 develops it: the light read at the nearest whole nanometre and
/// divided by its luminance (a sum over whole nanometres) times its `scale`, the sensor
/// giving the light's own luminance 1.
fn pbrt_colour(light: Vec3, reflectances: &[Vec3]) -> DVec3 {
    let emitted = bands::illuminant(light);
    let luminance: f64 = observer()
        .iter()
        .map(|(l, c)| c.y * eval(&emitted, *l))
        .sum();
    let scale = f64::from(bands::luminance(light)) / luminance;
    to_srgb(xyz(light, reflectances, f64::round) * scale)
}

/// The colours of the Cornell box, its light, and the products of up to three bounces.
#[test]
fn band_spectra_multiply_like_rgb() {
    let light = Vec3::new(17.0, 12.0, 4.0);
    let (red, green, white) = (
        Vec3::new(0.63, 0.065, 0.05),
        Vec3::new(0.14, 0.45, 0.091),
        Vec3::new(0.725, 0.71, 0.68),
    );
    for path in [
        vec![],
        vec![red],
        vec![green],
        vec![red, white],
        vec![green, red, white],
    ] {
        let expected = path.iter().fold(light, |c, r| c * *r).as_dvec3();
        for (renderer, got) in [
            ("Mitsuba 3", mitsuba_colour(light, &path)),
            ("pbrt-v4", pbrt_colour(light, &path)),
        ] {
            let error = ((got - expected) / expected).abs().max_element();
            // pbrt's whole-nanometre sums differ from the integral by about 1e-4.
            assert!(
                error < 1e-3,
                "{renderer}, light {light} off {path:?}: {got} against {expected}"
            );
        }
    }
}
