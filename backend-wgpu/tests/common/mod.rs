//! The eye and photon passes several device tests run, on whatever scene the backend holds.

use backend_wgpu::WgpuBackend;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{EyePassParams, PhotonPassParams};
use ppm_core::passes::{EyePass, PhotonPass};

/// One eye pass of one sample a pixel, its visible points starting at squared radius
/// `r2_initial`.
pub fn eye_pass(backend: &mut WgpuBackend, r2_initial: f32) {
    let eye = EyePassParams {
        spp: 1,
        max_depth: 4,
        r2_initial,
        ray_epsilon: 1e-3,
        ..Default::default()
    };
    backend.eye_pass(&eye).unwrap();
}

/// One photon pass of 20,000 photons from the lights.
pub fn photon_pass(backend: &mut WgpuBackend) {
    let photons = PhotonPassParams {
        photon_count: 20_000,
        max_depth: 8,
        ray_epsilon: 1e-3,
        power_scale: 1.0,
        ..Default::default()
    };
    backend
        .photon_pass(&photons, &PhotonSource::Lights)
        .unwrap();
}
