//! Throughput of each backend on `cornell-box`, whole iterations: eye pass, direct light, photon
//! pass and gather, at 256x256 and 768x768, side by side in one run.
//!
//! `cargo bench -p harness --bench throughput` prints one row per backend and resolution: the
//! headline is photons per second over the whole iteration (so eye, direct light and gather
//! count against it), then milliseconds per iteration and per pass kind, and rays per second
//! of each kind. Figures only: no threshold is asserted, since shared machines are noisy;
//! compare rows of one run. The wgpu rows use whatever adapter wgpu finds (lavapipe on a
//! machine without a GPU) and are left out, with a note, when there is none. Set
//! `PPM_BENCH_ITERATIONS` and `PPM_BENCH_PHOTONS` to change the workload (default 16 x
//! 200,000), `PPM_BENCH_RADIUS` (default: the scene's), `PPM_BENCH_SIZES` (default
//! `256,768`), and `PPM_BENCH_BACKENDS` (default `cpu,wgpu`).

mod common;

use backend_cpu::CpuBackend;
use common::{backends, setting, wgpu_if_wanted};
use harness::driver::{Budget, Schedule, run};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::Backend;

fn main() {
    let scene = scenes::builtin("cornell-box")
        .and_then(|s| s.load().ok())
        .expect("cornell-box loads");
    let iterations: u32 = setting("PPM_BENCH_ITERATIONS", 16);
    let photons: u32 = setting("PPM_BENCH_PHOTONS", 200_000);
    let sizes: Vec<u32> = std::env::var("PPM_BENCH_SIZES")
        .unwrap_or_else(|_| "256,768".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let backends = backends();
    let threads = rayon::current_num_threads();
    let mut gpu = wgpu_if_wanted(&backends);
    let radius: f32 = setting("PPM_BENCH_RADIUS", scene.render.initial_radius);
    println!(
        "cornell-box, sppm, {iterations} iterations x {photons} photons from scratch, initial radius {radius}; cpu on {threads} threads"
    );
    if let Some(g) = &gpu {
        println!("wgpu adapter: {}", g.adapter_name());
    }
    println!(
        "{:<5} {:>9} {:>12} {:>8} {:>7} {:>7} {:>7} {:>7} {:>12} {:>12} {:>12}",
        "back",
        "size",
        "photons/s",
        "iter ms",
        "eye",
        "direct",
        "photon",
        "gather",
        "eye rays/s",
        "shadow/s",
        "photon/s"
    );
    for size in sizes {
        let mut params = RenderParams::for_scene(&scene);
        params.width = size;
        params.height = size;
        params.passes = iterations;
        params.photons_per_pass = photons;
        params.initial_radius = radius;
        let mut cpu = CpuBackend::new();
        let mut rows: Vec<&mut dyn Backend> = Vec::new();
        if backends.contains("cpu") {
            rows.push(&mut cpu);
        }
        if let Some(g) = gpu.as_mut() {
            rows.push(g);
        }
        for backend in rows {
            let schedule = Schedule::frame(0, Budget::iterations(iterations));
            let outcome = run(
                backend,
                &scene,
                &params,
                &MoveParams::default(),
                &schedule,
                &mut (),
            )
            .expect("render");
            let r = &outcome.report;
            let t = &r.times;
            let n = f64::from(r.passes);
            let iteration = t.eye + t.direct + t.photon + t.gather;
            let ms = |s: f64| 1e3 * s / n;
            println!(
                "{:<5} {:>9} {:>12.0} {:>8.1} {:>7.1} {:>7.1} {:>7.1} {:>7.1} {:>12.3e} {:>12.3e} {:>12.3e}",
                r.backend,
                format!("{size}x{size}"),
                r.photons_emitted as f64 / iteration,
                ms(iteration),
                ms(t.eye),
                ms(t.direct),
                ms(t.photon),
                ms(t.gather),
                r.rays.eye as f64 / t.eye,
                r.rays.shadow as f64 / t.direct,
                r.rays.photon as f64 / t.photon,
            );
        }
    }
}
