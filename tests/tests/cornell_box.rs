//! `ppm render cornell-box` must give a recognisable Cornell box: red wall on the left, green on
//! the right, colour bleeding onto the white surfaces, and soft shadows from the area light.

use ppm_core::image::Image;
use ppm_core::params::{Estimator, RenderParams};
use tests::{luminance, render_cpu};

const SIZE: u32 = 96;

fn cornell(estimator: Estimator, passes: u32, direct_samples: u32) -> Image {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.estimator = estimator;
    params.width = SIZE;
    params.height = SIZE;
    params.passes = passes;
    params.photons_per_pass = 100_000;
    params.direct_samples = direct_samples;
    render_cpu(&scene, 0, &params, 2).0.image
}

/// Mean colour of the block of pixels at fractions `x0..x1`, `y0..y1` of the image.
fn region(image: &Image, x0: f32, x1: f32, y0: f32, y1: f32) -> [f64; 3] {
    let at = |f: f32| (f * SIZE as f32) as u32;
    image.mean_in(at(x0), at(x1), at(y0), at(y1))
}

#[test]
fn red_wall_left_green_wall_right_and_colour_bleeds_onto_the_ceiling() {
    let image = cornell(Estimator::Sppm, 8, 16);
    assert!(image.is_finite());
    let left = region(&image, 0.04, 0.12, 0.35, 0.65);
    let right = region(&image, 0.88, 0.96, 0.35, 0.65);
    assert!(
        left[0] > 3.0 * left[1] && left[0] > 3.0 * left[2],
        "left wall not red: {left:?}"
    );
    assert!(
        right[1] > 1.5 * right[0] && right[1] > 1.5 * right[2],
        "right wall not green: {right:?}"
    );
    // The ceiling sees no direct light (the light faces down): everything on it came by
    // photons from the walls, so its corner by the red wall is redder than by the green one.
    let ceiling_left = region(&image, 0.12, 0.25, 0.03, 0.09);
    let ceiling_right = region(&image, 0.75, 0.88, 0.03, 0.09);
    assert!(
        ceiling_left.iter().all(|&c| c > 0.0),
        "ceiling black: {ceiling_left:?}"
    );
    println!(
        "walls {left:?} {right:?}; ceiling by red {ceiling_left:?}, by green {ceiling_right:?}"
    );
    let red_ratio = |c: [f64; 3]| c[0] / c[1];
    assert!(
        red_ratio(ceiling_left) > 1.2 * red_ratio(ceiling_right),
        "no red bleeding: left {ceiling_left:?}, right {ceiling_right:?}"
    );
    let green_ratio = |c: [f64; 3]| c[1] / c[0];
    assert!(
        green_ratio(ceiling_right) > 1.2 * green_ratio(ceiling_left),
        "no green bleeding: left {ceiling_left:?}, right {ceiling_right:?}"
    );
}

/// The short block's shadow on the floor in front of it has a penumbra many pixels wide: the
/// light is a 130 x 105 mm area, not a point, so the floor row between the lit and the shadowed
/// part passes through intermediate values instead of jumping. Direct light alone: `ppm`'s hit
/// points at the pixel centres with 256 shadow samples each, and no photon pass.
#[test]
fn shadows_are_soft() {
    let image = cornell(Estimator::Ppm, 0, 256);
    let y = (0.97 * SIZE as f32) as u32;
    let row: Vec<f32> = (0..SIZE).map(|x| luminance(image.at(x, y))).collect();
    let lit = row.iter().copied().fold(0.0f32, f32::max);
    let dark = row[(SIZE / 5) as usize..(4 * SIZE / 5) as usize]
        .iter()
        .copied()
        .fold(f32::MAX, f32::min);
    assert!(dark < 0.3 * lit, "no shadow on the floor row: {row:?}");
    let penumbra = row
        .iter()
        .filter(|&&l| l > dark + 0.2 * (lit - dark) && l < dark + 0.8 * (lit - dark))
        .count();
    println!("floor row: lit {lit}, dark {dark}, {penumbra} penumbra pixels");
    assert!(
        penumbra >= 4,
        "shadow edge is hard ({penumbra} pixels between): {row:?}"
    );
}
