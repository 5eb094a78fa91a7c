//! The furnace (scenes::analytic::furnace): a closed box whose walls all emit `Le` and reflect
//! with albedo `rho`. Its radiance is `Le / (1 - rho)` everywhere (derivation in
//! `furnace`'s doc comment), so PPM must converge to that value, with error falling as passes
//! accumulate, whichever way direct light is computed.

use glam::Vec3;
use ppm_core::image::Image;
use ppm_core::metrics::rmse;
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::scene::MaterialKind;
use scenes::analytic::{furnace, furnace_radiance, specular_furnace};
use tests::render_cpu;

fn params(scene: &ppm_core::scene::Scene, direct: DirectMode, passes: u32) -> RenderParams {
    let mut p = RenderParams::for_scene(scene);
    p.direct = direct;
    p.passes = passes;
    p.photons_per_pass = 20_000;
    // Shadow rays are drawn once per frame, so their noise does not fall with passes: take
    // enough that the photon estimate's error dominates what the test watches fall.
    p.direct_samples = 256;
    p
}

fn constant(like: &Image, value: Vec3) -> Image {
    Image {
        pixels: vec![value.into(); like.pixels.len()],
        ..like.clone()
    }
}

/// Relative error of the image mean, per channel, and the relative RMSE against the truth.
fn errors(image: &Image, truth: Vec3) -> (Vec3, f64) {
    let mean = image.mean_in(0, image.width, 0, image.height);
    let mean = Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32);
    let rel_rmse = rmse(image, &constant(image, truth)) / f64::from(truth.element_sum() / 3.0);
    (((mean - truth) / truth).abs(), rel_rmse)
}

fn converges(scene: &ppm_core::scene::Scene, albedo: Vec3, direct: DirectMode) {
    let truth = furnace_radiance(albedo, 1.0);
    let mut last_rmse = f64::INFINITY;
    for passes in [2, 8, 32] {
        let (outcome, _) = render_cpu(scene, 0, &params(scene, direct, passes), 2);
        let (mean_err, rel_rmse) = errors(&outcome.image, truth);
        println!(
            "{} {direct:?} passes {passes}: mean error {mean_err}, relative RMSE {rel_rmse:.4}",
            scene.name
        );
        assert!(
            rel_rmse < last_rmse,
            "error did not fall: {rel_rmse} after {last_rmse}"
        );
        last_rmse = rel_rmse;
        if passes == 32 {
            // 640,000 photons over 24 unit-area walls: the image mean averages 1,024 pixels,
            // so 2% is several standard errors; the per-pixel error (2.2% seen) is allowed 5%.
            assert!(mean_err.max_element() < 0.02, "mean off by {mean_err}");
            assert!(rel_rmse < 0.05, "relative RMSE {rel_rmse}");
        }
    }
}

#[test]
fn furnace_converges_to_le_over_one_minus_albedo_with_explicit_direct_light() {
    let albedo = Vec3::new(0.5, 0.3, 0.7);
    converges(&furnace(albedo, 1.0), albedo, DirectMode::Explicit);
}

#[test]
fn furnace_converges_to_le_over_one_minus_albedo_when_photons_carry_direct_light() {
    let albedo = Vec3::new(0.5, 0.3, 0.7);
    converges(&furnace(albedo, 1.0), albedo, DirectMode::Photons);
}

/// Seen in a lossless mirror and through a glass cube, the furnace keeps its radiance: this
/// fails if specular eye chains, Fresnel choices or caustic photons lose or gain energy.
#[test]
fn specular_furnace_keeps_its_radiance_through_mirror_and_glass() {
    let albedo = Vec3::splat(0.5);
    converges(&specular_furnace(albedo, 1.0), albedo, DirectMode::Explicit);
}

/// The specular furnace with `kind` in place of its mirror.
fn with_mirror_as(kind: MaterialKind) -> ppm_core::scene::Scene {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    let mirror = scene
        .materials
        .iter_mut()
        .find(|m| matches!(m.kind, MaterialKind::Mirror { .. }))
        .expect("the specular furnace has a mirror");
    mirror.kind = kind;
    scene
}

/// A smooth lossless conductor (`eta = 0`, `k = 1`: Fresnel factor one at every angle) in
/// place of the mirror keeps the radiance too: this fails if the conductor's delta lobe or
/// its Fresnel term lose or gain energy.
#[test]
fn a_lossless_smooth_conductor_keeps_the_furnace_radiance() {
    let scene = with_mirror_as(MaterialKind::Conductor {
        eta: Vec3::ZERO,
        k: Vec3::ONE,
        reflectance: Vec3::ONE,
        alpha: 0.0,
        alpha_v: 0.0,
    });
    converges(&scene, Vec3::splat(0.5), DirectMode::Explicit);
}

/// A white base under a smooth coat, its light meeting the base at every return, in place of
/// the mirror: the coat's reflection and what the base sends back out add to one, so the
/// furnace keeps its radiance. This fails if the coat's transmittance is left out of the
/// eye paths that stop at the base, of the photons stored there or of the direct light, or
/// if the returns under the coat are miscounted.
#[test]
fn a_white_base_under_a_smooth_coat_keeps_the_furnace_radiance() {
    let scene = with_mirror_as(MaterialKind::Coated {
        albedo: Vec3::ONE,
        ior: 1.5,
        alpha: 0.0,
        nonlinear: true,
    });
    converges(&scene, Vec3::splat(0.5), DirectMode::Explicit);
}
