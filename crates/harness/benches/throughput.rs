//! Throughput of each backend on `cornell-box`: photons and rays per second (photons/s and
//! photon rays/s over the photon pass's time), and time per photon and gather pass.
//!
//! `cargo bench -p harness --bench throughput` prints one row per backend and resolution,
//! measured side by side in one run. Figures only: no threshold is asserted, since shared
//! machines are noisy; compare rows of one run. The wgpu rows use whatever adapter wgpu finds
//! (lavapipe on a machine without a GPU) and are left out, with a note, when there is none.

use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use harness::driver::{Budget, Schedule, run};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::DynamicBackend;

fn main() {
    let scene = scenes::builtin("cornell-box")
        .and_then(|s| s.load().ok())
        .expect("cornell-box loads");
    let threads = rayon::current_num_threads();
    let mut gpu = match WgpuBackend::new() {
        Ok(b) => Some(b),
        Err(e) => {
            println!("no wgpu rows: {e}");
            None
        }
    };
    println!("cornell-box, 8 passes x 200,000 photons; cpu on {threads} threads");
    if let Some(g) = &gpu {
        println!("wgpu adapter: {}", g.adapter_name());
    }
    println!(
        "(wgpu accumulates each photon batch into the hit points inside its photon pass, so its"
    );
    println!(
        " gather column is only the update: compare the photon+gather column across backends)"
    );
    println!(
        "{:<5} {:>9} {:>12} {:>14} {:>12} {:>14} {:>10} {:>10} {:>15}",
        "back",
        "size",
        "photons/s",
        "photon rays/s",
        "eye rays/s",
        "shadow rays/s",
        "photon ms",
        "gather ms",
        "photon+gather ms"
    );
    for size in [256, 768] {
        let mut params = RenderParams::for_scene(&scene);
        params.width = size;
        params.height = size;
        params.passes = 8;
        params.photons_per_pass = 200_000;
        let mut cpu = CpuBackend::new();
        let mut backends: Vec<&mut dyn DynamicBackend> = vec![&mut cpu];
        if let Some(g) = gpu.as_mut() {
            backends.push(g);
        }
        for backend in backends {
            let schedule = Schedule::frame(0, Budget::iterations(params.passes));
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
            let passes = f64::from(r.passes);
            println!(
                "{:<5} {:>9} {:>12.0} {:>14.0} {:>12.0} {:>14.0} {:>10.1} {:>10.1} {:>15.1}",
                r.backend,
                format!("{size}x{size}"),
                r.photons_emitted as f64 / t.photon,
                r.rays.photon as f64 / t.photon,
                r.rays.eye as f64 / t.eye,
                r.rays.shadow as f64 / t.direct,
                1e3 * t.photon / passes,
                1e3 * t.gather / passes,
                1e3 * (t.photon + t.gather) / passes,
            );
        }
    }
}
