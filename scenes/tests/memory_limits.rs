//! The memory a render plans is checked before anything is allocated
//! (`ppm_core::limits`), on the canonical Cornell box: refusals name the options to change.

use ppm_core::limits::{MemoryBudget, check_render_memory};
use ppm_core::params::RenderParams;
use ppm_core::scene::Scene;

fn tiny_budget() -> MemoryBudget {
    MemoryBudget {
        bytes: 1 << 20,
        source: "a test's 1 MiB".into(),
    }
}

fn cornell() -> Scene {
    scenes::cornell_box_file().unwrap()
}

#[test]
fn hit_points_beyond_the_budget_are_refused_naming_the_options() {
    let scene = cornell();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height, params.photons_per_pass) = (90, 90, 100);
    assert!(check_render_memory(&params, &scene, &tiny_budget()).is_ok());
    params.width = 200;
    let err = check_render_memory(&params, &scene, &tiny_budget())
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "command line: width * height * spp = 200 * 90 * 1 = 18000: hit points of 112 \
         bytes need 2.0 MB; 1.0 MB fits (a test's 1 MiB): lower --width, --height or --spp"
    );
}

/// cornell-box's whitest albedo is 0.725: 3.6 deposits per path at most on average.
#[test]
fn deposits_are_bounded_by_the_largest_albedo() {
    let scene = cornell();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height) = (8, 8);
    params.photons_per_pass = 9_000;
    assert!(check_render_memory(&params, &scene, &tiny_budget()).is_ok());
    params.photons_per_pass = 10_000;
    let err = check_render_memory(&params, &scene, &tiny_budget())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("command line: photons_per_pass = 10000: 36364 deposits of 32 bytes")
            && err.ends_with("lower --photons-per-pass"),
        "{err}"
    );
}
