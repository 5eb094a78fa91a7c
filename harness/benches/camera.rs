//! What a camera step costs in local mode: small orbit steps in a row, each with the
//! iteration after it, against an ordinary iteration, side by side in one run.
//!
//! `cargo bench -p harness --bench camera` warms each scene up for `PPM_BENCH_WARMUP`
//! iterations (default 30) at `PPM_BENCH_SIZE` (default 256), then turns its camera about
//! its look-at point's vertical by `PPM_BENCH_DEGREES` (default 0.5), `PPM_BENCH_STEPS`
//! times (default 20), an iteration after each. It prints milliseconds per ordinary
//! iteration (the warm-up's last ten), per camera step (the move's passes and the iteration
//! after it; mean and largest) and per move alone, the step's cost in ordinary iterations,
//! and the share of slots the steps kept. Figures only, no threshold: machines are noisy,
//! compare rows of one run. `PPM_BENCH_BACKENDS` (default `cpu,wgpu`) and `PPM_BENCH_SCENES`
//! (default `cornell-box`) choose the rows.

mod common;

use backend_cpu::CpuBackend;
use common::{backends, setting, wgpu_if_wanted};
use harness::driver::Renderer;
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::{Camera, Scene};
use std::time::Instant;

fn main() {
    let warmup: u32 = setting("PPM_BENCH_WARMUP", 30);
    let steps: u32 = setting("PPM_BENCH_STEPS", 20);
    let size: u32 = setting("PPM_BENCH_SIZE", 256);
    let degrees: f32 = setting("PPM_BENCH_DEGREES", 0.5);
    let backends = backends();
    let scenes = std::env::var("PPM_BENCH_SCENES").unwrap_or_else(|_| "cornell-box".into());
    let mut gpu = wgpu_if_wanted(&backends);
    println!(
        "local mode, {size}x{size}, {warmup} iterations of warm-up, then {steps} camera steps \
         of {degrees} degrees of orbit, one iteration after each"
    );
    println!(
        "{:<12} {:<5} {:>12} {:>8} {:>8} {:>8} {:>10} {:>6}",
        "scene", "back", "ms/iteration", "ms/step", "largest", "ms/move", "step/iter", "kept"
    );
    for name in scenes.split(',') {
        let Some(scene) = scenes::builtin(name.trim()).and_then(|s| s.load().ok()) else {
            println!("{name}: no such built-in scene");
            continue;
        };
        let mut p = RenderParams::for_scene(&scene);
        (p.width, p.height) = (size, size);
        let row = |backend: &mut dyn Backend| {
            let s = orbit(backend, &scene, &p, (warmup, steps, degrees));
            println!(
                "{:<12} {:<5} {:>12.2} {:>8.2} {:>8.2} {:>8.2} {:>10.2} {:>5.0}%",
                name.trim(),
                backend.name(),
                s.iteration_ms,
                s.step_ms,
                s.largest_ms,
                s.move_ms,
                s.step_ms / s.iteration_ms,
                s.kept * 100.0
            );
        };
        if backends.contains("cpu") {
            row(&mut CpuBackend::new());
        }
        if let Some(gpu) = gpu.as_mut() {
            row(gpu);
        }
    }
}

/// What the camera steps of one row cost.
struct Steps {
    /// Milliseconds per ordinary iteration (the warm-up's last ten).
    iteration_ms: f64,
    /// Milliseconds per step, its iteration included: mean and largest.
    step_ms: f64,
    largest_ms: f64,
    /// Milliseconds per move alone (its passes, without the iteration after).
    move_ms: f64,
    /// The share of slots the steps kept.
    kept: f64,
}

/// Warms `scene` up on `backend`, then orbits its camera in `steps` steps of `degrees`.
fn orbit(
    backend: &mut dyn Backend,
    scene: &Scene,
    p: &RenderParams,
    (warmup, steps, degrees): (u32, u32, f32),
) -> Steps {
    let mut r = Renderer::start(backend, scene.clone(), p, &MoveParams::default())
        .expect("the scene loads");
    r.expect_local_moves().expect("the moves are prepared");
    let mut warm = Vec::new();
    for _ in 0..warmup {
        let t = Instant::now();
        r.iteration().expect("an iteration runs");
        warm.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let mut camera: Camera = scene.camera.clone();
    let (mut step_ms, mut move_ms, mut kept, mut slots) = (Vec::new(), Vec::new(), 0, 0);
    for _ in 0..steps {
        camera = camera.orbited(degrees, 0.0);
        let t = Instant::now();
        let report = r
            .move_camera(camera.clone(), MoveMode::Local)
            .expect("a camera move runs");
        let moved = t.elapsed().as_secs_f64() * 1e3;
        r.iteration().expect("an iteration runs");
        step_ms.push(t.elapsed().as_secs_f64() * 1e3);
        move_ms.push(moved);
        if let Some(why) = report.restarted {
            println!("{}: the step started over: {why}", r.backend().name());
        }
        (kept, slots) = (kept + report.kept, slots + report.kept + report.updated);
    }
    Steps {
        iteration_ms: mean(&warm[warm.len().saturating_sub(10)..]),
        step_ms: mean(&step_ms),
        largest_ms: step_ms.iter().copied().fold(0.0, f64::max),
        move_ms: mean(&move_ms),
        kept: kept as f64 / slots.max(1) as f64,
    }
}

fn mean(ms: &[f64]) -> f64 {
    ms.iter().sum::<f64>() / ms.len().max(1) as f64
}
