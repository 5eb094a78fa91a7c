//! Throughput of the CPU backend on `cornell-box`: photons and rays per second, time per pass.
//!
//! `cargo bench -p harness --bench throughput` prints one row per resolution. Figures only: no
//! threshold is asserted here, since shared machines are noisy; compare rows of one run.

use backend_cpu::CpuBackend;
use harness::render::render;
use ppm_core::params::RenderParams;

fn main() {
    let scene = scenes::builtin("cornell-box")
        .and_then(|s| s.load().ok())
        .expect("cornell-box loads");
    let threads = rayon::current_num_threads();
    println!("cornell-box on the CPU backend, {threads} threads, 8 passes x 200,000 photons");
    println!(
        "{:>9} {:>13} {:>15} {:>13} {:>15} {:>15} {:>15}",
        "size",
        "photons/s",
        "photon rays/s",
        "eye rays/s",
        "shadow rays/s",
        "photon ms/pass",
        "gather ms/pass"
    );
    for size in [256, 768] {
        let mut params = RenderParams::for_scene(&scene);
        params.width = size;
        params.height = size;
        params.passes = 8;
        params.photons_per_pass = 200_000;
        let outcome =
            render(&mut CpuBackend::new(), &scene, 0, &params, &mut |_, _| {}).expect("render");
        let r = &outcome.report;
        let t = &r.times;
        let passes = f64::from(r.passes);
        println!(
            "{:>9} {:>13.0} {:>15.0} {:>13.0} {:>15.0} {:>15.1} {:>15.1}",
            format!("{size}x{size}"),
            r.photons_emitted as f64 / t.photon,
            r.rays.photon as f64 / t.photon,
            r.rays.eye as f64 / t.eye,
            r.rays.shadow as f64 / t.direct,
            1e3 * t.photon / passes,
            1e3 * t.gather / passes,
        );
    }
}
