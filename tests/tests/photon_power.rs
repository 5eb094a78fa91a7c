//! Power bookkeeping of the photon pass: what photons deposit must equal what the lights emit
//! times the albedo series. In the closed furnace every photon meets a wall, and Russian roulette
//! with survival `q = max(rho)` scales power by `rho / q`, so the expected power deposited per
//! emitted photon is `Phi * rho^k` at the k-th surface: `Phi / (1 - rho)` in all when the first
//! surface deposits, `Phi * rho / (1 - rho)` when direct light is explicit (series cut at the
//! depth limit, whose remainder `rho^16` is below 1e-2 here).

use glam::Vec3;
use ppm_core::compile::compile_scene;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{EyePassParams, PhotonPassParams, first_hit};
use ppm_core::passes::{EyePass, PhotonPass, ReadBack, SceneUpload};
use scenes::analytic::furnace;

fn deposited_per_photon(albedo: Vec3, mode: u32, photons: u32) -> (Vec3, Vec3) {
    let scene = furnace(albedo, 1.0);
    let compiled = compile_scene(&scene, 8, 8);
    let mut backend = backend_cpu::CpuBackend::new();
    backend.load_scene(&compiled).unwrap();
    backend
        .eye_pass(&EyePassParams {
            spp: 1,
            max_depth: 4,
            r2_initial: 0.01,
            ray_epsilon: 1e-5,
            ..Default::default()
        })
        .unwrap();
    let stats = backend
        .photon_pass(
            &PhotonPassParams {
                seed: 11,
                photon_count: photons,
                max_depth: 16,
                first_hit: mode,
                ray_epsilon: 1e-5,
                power_scale: 1.0,
                ..Default::default()
            },
            &PhotonSource::Lights,
        )
        .unwrap();
    let deposits = backend.read_photons().unwrap();
    assert_eq!(stats.deposited as usize, deposits.len());
    let total = deposits
        .iter()
        .fold(Vec3::ZERO, |a, p| a + Vec3::from(p.power));
    (total / photons as f32, compiled.light_power)
}

fn check(albedo: Vec3, mode: u32, expected_factor: Vec3) {
    let (per_photon, phi) = deposited_per_photon(albedo, mode, 200_000);
    let expected = phi * expected_factor;
    let rel = ((per_photon - expected) / expected).abs();
    println!("albedo {albedo}: deposited {per_photon}, expected {expected}, relative error {rel}");
    // Deposit counts are geometric: the standard error of the mean is below 0.7% for the
    // reddest channel here (rho 0.8 with q 0.8); 2.5% is over three of them.
    assert!(rel.max_element() < 0.025, "relative error {rel}");
}

#[test]
fn deposited_power_is_emitted_power_times_the_albedo_series() {
    let rho = Vec3::new(0.8, 0.4, 0.2);
    let series = Vec3::ONE / (Vec3::ONE - rho) - rho.powf(16.0) / (Vec3::ONE - rho);
    check(rho, first_hit::DEPOSIT, series);
}

#[test]
fn explicit_direct_light_removes_exactly_the_first_bounce() {
    let rho = Vec3::splat(0.5);
    let series = rho / (Vec3::ONE - rho) - rho.powf(16.0) / (Vec3::ONE - rho);
    check(rho, first_hit::SKIP, series);
}

#[test]
fn emitted_power_is_pi_times_area_times_radiance() {
    let (_, phi) = deposited_per_photon(Vec3::splat(0.5), first_hit::SKIP, 1);
    // Six faces of area 4 emitting Le = 1.
    approx::assert_relative_eq!(phi.x, std::f32::consts::PI * 24.0, max_relative = 1e-5);
}
