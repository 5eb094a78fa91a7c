//! Helpers shared by the workspace-level integration tests in `tests/tests/`.

use backend_cpu::CpuBackend;
use harness::render::{RenderOutcome, render};
use ppm_core::params::RenderParams;
use ppm_core::scene::Scene;

/// Renders `scene` at `frame` on the CPU backend in a pool of `threads` workers; panics on a
/// pass error, since a test render must not fail.
pub fn render_cpu(
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
    threads: usize,
) -> (RenderOutcome, CpuBackend) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut backend = CpuBackend::new();
    let outcome = pool
        .install(|| render(&mut backend, scene, frame, params, &mut |_, _| {}))
        .expect("render");
    if let Some(e) = &outcome.error {
        panic!("pass failed: {e}");
    }
    (outcome, backend)
}

/// Luminance (Rec. 709 weights) of a linear RGB value.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
