//! What a render leaves out is what it did not compile, allocate or run: the wgpu backend
//! compiles a move's pipelines and allocates the pending sums, the photon path weights and a
//! camera move's copies of the slots only when a move needs them (or a render says moves
//! will follow), and the report says so, with the bytes, until then and not after.

use harness::driver::{Budget, Renderer, Schedule, run};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use std::process::ExitCode;
use std::time::{Duration, Instant};
use tests::Suite;

fn listed(lines: &[String], start: &str) -> bool {
    lines.iter().any(|l| l.starts_with(start))
}

fn a_still_wgpu_render_lists_what_it_never_created_and_a_move_creates_it() {
    let mut backend = backend_wgpu::WgpuBackend::new().unwrap();
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
    assert!(
        listed(&report.left_out, "photon path weights: "),
        "{:?}",
        report.left_out
    );
    assert!(
        listed(
            &report.left_out,
            "local-move pipelines: not compiled (no local move)"
        ),
        "{:?}",
        report.left_out
    );
    let copies = format!(
        "camera-move copies of the slots: {} bytes not allocated",
        32 * 24 * (112 + 32)
    );
    assert!(
        listed(
            &report.left_out,
            "camera-move pipeline: not compiled (no camera move)"
        ) && listed(&report.left_out, &copies),
        "{:?}",
        report.left_out
    );

    // Area mode's move re-traces the slots and defers its region passes.
    let moved = Schedule::after_move(Budget::iterations(2), MoveMode::Area, Budget::iterations(2));
    let report = run(&mut backend, &scene, &p, &moves, &moved, &mut ())
        .unwrap()
        .report;
    assert!(
        !listed(&report.left_out, "hit-point update pipeline")
            && !listed(&report.left_out, "landing-path pipeline")
            && !listed(&report.left_out, "pending sums")
            && !listed(&report.left_out, "photon path weights"),
        "{:?}",
        report.left_out
    );
    assert!(
        listed(&report.left_out, "local-move pipelines"),
        "{:?}",
        report.left_out
    );

    // A render in local mode compiles its moves' pipelines ahead of the first, the probe's
    // too (no path bounces off a mirror to probe in cornell-box, but a user's drag may meet
    // one elsewhere), and the camera move's.
    let moved = Schedule::after_move(
        Budget::iterations(2),
        MoveMode::Local,
        Budget::iterations(1),
    );
    let report = run(&mut backend, &scene, &p, &moves, &moved, &mut ())
        .unwrap()
        .report;
    assert!(
        !listed(&report.left_out, "local-move")
            && !listed(&report.left_out, "camera-move pipeline"),
        "{:?}",
        report.left_out
    );
}

/// The pipelines that moves use, and only moves, none of which a still render compiles.
fn move_pipelines(left_out: &[String]) -> Vec<&String> {
    left_out
        .iter()
        .filter(|l| {
            l.starts_with("local-move")
                || l.starts_with("camera-move pipeline")
                || l.starts_with("photon pass: mover-box tests")
        })
        .collect()
}

/// A render that says it will move has every pipeline a move uses compiled before its first
/// move, on a thread of the backend's own while it renders on: the first drag step waits for
/// no compiler.
fn a_render_that_expects_moves_compiles_their_pipelines_while_it_renders() {
    let mut backend = backend_wgpu::WgpuBackend::new().unwrap();
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    (p.width, p.height, p.photons_per_pass) = (32, 24, 10_000);
    let mut r = Renderer::start(&mut backend, scene, &p, &MoveParams::default()).unwrap();
    r.iteration().unwrap();
    let still = r.backend().not_created();
    assert_eq!(move_pipelines(&still).len(), 3, "{still:?}");
    r.expect_local_moves().unwrap();
    let start = Instant::now();
    let mut iterations = 0;
    while !move_pipelines(&r.backend().not_created()).is_empty() {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "after {iterations} iterations: {:?}",
            r.backend().not_created()
        );
        r.iteration().unwrap();
        iterations += 1;
    }
}

