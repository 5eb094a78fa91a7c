//! Requests that cannot fit the device are refused up front with the limit named, before any
//! work is submitted, and the backend stays usable afterwards.

use ppm_core::compile::compile_scene;
use ppm_core::layout::EyePassParams;
use ppm_core::passes::{BackendError, EyePass, SceneUpload};

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

#[test]
fn an_image_beyond_the_binding_limit_is_refused_naming_the_limit() {
    let Some(mut gpu) = backend_wgpu::backend_or_skip(
        "an_image_beyond_the_binding_limit_is_refused_naming_the_limit",
    ) else {
        return;
    };
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
#[test]
fn a_scene_without_triangles_traces_to_nothing() {
    let Some(mut gpu) =
        backend_wgpu::backend_or_skip("a_scene_without_triangles_traces_to_nothing")
    else {
        return;
    };
    let mut scene = scenes::analytic::furnace(glam::Vec3::splat(0.5), 1.0);
    scene.objects.clear();
    gpu.load_scene(&compile_scene(&scene, 8, 8)).unwrap();
    let params = eye_params();
    let stats = gpu.eye_pass(&params).expect("an empty scene traces");
    assert_eq!((stats.rays, stats.hit_points), (64, 0));
}
