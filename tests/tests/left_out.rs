//! What a render leaves out is what it did not compile, allocate or run: the wgpu backend
//! compiles a move's pipelines and allocates the pending sums only when a move needs them,
//! and the report says so, with the bytes, until then and not after.

use harness::driver::{Budget, Schedule, run};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};

fn listed(lines: &[String], start: &str) -> bool {
    lines.iter().any(|l| l.starts_with(start))
}

#[test]
fn a_still_wgpu_render_lists_what_it_never_created_and_a_move_creates_it() {
    let Some(mut backend) = backend_wgpu::backend_or_skip(
        "a_still_wgpu_render_lists_what_it_never_created_and_a_move_creates_it",
    ) else {
        return;
    };
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    p.width = 32;
    p.height = 24;
    p.photons_per_pass = 10_000;
    let moves = MoveParams::default();
    let still = Schedule::frame(0, Budget::iterations(2));
    let report = run(&mut backend, &scene, &p, &moves, &still, &mut ())
        .unwrap()
        .report;
    assert!(listed(
        &report.left_out,
        "hit-point update pipeline: not compiled"
    ));
    assert!(listed(
        &report.left_out,
        "landing-path pipeline: not compiled"
    ));
    let bytes = format!("pending sums: {} bytes not allocated", 32 * 24 * 16);
    assert!(listed(&report.left_out, &bytes), "{:?}", report.left_out);

    // Area mode's move re-traces the slots and defers its region passes.
    let moved = Schedule::after_move(Budget::iterations(2), MoveMode::Area, Budget::iterations(2));
    let report = run(&mut backend, &scene, &p, &moves, &moved, &mut ())
        .unwrap()
        .report;
    assert!(
        !listed(&report.left_out, "hit-point update pipeline")
            && !listed(&report.left_out, "landing-path pipeline")
            && !listed(&report.left_out, "pending sums"),
        "{:?}",
        report.left_out
    );
}
