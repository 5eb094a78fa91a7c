//! Same seed, same backend: the same buffers whatever the thread count (docs/algorithm.md 5),
//! the device's limits, or the work a wgpu local move saves.

use harness::driver::{Budget, Renderer, Schedule, run};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
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
/// offers (four storage textures and eight storage buffers per stage, among others), still or
/// through a local move.
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

    // And through a local move, whose passes run on the device too.
    let moved = Schedule::after_move(
        Budget::iterations(2),
        MoveMode::Local,
        Budget::iterations(1),
    );
    let after_move = |backend: &mut backend_wgpu::WgpuBackend| {
        let outcome = run(
            backend,
            &scene,
            &params,
            &MoveParams::default(),
            &moved,
            &mut (),
        )
        .unwrap();
        assert!(outcome.error.is_none(), "{:?}", outcome.error);
        let hit_points = backend.read_hit_points().unwrap();
        (
            bytemuck::cast_slice::<_, u8>(&hit_points).to_vec(),
            outcome.image.pixels,
        )
    };
    let (a, b) = (after_move(&mut adapter_limits), after_move(&mut baseline));
    assert!(a == b, "baseline limits changed a local move's buffers");
}

/// Along a drag, a wgpu local move takes its pose-A pairs' light from the last move's pose
/// B, which is its pose A, rather than evaluating it again, and answers its pose-A correction
/// photons from the paths the ordinary pass before it kept, rather than tracing them: the same
/// slots bit for bit either way, on a scene whose direct light the drag blocks (cornell-box)
/// and one whose paths bounce off mirrors (wedding-band).
fn a_wgpu_drag_keeps_its_pairs_and_paths_and_changes_nothing() {
    for name in ["cornell-box", "wedding-band"] {
        let scene = scenes::builtin(name).unwrap().load().unwrap();
        let declared = scene.moves[0];
        let step = ppm_core::scene::Move {
            translation: declared.translation / 8.0,
            rotation: glam::Quat::IDENTITY.slerp(declared.rotation, 1.0 / 8.0),
            ..declared
        };
        let mut params = RenderParams::for_scene(&scene);
        (params.width, params.height, params.photons_per_pass) = (40, 32, 10_000);
        let drag = |keep_pairs: bool, keep_paths: bool| {
            let mut backend = backend_wgpu::WgpuBackend::new().unwrap();
            backend.set_keep_pairs(keep_pairs);
            backend.set_keep_paths(keep_paths);
            let moves = MoveParams::default();
            let mut render = Renderer::start(&mut backend, scene.clone(), &params, &moves).unwrap();
            for _ in 0..4 {
                render.iteration().unwrap();
            }
            let mut corrected = 0;
            for _ in 0..4 {
                let moved = render.move_objects(&[step], MoveMode::Local).unwrap();
                corrected += moved.direct_corrected;
                render.iteration().unwrap();
            }
            let hit_points = render.backend().read_hit_points().unwrap();
            (
                bytemuck::cast_slice::<_, u8>(&hit_points).to_vec(),
                corrected,
            )
        };
        let (kept, corrected) = drag(true, true);
        let (evaluated, _) = drag(false, true);
        let (traced, _) = drag(true, false);
        assert!(
            corrected > 0,
            "{name}: the drag corrected no slot's direct light"
        );
        assert!(kept == evaluated, "{name}: kept pairs changed the slots");
        assert!(kept == traced, "{name}: kept paths changed the slots");
    }
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
        .test_needing(
            &[tests::wgpu()],
            "a_wgpu_drag_keeps_its_pairs_and_paths_and_changes_nothing",
            a_wgpu_drag_keeps_its_pairs_and_paths_and_changes_nothing,
        )
        .run()
}
