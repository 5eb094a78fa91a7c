//! What a drag costs in local mode: many small moves in a row, each followed by one
//! iteration, against the iterations between them, side by side in one run.
//!
//! `cargo bench -p harness --bench drag` warms each canonical scene up for
//! `PPM_BENCH_WARMUP` iterations (default 30) at `PPM_BENCH_SIZE` (default 256), saying
//! that local moves will follow (as `ppm view` does: the moves' pipelines compile and
//! ordinary passes keep their paths meanwhile), then moves
//! the object its `[[moves]]` name by a thirtieth of that move, `PPM_BENCH_MOVES` times
//! (default 30), an iteration after each. It prints milliseconds per iteration (the warm-up's
//! last ten, and the mean of those between the moves, which keep their photon paths for the
//! next move and serve the reset slots first) and per move (mean, median and largest), the
//! mean and median move's ratio to a warm-up iteration, and the slots the moves reset and
//! corrected on average, then where a move's time goes (each part's median: the host's refit
//! and request, the backend's passes).
//! The `crowd` row drags cornell-bunny's short block past 14 more small bunnies (1.05
//! million triangles): a move must cost what the moved object touches, not the scene.
//! Figures only, no threshold: machines are noisy, compare rows of one
//! run. `PPM_BENCH_BACKENDS` (default `cpu,wgpu`) and `PPM_BENCH_SCENES` choose the rows;
//! `PPM_BENCH_CORRECTION_PASSES` caps local mode's correction (0: none, the move's fixed
//! cost).

mod common;
#[path = "common/drag.rs"]
mod drag;

use backend_cpu::CpuBackend;
use common::{backends, setting, wgpu_if_wanted};
use drag::{drag, step_of, warm_up};
use glam::{Quat, Vec3};
use harness::driver::Renderer;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::{Move, Scene};

fn main() {
    let warmup: u32 = setting("PPM_BENCH_WARMUP", 30);
    let moves: u32 = setting("PPM_BENCH_MOVES", 30);
    let size: u32 = setting("PPM_BENCH_SIZE", 256);
    let defaults = MoveParams::default();
    let move_params = MoveParams {
        correction_passes: setting("PPM_BENCH_CORRECTION_PASSES", defaults.correction_passes),
        ..defaults
    };
    let backends = backends();
    let scenes = std::env::var("PPM_BENCH_SCENES")
        .unwrap_or_else(|_| format!("cornell-box,cornell-bunny,wedding-band,{CROWD}"));
    let mut gpu = wgpu_if_wanted(&backends);
    println!(
        "local mode, {size}x{size}, {warmup} iterations of warm-up, then {moves} moves of a \
         thirtieth of the scene's move, one iteration after each"
    );
    println!(
        "{:<14} {:<5} {:>12} {:>11} {:>9} {:>9} {:>9} {:>10} {:>10} {:>9} {:>9}",
        "scene",
        "back",
        "ms/iteration",
        "in the drag",
        "ms/move",
        "median",
        "largest",
        "move/iter",
        "median/it",
        "reset",
        "corrected"
    );
    for name in scenes.split(',') {
        let loaded = match name.trim() {
            CROWD => crowd(),
            name => scenes::builtin(name).and_then(|s| s.load().ok()),
        };
        let Some(scene) = loaded else {
            println!("{name}: no such built-in scene");
            continue;
        };
        let Some(declared) = scene.moves.first().copied() else {
            println!("{name}: declares no move to take a thirtieth of");
            continue;
        };
        let step = step_of(declared);
        let mut p = RenderParams::for_scene(&scene);
        (p.width, p.height) = (size, size);
        let row = |backend: &mut dyn Backend| {
            let mut r =
                Renderer::start(backend, scene.clone(), &p, &move_params).expect("the scene loads");
            // As `ppm view` does: the moves' pipelines compile during the warm-up.
            r.expect_local_moves().expect("the moves are prepared");
            let per_iteration = warm_up(&mut r, warmup);
            let d = drag(&mut r, step, moves);
            println!(
                "{name:<14} {:<5} {per_iteration:>12.1} {:>11.1} {:>9.1} {:>9.1} {:>9.1} {:>10.2} {:>10.2} {:>9} {:>9}",
                r.backend().name(),
                d.iteration_ms,
                d.move_ms,
                d.median_ms,
                d.largest_ms,
                d.move_ms / per_iteration,
                d.median_ms / per_iteration,
                d.reset,
                d.corrected
            );
            println!("  where a move goes, median ms: {}", d.parts_line());
        };
        if backends.contains("cpu") {
            row(&mut CpuBackend::new());
        }
        if let Some(gpu) = gpu.as_mut() {
            row(gpu);
        }
    }
}

/// The row that drags a small object through a large scene.
const CROWD: &str = "crowd";

/// cornell-bunny with 14 more bunnies a fifth of its size in two rows behind it (1.05
/// million triangles in all), whose move turns and shifts the short block instead: what a
/// move costs where the scene is far larger than what moves.
fn crowd() -> Option<Scene> {
    let mut scene = scenes::builtin("cornell-bunny")?.load().ok()?;
    let bunny = scene.object_index("bunny")?;
    let block = scene.object_index("short-block")?;
    let origin = Vec3::new(368.0, 0.0, 351.0);
    for k in 0..14 {
        let mut copy = scene.objects[bunny].clone();
        copy.name = format!("small-bunny-{k}");
        let at = Vec3::new(
            60.0 + 60.0 * (k % 7) as f32,
            0.0,
            440.0 + 60.0 * (k / 7) as f32,
        );
        for v in copy.triangles.iter_mut().flatten() {
            *v = (*v - origin) * 0.2 + at;
        }
        scene.objects.push(copy);
    }
    scene.moves = vec![Move {
        object: block,
        translation: Vec3::new(60.0, 0.0, 60.0),
        rotation: Quat::from_rotation_y(15f32.to_radians()),
    }];
    Some(scene)
}
