//! Camera moves at their hardest (docs/algorithm.md 3d), each in local mode against a restart
//! of the same iterations and the path tracer's truth of where it ends: a view that shares
//! nothing with the old one, dollies that make footprints much larger or smaller, a grazing
//! view, a camera that moves into water, and camera and object moves one right after the
//! other. In each the kept render stays finite, its brightest pixel near the truth's, and
//! its error no worse than the restart's.

use backend_cpu::CpuBackend;
use glam::{Quat, Vec3};
use harness::driver::{MoveReport, Renderer};
use ppm_core::camera_move::started_over;
use ppm_core::image::Image;
use ppm_core::metrics::{block_relative_rmse, relative_rmse_parts};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::scene::{Camera, Move, Scene};
use std::process::ExitCode;
use tests::{Suite, figure};

const SIZE: u32 = 32;

/// What a case does after its warm-up.
#[derive(Clone)]
enum Step {
    Camera(Camera),
    Object(Move),
}

fn params(scene: &Scene) -> RenderParams {
    let mut p = RenderParams::for_scene(scene);
    (p.width, p.height, p.photons_per_pass) = (SIZE, SIZE, 10_000);
    p
}

/// A render after its steps.
struct Rendered {
    image: Image,
    /// The moves' reports.
    reports: Vec<MoveReport>,
    /// Per pixel, whether its slots kept their light at the last camera step (none without
    /// one).
    kept: Vec<bool>,
}

/// The render after 30 iterations, `steps` in `mode` (each followed by 2 iterations) and 8
/// more.
fn render(scene: &Scene, steps: &[Step], mode: MoveMode) -> Rendered {
    let p = params(scene);
    let mut backend = CpuBackend::new();
    let mut r = Renderer::start(&mut backend, scene.clone(), &p, &MoveParams::default()).unwrap();
    for _ in 0..30 {
        r.iteration().unwrap();
    }
    let (mut reports, mut kept) = (Vec::new(), vec![false; (SIZE * SIZE) as usize]);
    for step in steps {
        reports.push(match step {
            Step::Camera(c) => r.move_camera(c.clone(), mode).unwrap(),
            Step::Object(m) => r.move_objects(&[*m], mode).unwrap(),
        });
        if let Step::Camera(_) = step {
            kept.fill(false);
            for hp in r.backend().read_hit_points().unwrap() {
                kept[hp.pixel as usize] |= !started_over(&hp);
            }
        }
        for _ in 0..2 {
            r.iteration().unwrap();
        }
    }
    for _ in 0..8 {
        r.iteration().unwrap();
    }
    let image = r.resolve().unwrap();
    Rendered {
        image,
        reports,
        kept,
    }
}

/// Runs `steps` in local mode and restarting, and holds the local render to the truth of
/// where they end: finite, its brightest pixel within 1.5 times the truth's, its error over
/// 4x4 blocks at most 1.1 times the restart's. Returns the local render and the truth.
fn holds(name: &str, scene: &Scene, steps: &[Step]) -> (Rendered, Image) {
    let mut end = scene.clone();
    for step in steps {
        match step {
            Step::Camera(c) => end.camera = c.clone(),
            Step::Object(m) => end.apply(m),
        }
    }
    let truth = tests::truth(&end, SIZE, 512);
    let local = render(scene, steps, MoveMode::Local);
    let restart = render(scene, steps, MoveMode::Restart).image;
    let (image, reports) = (&local.image, &local.reports);
    assert!(
        image.pixels.iter().flatten().all(|c| c.is_finite()),
        "{name}"
    );
    let (l, r) = (
        block_relative_rmse(image, &truth, 4),
        block_relative_rmse(&restart, &truth, 4),
    );
    let (bl, bt) = (image.brightest(), truth.brightest());
    figure!(
        "{name}: block error {l:.4} (restart {r:.4}), brightest {bl:.3} (truth {bt:.3}); {reports:?}"
    );
    assert!(bl <= 1.5 * bt, "{name}: brightest {bl} against {bt}");
    assert!(l <= 1.1 * r, "{name}: {l} against restart's {r}");
    (local, truth)
}

fn cornell() -> Scene {
    scenes::builtin("cornell-box").unwrap().load().unwrap()
}

/// A camera turned to face away from everything it saw keeps no slot.
fn a_view_that_shares_nothing_keeps_nothing() {
    let scene = cornell();
    let away = scene.camera.orbited(180.0, 0.0);
    let reports = holds("turned away", &scene, &[Step::Camera(away)])
        .0
        .reports;
    assert_eq!(reports[0].kept, 0, "{reports:?}");
}

