//! Helpers shared by the workspace-level integration tests in `tests/tests/`.

#![warn(missing_docs)]

use backend_cpu::CpuBackend;
use harness::driver::{Budget, Outcome, Schedule, run};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::DynamicBackend;
use ppm_core::scene::Scene;

/// Renders `scene` at `frame` for `params.passes` iterations on the CPU backend in a pool of
/// `threads` workers; panics on a pass error, since a test render must not fail.
pub fn render_cpu(
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
    threads: usize,
) -> (Outcome, CpuBackend) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut backend = CpuBackend::new();
    let outcome = pool.install(|| render_on(&mut backend, scene, frame, params));
    (outcome, backend)
}

/// Renders `scene` at `frame` for `params.passes` iterations on `backend`; panics on a pass
/// error, since a test render must not fail.
pub fn render_on(
    backend: &mut dyn DynamicBackend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
) -> Outcome {
    let schedule = Schedule::frame(frame, Budget::iterations(params.passes));
    let outcome = run(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        &mut (),
    )
    .expect("render");
    if let Some(e) = &outcome.error {
        panic!("pass failed: {e}");
    }
    outcome
}

/// Luminance (Rec. 709 weights) of a linear RGB value.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