/// The eye and photon pipelines are specialised to the scene: without mirrors or glass their
/// specular code is not compiled, ordinary photon passes carry no mover-box tests, and the
/// report says so. Through a still warm-up and a local move, the specialised build renders
/// the general build's image bit for bit, on a diffuse scene and on one with mirrors.
fn specialised_pipelines_leave_out_what_the_scene_cannot_reach_and_render_the_same_image() {
    for (name, specular) in [("cornell-box", false), ("wedding-band", true)] {
        let scene = scenes::builtin(name).unwrap().load().unwrap();
        let mut p = RenderParams::for_scene(&scene);
        (p.width, p.height, p.photons_per_pass) = (40, 30, 10_000);
        let render = |general: bool| {
            let mut backend = backend_wgpu::WgpuBackend::new().unwrap();
            backend.set_general(general);
            let schedule = Schedule::after_move(
                Budget::iterations(3),
                MoveMode::Local,
                Budget::iterations(2),
            );
            let still = Schedule::frame(0, Budget::iterations(2));
            let before = run(
                &mut backend,
                &scene,
                &p,
                &MoveParams::default(),
                &still,
                &mut (),
            )
            .unwrap()
            .report
            .left_out;
            let outcome = run(
                &mut backend,
                &scene,
                &p,
                &MoveParams::default(),
                &schedule,
                &mut (),
            )
            .unwrap();
            assert!(outcome.error.is_none(), "{name}: {:?}", outcome.error);
            let compiled = backend.compiled_specialisations();
            (outcome.image, before, compiled)
        };
        let (special, left_out, (eye, photon)) = render(false);
        let (general, general_left_out, (general_eye, _)) = render(true);
        assert_eq!(
            special.pixels, general.pixels,
            "{name}: specialised and general images"
        );
        assert!(special.pixels.iter().flatten().any(|c| *c > 0.0));
        // Neither scene has glass: no refraction code either way.
        assert!(
            eye.iter().all(|s| s.specular == specular && !s.glass),
            "{name}: {eye:?}"
        );
        assert!(
            general_eye.iter().all(|s| s.specular && s.glass),
            "{general_eye:?}"
        );
        // The ordinary passes test no mover box; the local move's correction does.
        assert!(photon[0].iter().any(|s| !s.movers) && photon[0].iter().any(|s| s.movers));
        let says = |lines: &[String], what: &str| lines.iter().any(|l| l.contains(what));
        assert_eq!(
            says(
                &left_out,
                "eye pass: mirror, glass and conductor code not compiled"
            ),
            !specular,
            "{name}: {left_out:?}"
        );
        assert_eq!(
            says(&left_out, "eye pass: refraction code not compiled"),
            specular,
            "{name}: {left_out:?}"
        );
        assert!(
            says(&left_out, "mover-box tests not compiled"),
            "{left_out:?}"
        );
        assert!(
            !says(&general_left_out, "not compiled (the scene has")
                && !says(&general_left_out, "mover-box tests not compiled"),
            "{general_left_out:?}"
        );
    }
}

fn main() -> ExitCode {
    Suite::new()
        .test_needing(
            &[tests::wgpu()],
            "a_still_wgpu_render_lists_what_it_never_created_and_a_move_creates_it",
            a_still_wgpu_render_lists_what_it_never_created_and_a_move_creates_it,
        )
        .test_needing(
            &[tests::wgpu()],
            "a_render_that_expects_moves_compiles_their_pipelines_while_it_renders",
            a_render_that_expects_moves_compiles_their_pipelines_while_it_renders,
        )
        .test_needing(
            &[tests::wgpu()],
            "specialised_pipelines_leave_out_what_the_scene_cannot_reach_and_render_the_same_image",
            specialised_pipelines_leave_out_what_the_scene_cannot_reach_and_render_the_same_image,
        )
        .run()
}