/// Footprints four times the area, and a quarter: the camera twice as far and half as far
/// from its look-at point.
fn large_dollies_stay_near_the_truth() {
    let scene = cornell();
    for (name, nearer) in [("dolly out", -1.0), ("dolly in", 0.5)] {
        let camera = scene.camera.orbited(0.0, nearer);
        let reports = holds(name, &scene, &[Step::Camera(camera)]).0.reports;
        assert!(reports[0].restarted.is_none(), "{reports:?}");
    }
}

/// The camera lowered to a few millimetres above the floor, looking along it. The blocks'
/// tops now stand against the back wall: edges the old view did not have, across pixels
/// whose fresh eye paths found the wall. The pixels that kept their light are as near the
/// truth as those of a render of the grazing view as old as their light (were such a pixel
/// to keep the wall's light, the block's part of it would stay missing for as long as that
/// history weighs).
fn a_grazing_view_stays_near_the_truth() {
    let scene = cornell();
    let grazing = Camera {
        eye: Vec3::new(278.0, 2.0, -800.0),
        look_at: Vec3::new(278.0, 2.0, 0.0),
        ..scene.camera.clone()
    };
    let (local, truth) = holds("grazing", &scene, &[Step::Camera(grazing.clone())]);
    let mut end = scene.clone();
    end.camera = grazing;
    let mut still = CpuBackend::new();
    let mut s = Renderer::start(&mut still, end, &params(&scene), &MoveParams::default()).unwrap();
    for _ in 0..40 {
        s.iteration().unwrap();
    }
    let as_old = s.resolve().unwrap();
    let kept = &local.kept;
    let (l, o) = (
        relative_rmse_parts(&local.image, &truth, kept).1,
        relative_rmse_parts(&as_old, &truth, kept).1,
    );
    let count = kept.iter().filter(|&&k| k).count();
    figure!("grazing: the {count} kept pixels' error {l:.4}, a render as old {o:.4}");
    assert!(l <= 1.1 * o, "kept pixels {l} against a render as old {o}");
}

/// The camera of the half-filled water furnace moved under the water: nothing it sees now
/// did it see directly before, and what it sees through the surface starts over.
fn a_camera_that_moves_into_water_keeps_nothing_seen_through_it() {
    let scene = scenes::builtin("water-furnace").unwrap().load().unwrap();
    let under = Camera {
        eye: scene.camera.eye - Vec3::Y * (scene.camera.eye.y + 0.5),
        look_at: scene.camera.look_at - Vec3::Y * (scene.camera.eye.y + 0.5),
        ..scene.camera.clone()
    };
    holds("into the water", &scene, &[Step::Camera(under)]);
}

/// An object move right after a camera move, and a camera move right after an object move:
/// each keeps what it did not change (a later move resets what its inherited light saw).
fn camera_and_object_moves_follow_each_other() {
    let scene = cornell();
    let block = Move {
        object: scene.object_index("short-block").unwrap(),
        translation: Vec3::new(-40.0, 0.0, 60.0),
        rotation: Quat::from_rotation_y(0.3),
    };
    let camera = scene.camera.orbited(6.0, 0.1);
    for (name, steps) in [
        (
            "camera then object",
            [Step::Camera(camera.clone()), Step::Object(block)],
        ),
        (
            "object then camera",
            [Step::Object(block), Step::Camera(camera.clone())],
        ),
    ] {
        let reports = holds(name, &scene, &steps).0.reports;
        assert!(
            reports.iter().all(|r| r.restarted.is_none() && r.kept > 0),
            "{reports:?}"
        );
    }
}

fn main() -> ExitCode {
    Suite::new()
        .test(
            "a_view_that_shares_nothing_keeps_nothing",
            a_view_that_shares_nothing_keeps_nothing,
        )
        .test(
            "large_dollies_stay_near_the_truth",
            large_dollies_stay_near_the_truth,
        )
        .test(
            "a_grazing_view_stays_near_the_truth",
            a_grazing_view_stays_near_the_truth,
        )
        .test(
            "a_camera_that_moves_into_water_keeps_nothing_seen_through_it",
            a_camera_that_moves_into_water_keeps_nothing_seen_through_it,
        )
        .test(
            "camera_and_object_moves_follow_each_other",
            camera_and_object_moves_follow_each_other,
        )
        .run()
}
