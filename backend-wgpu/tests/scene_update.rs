//! A drag step's scene update written in place (the movers' boxes of the pose held, then a
//! refit of it: `update_scene`), and a camera step's (the camera alone), render what the same
//! scene uploaded whole renders: every eye path and every photon, bit for bit.

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::compile::{CompiledScene, compile_scene, gpu_camera, mover_boxes};
use ppm_core::passes::{LocalMoves, ReadBack, SceneUpload};
use ppm_core::refit::recompile_moved;
use std::process::ExitCode;
use test_support::{Need, Suite};

mod common;

/// The slots and the photons of one eye pass and one photon pass, as bytes.
fn traced(backend: &mut WgpuBackend) -> (Vec<u8>, Vec<u8>) {
    common::eye_pass(backend, 1.0);
    common::photon_pass(backend);
    (
        bytemuck::cast_slice(&backend.read_hit_points().unwrap()).to_vec(),
        bytemuck::cast_slice(&backend.read_photons().unwrap()).to_vec(),
    )
}

fn a_drag_step_written_in_place_renders_what_a_whole_upload_renders() {
    let mut scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut a = compile_scene(&scene, 16, 16);
    let step = ppm_core::scene::Move {
        translation: glam::Vec3::new(-20.0, 0.0, 10.0),
        rotation: glam::Quat::from_rotation_y(0.1),
        ..scene.moves[0]
    };
    let moved = [step.object];
    let before = scene.clone();
    scene.apply(&step);
    let boxes = mover_boxes(&before, &scene, &moved, a.extent);
    a.movers = boxes.clone();
    let mut b: CompiledScene = recompile_moved(&a, &scene, &moved, None);
    assert!(b.refit_from.is_some(), "a small step refits");
    b.movers = boxes;
    let mut held = WgpuBackend::new().unwrap();
    held.load_scene(&a).unwrap();
    held.update_scene(&a).unwrap();
    held.update_scene(&b).unwrap();
    let mut whole = WgpuBackend::new().unwrap();
    whole.load_scene(&b).unwrap();
    let (in_place, uploaded) = (traced(&mut held), traced(&mut whole));
    assert!(
        !in_place.1.is_empty(),
        "the photons must deposit to test anything"
    );
    assert!(in_place.0 == uploaded.0, "the eye paths differ");
    assert!(in_place.1 == uploaded.1, "the photons differ");
}

fn a_camera_step_written_in_place_renders_what_a_whole_upload_renders() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let a = compile_scene(&scene, 16, 16);
    // The same pose seen from elsewhere, as the driver's camera step makes it.
    let mut camera = scene.camera.clone();
    camera.eye += glam::Vec3::new(40.0, -10.0, 30.0);
    let b = CompiledScene {
        camera: gpu_camera(&camera, 16, 16),
        ..a.clone()
    };
    assert_ne!(a.camera, b.camera);
    let mut held = WgpuBackend::new().unwrap();
    held.load_scene(&a).unwrap();
    traced(&mut held);
    held.update_scene(&b).unwrap();
    let mut whole = WgpuBackend::new().unwrap();
    whole.load_scene(&b).unwrap();
    let (in_place, uploaded) = (traced(&mut held), traced(&mut whole));
    assert!(in_place.0 == uploaded.0, "the eye paths differ");
    assert!(in_place.1 == uploaded.1, "the photons differ");
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "a_drag_step_written_in_place_renders_what_a_whole_upload_renders",
            a_drag_step_written_in_place_renders_what_a_whole_upload_renders,
        )
        .test_needing(
            &[&adapter],
            "a_camera_step_written_in_place_renders_what_a_whole_upload_renders",
            a_camera_step_written_in_place_renders_what_a_whole_upload_renders,
        )
        .run()
}
