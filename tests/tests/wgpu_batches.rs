//! A photon pass too large for one buffer is split into batches on the wgpu backend, and the
//! split does not change the result: the gather still makes one update per pass from all of
//! the pass's photons, so hit points agree with the unsplit run (and with the CPU) up to the
//! rounding of summing batch by batch.

use harness::diff::{record, same_seed};
use ppm_core::params::RenderParams;
use std::process::ExitCode;
use tests::{Suite, figure};

fn a_photon_pass_split_into_batches_matches_the_unsplit_pass() {
    let mut whole = backend_wgpu::WgpuBackend::new().unwrap();
    let mut split = backend_wgpu::WgpuBackend::new().unwrap();
    // 64 KiB holds 2,048 deposits: a pass of 20,000 photons takes about ten batches.
    split.set_photon_buffer_limit(64 * 1024);
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    p.width = 40;
    p.height = 40;
    p.passes = 3;
    p.photons_per_pass = 20_000;
    let a = record(&mut whole, &scene, 0, &p).unwrap();
    let b = record(&mut split, &scene, 0, &p).unwrap();
    assert_eq!(whole.last_pass_batches(), 1);
    assert!(
        split.last_pass_batches() >= 8,
        "only {} batches",
        split.last_pass_batches()
    );
    let report = same_seed::compare(&a, &b, &p, 5);
    figure!("{}", harness::diff::same_seed::format(&report));
    assert!(report.agree);
    let n = report.fields.iter().find(|f| f.field == "n").unwrap();
    assert_eq!(
        n.share, 1.0,
        "batches must find exactly the photons of the whole pass"
    );
    let cpu = record(&mut backend_cpu::CpuBackend::new(), &scene, 0, &p).unwrap();
    assert!(same_seed::compare(&cpu, &b, &p, 5).agree);
}

fn main() -> ExitCode {
    Suite::new()
        .test_needing(
            &[tests::wgpu()],
            "a_photon_pass_split_into_batches_matches_the_unsplit_pass",
            a_photon_pass_split_into_batches_matches_the_unsplit_pass,
        )
        .run()
}
