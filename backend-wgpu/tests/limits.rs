//! Requests that cannot fit the device are refused up front with the limit named, before any
//! work is submitted, and the backend stays usable afterwards.

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::compile::compile_scene;
use ppm_core::layout::EyePassParams;
use ppm_core::passes::{BackendError, EyePass, SceneUpload};
use std::process::ExitCode;
use test_support::{Need, Suite};

/// One eye sample per pixel, four bounces.
fn eye_params() -> EyePassParams {
    EyePassParams {
        spp: 1,
        max_depth: 4,
        r2_initial: 0.01,
        ray_epsilon: 1e-5,
        ..Default::default()
    }
}

fn an_image_beyond_the_binding_limit_is_refused_naming_the_limit() {
    let mut gpu = WgpuBackend::new().unwrap();
    let scene = scenes::analytic::furnace(glam::Vec3::splat(0.5), 1.0);
    // 20,000 x 20,000 hit points are 38 GB: more than any adapter binds at once.
    gpu.load_scene(&compile_scene(&scene, 20_000, 20_000))
        .unwrap();
    let params = eye_params();
    match gpu.eye_pass(&params) {
        Err(BackendError::Limit(message)) => {
            assert!(
                message.contains("hit_points")
                    && message.contains("max_storage_buffer_binding_size"),
                "{message}"
            );
        }
        other => panic!("expected a limit error, got {other:?}"),
    }
    gpu.load_scene(&compile_scene(&scene, 8, 8)).unwrap();
    let stats = gpu
        .eye_pass(&params)
        .expect("a request that fits still runs");
    assert_eq!(stats.hit_points, 64);
}

/// A scene without triangles uploads (its BVH stands in as one leaf of one degenerate
/// triangle) and every eye ray misses, as on the CPU.
fn a_scene_without_triangles_traces_to_nothing() {
    let mut gpu = WgpuBackend::new().unwrap();
    let mut scene = scenes::analytic::furnace(glam::Vec3::splat(0.5), 1.0);
    scene.objects.clear();
    gpu.load_scene(&compile_scene(&scene, 8, 8)).unwrap();
    let params = eye_params();
    let stats = gpu.eye_pass(&params).expect("an empty scene traces");
    assert_eq!((stats.rays, stats.hit_points), (64, 0));
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "an_image_beyond_the_binding_limit_is_refused_naming_the_limit",
            an_image_beyond_the_binding_limit_is_refused_naming_the_limit,
        )
        .test_needing(
            &[&adapter],
            "a_scene_without_triangles_traces_to_nothing",
            a_scene_without_triangles_traces_to_nothing,
        )
        .run()
}
