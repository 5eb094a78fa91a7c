//! Same seed, same backend: the same buffers whatever the thread count (docs/algorithm.md 5).

use ppm_core::params::RenderParams;
use ppm_core::passes::ReadBack;
use std::process::ExitCode;
use tests::Suite;
use tests::{render_cpu, render_on};

fn cpu_buffers_are_bit_identical_across_thread_counts() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.width = 48;
    params.height = 40;
    params.spp = 2;
    params.passes = 3;
    params.photons_per_pass = 30_000;
    params.seed = 5;
    let mut reference = None;
    for threads in [1, 2, 3, 8] {
        let (outcome, mut backend) = render_cpu(&scene, 0, &params, threads);
        let hit_points = backend.read_hit_points().unwrap();
        let photons = backend.read_photons().unwrap();
        let bytes = (
            bytemuck::cast_slice::<_, u8>(&hit_points).to_vec(),
            bytemuck::cast_slice::<_, u8>(&photons).to_vec(),
            outcome.image.pixels,
        );
        match &reference {
            None => reference = Some(bytes),
            Some(r) => assert!(r == &bytes, "{threads} threads gave different buffers"),
        }
    }
}

fn a_different_seed_gives_different_photons() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.width = 16;
    params.height = 16;
    params.passes = 1;
    params.photons_per_pass = 1000;
    let (_, mut a) = render_cpu(&scene, 0, &params, 2);
    params.seed = 1;
    let (_, mut b) = render_cpu(&scene, 0, &params, 2);
    assert_ne!(a.read_photons().unwrap(), b.read_photons().unwrap());
}

/// The wgpu backend on a device held to WebGPU's baseline limits renders, bit for bit, what
/// it renders with the adapter's own: no pass binds or needs more than any WebGPU device
/// offers (four storage textures and eight storage buffers per stage, among others).
fn wgpu_renders_the_same_buffers_within_baseline_limits() {
    let mut adapter_limits = backend_wgpu::WgpuBackend::new().unwrap();
    let mut baseline = backend_wgpu::GpuContext::baseline()
        .and_then(backend_wgpu::WgpuBackend::on)
        .expect("the passes fit baseline WebGPU limits");
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.width = 32;
    params.height = 24;
    params.passes = 2;
    params.photons_per_pass = 20_000;
    params.seed = 3;
    let buffers = |backend: &mut backend_wgpu::WgpuBackend| {
        let outcome = render_on(backend, &scene, 0, &params);
        let hit_points = backend.read_hit_points().unwrap();
        let photons = backend.read_photons().unwrap();
        (
            bytemuck::cast_slice::<_, u8>(&hit_points).to_vec(),
            bytemuck::cast_slice::<_, u8>(&photons).to_vec(),
            outcome.image.pixels,
        )
    };
    let (a, b) = (buffers(&mut adapter_limits), buffers(&mut baseline));
    assert!(!a.1.is_empty(), "the render deposited photons");
    assert!(a == b, "baseline limits changed the buffers");
}

fn main() -> ExitCode {
    Suite::new()
        .test(
            "cpu_buffers_are_bit_identical_across_thread_counts",
            cpu_buffers_are_bit_identical_across_thread_counts,
        )
        .test(
            "a_different_seed_gives_different_photons",
            a_different_seed_gives_different_photons,
        )
        .test_needing(
            &[tests::wgpu()],
            "wgpu_renders_the_same_buffers_within_baseline_limits",
            wgpu_renders_the_same_buffers_within_baseline_limits,
        )
        .run()
}
