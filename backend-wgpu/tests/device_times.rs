//! Each kernel's device time, where the adapter offers timestamp queries: every pass of an
//! iteration is measured, in positive and finite seconds, and read once. Without the feature
//! (a device opened with the baseline only) the backend says it measures nothing, never zeros.

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::compile::compile_scene;
use ppm_core::device_time::{DeviceTime, per_pass};
use ppm_core::layout::{DirectLightParams, GatherParams};
use ppm_core::passes::{Backend, DirectLight, GatherPass, SceneUpload};
use std::process::ExitCode;
use test_support::{Need, Suite, figure};

mod common;

/// One iteration on cornell-box at 16x16: eye pass, direct light, a photon pass and its gather.
fn iteration(backend: &mut WgpuBackend) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    backend.load_scene(&compile_scene(&scene, 16, 16)).unwrap();
    common::eye_pass(backend, 1.0);
    let direct = DirectLightParams {
        samples: 1,
        ray_epsilon: 1e-3,
        ..Default::default()
    };
    backend.direct_light(&direct).unwrap();
    common::photon_pass(backend);
    let gather = GatherParams {
        alpha: 0.7,
        emitted_increment: 20_000.0,
        ..Default::default()
    };
    backend.gather_pass(&gather).unwrap();
}

fn every_pass_of_an_iteration_has_positive_finite_device_time() {
    let mut backend = WgpuBackend::new().unwrap();
    assert!(backend.has_device_times());
    iteration(&mut backend);
    let times: Vec<DeviceTime> = backend.device_times().unwrap().expect("timestamps");
    for t in &times {
        figure!(
            "{:<14} {:<28} {:>9.3} ms",
            t.pass,
            t.kernel,
            t.seconds * 1e3
        );
        // A kernel of one workgroup may finish within the clock's tick: zero, not negative.
        assert!(t.seconds.is_finite() && t.seconds >= 0.0, "{t:?}");
        assert!(t.dispatches > 0, "{t:?}");
    }
    let passes = per_pass(&times);
    for pass in [
        "eye",
        "direct light",
        "photon trace",
        "photon map",
        "gather",
    ] {
        let seconds = passes.iter().find(|(p, _)| p == pass).map(|(_, s)| *s);
        assert!(
            seconds.is_some_and(|s| s > 0.0 && s.is_finite()),
            "{pass}: {seconds:?} in {passes:?}"
        );
    }
    // The grid build and its scan are kernels of the photon map, timed on their own.
    for kernel in [
        "grid_count_main",
        "scan_blocks_main",
        "gather_accumulate_main",
    ] {
        assert!(
            times.iter().any(|t| t.kernel == kernel),
            "{kernel} missing from {times:?}"
        );
    }
    let again = backend.device_times().unwrap().expect("timestamps");
    assert!(again.is_empty(), "read twice: {again:?}");
}

fn a_device_without_timestamps_measures_nothing() {
    let mut backend = WgpuBackend::on(GpuContext::baseline().unwrap()).unwrap();
    assert!(!backend.has_device_times());
    iteration(&mut backend);
    assert_eq!(backend.device_times().unwrap(), None);
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    let timestamps = Need::new(
        "an adapter with timestamp queries",
        "PPM_REQUIRE_TIMESTAMPS",
        "a GPU whose driver offers WebGPU's timestamp-query feature",
        || match GpuContext::new() {
            Ok(ctx) if ctx.timestamps() => Ok(()),
            Ok(ctx) => Err(format!("{} offers no timestamp queries", ctx.adapter.name)),
            Err(e) => Err(e.to_string()),
        },
    );
    Suite::new()
        .test_needing(
            &[&adapter, &timestamps],
            "every_pass_of_an_iteration_has_positive_finite_device_time",
            every_pass_of_an_iteration_has_positive_finite_device_time,
        )
        .test_needing(
            &[&adapter],
            "a_device_without_timestamps_measures_nothing",
            a_device_without_timestamps_measures_nothing,
        )
        .run()
}
