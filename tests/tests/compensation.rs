//! Compensation photons on the CPU backend (docs/algorithm.md 2 and 3): in an unchanged scene a
//! negative region pass and a positive one cancel, and difference passes leave the statistics
//! as they were; after a move, area and difference modes converge towards the new pose with
//! either estimator; the clamps hold when negative photons outnumber the count.

use backend_cpu::CpuBackend;
use harness::driver::{Renderer, pass_params};
use harness::reference::{ReferenceBudget, render_reference};
use ppm_core::compile::{CompiledScene, camera_ray, compile_scene};
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::{
    GatherParams, PhotonPassParams, first_hit, gather_kind, hit_flags, material_kind, region_mode,
};
use ppm_core::metrics::relative_rmse;
use ppm_core::params::{Estimator, MoveMode, MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::region::emitting_region;
use ppm_core::scene::Scene;
use ppm_core::trace::PoseQueries;
use std::ops::ControlFlow;
use std::process::ExitCode;
use tests::{BackendTrials, Suite, figure};
use tests::{around, luminance, objects_seen};

fn cornell(size: u32, photons: u32) -> (Scene, RenderParams) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    p.width = size;
    p.height = size;
    p.photons_per_pass = photons;
    // The thesis's 20 mm, not the scene's 10: the tolerances below assume the photons per
    // hit point that a 64x64 render gathers at this radius after eight passes.
    p.initial_radius = 20.0;
    (scene, p)
}

/// A CPU render of `scene` (at its own pose) after `passes` ordinary passes.
fn warmed<'a>(
    backend: &'a mut CpuBackend,
    scene: Scene,
    p: &RenderParams,
    passes: u32,
) -> Renderer<'a> {
    let mut render = Renderer::start(backend, scene, p, &MoveParams::default()).unwrap();
    for _ in 0..passes {
        render.iteration().unwrap();
    }
    render
}

/// The error against `truth` now, then after each of `rounds` rounds of `iterations`.
fn errors_every(render: &mut Renderer, truth: &Image, rounds: u32, iterations: u32) -> Vec<f64> {
    let mut errors = vec![relative_rmse(&render.resolve().unwrap(), truth)];
    for _ in 0..rounds {
        for _ in 0..iterations {
            render.iteration().unwrap();
        }
        errors.push(relative_rmse(&render.resolve().unwrap(), truth));
    }
    errors
}

fn mean_luminance(image: &Image) -> f64 {
    image
        .pixels
        .iter()
        .map(|p| f64::from(luminance(*p)))
        .sum::<f64>()
        / image.pixels.len() as f64
}

/// The tall block's vertices as posed in `scene`.
fn tall_block(scene: &Scene) -> Vec<glam::Vec3> {
    let block = scene.object_index("tall-block").unwrap();
    scene.objects[block]
        .triangles
        .iter()
        .flatten()
        .copied()
        .collect()
}

/// Runs a compensation pass (`neg_index`) then a region pass (`pos_index`) through the tall
/// block's region on an unchanged scene; returns the images before and after.
fn cancel(neg_index: u32, pos_index: u32) -> (Image, Image) {
    let (scene, p) = cornell(64, 40_000);
    let mut backend = CpuBackend::new();
    let mut render = warmed(&mut backend, scene.clone(), &p, 8);
    let before = render.resolve().unwrap();
    let compiled = compile_scene(&scene, p.width, p.height);
    let region = emitting_region(&compiled.lights, &tall_block(&scene), region_mode::AREA).unwrap();
    let nc = 65_536;
    let b = render.backend().dynamic().expect("dynamic passes");
    for (index, scale, kind) in [
        (neg_index, -1.0, gather_kind::REGION_NEGATIVE),
        (pos_index, 1.0, gather_kind::REGION_POSITIVE),
    ] {
        let params = PhotonPassParams {
            seed: p.seed,
            pass_index: index,
            photon_count: nc,
            max_depth: 16,
            first_hit: first_hit::SKIP,
            ray_epsilon: pass_params::ray_epsilon(&p, compiled.extent),
            power_scale: scale,
            gather_kind: kind,
            ..Default::default()
        };
        b.photon_pass(&params, &PhotonSource::Region(region))
            .unwrap();
        b.gather_pass(&GatherParams {
            alpha: p.alpha,
            emitted_increment: 0.0,
            kind,
            region_photons: nc as f32,
        })
        .unwrap();
    }
    let after = render.resolve().unwrap();
    (before, after)
}

fn a_negative_then_positive_region_pass_in_an_unchanged_scene_leaves_the_image() {
    // Same random numbers: the paths coincide and cancel up to the nonlinearity of eqs 5-7.
    let (before, after) = cancel(0, 0);
    let change = (mean_luminance(&after) / mean_luminance(&before) - 1.0).abs();
    let rmse = relative_rmse(&after, &before);
    figure!("common numbers: mean change {change:.2e}, relative RMSE {rmse:.2e}");
    assert!(change < 2e-3 && rmse < 2e-2, "change {change}, rmse {rmse}");
    // Independent numbers: the two passes differ sample by sample but agree in expectation.
    let (before, after) = cancel(0, 1);
    let change = (mean_luminance(&after) / mean_luminance(&before) - 1.0).abs();
    figure!(
        "independent numbers: mean change {change:.2e}, relative RMSE {:.2e}",
        relative_rmse(&after, &before)
    );
    assert!(change < 1e-2, "change {change}");
}

/// A move that changes no object keeps every statistic, bit for bit, in every mode; and the
/// paired passes that difference and local modes rest on cancel photon by photon when both
/// poses are the same: negative and positive ordinary passes with the same random numbers,
/// deferred and applied once, leave `n`, `r2` and `emitted` and move no `tau` beyond
/// rounding.
fn a_move_to_the_same_pose_leaves_the_statistics() {
    let (scene, p) = cornell(64, 40_000);
    for mode in [
        MoveMode::Thesis,
        MoveMode::Area,
        MoveMode::Difference,
        MoveMode::Local,
    ] {
        let mut backend = CpuBackend::new();
        let mut render = warmed(&mut backend, scene.clone(), &p, 8);
        let before = render.backend().read_hit_points().unwrap();
        let moved = render.move_to(scene.clone(), mode).unwrap();
        assert_eq!((moved.updated, &moved.restarted), (0, &None), "{moved:?}");
        let after = render.backend().read_hit_points().unwrap();
        assert!(before == after, "{mode:?} changed a slot");
    }
    let mut backend = CpuBackend::new();
    let mut render = warmed(&mut backend, scene.clone(), &p, 8);
    let before = render.backend().read_hit_points().unwrap();
    let b = render.backend();
    for (scale, kind) in [
        (-1.0, gather_kind::REGION_NEGATIVE),
        (1.0, gather_kind::REGION_POSITIVE),
    ] {
        let params = PhotonPassParams {
            seed: p.seed,
            pass_index: ppm_core::rng::DIFFERENCE_PASS_BASE,
            photon_count: 40_000,
            max_depth: 16,
            first_hit: first_hit::SKIP,
            ray_epsilon: pass_params::ray_epsilon(&p, compile_scene(&scene, 64, 64).extent),
            power_scale: scale,
            gather_kind: kind | gather_kind::DEFERRED,
            ..Default::default()
        };
        let stats = b.photon_pass(&params, &PhotonSource::Lights).unwrap();
        assert!(stats.deposited > 0);
        b.gather_pass(&GatherParams {
            alpha: p.alpha,
            emitted_increment: 0.0,
            kind: kind | gather_kind::DEFERRED,
            region_photons: 40_000.0,
        })
        .unwrap();
    }
    b.gather_pass(&GatherParams {
        alpha: p.alpha,
        emitted_increment: 0.0,
        kind: gather_kind::REGION_APPLY,
        region_photons: 0.0,
    })
    .unwrap();
    let after = b.read_hit_points().unwrap();
    let mut worst = 0.0f32;
    for (b, a) in before.iter().zip(&after) {
        assert_eq!((b.n, b.r2, b.emitted), (a.n, a.r2, a.emitted));
        for c in 0..3 {
            worst = worst.max((a.tau[c] - b.tau[c]).abs() / b.tau[c].max(1e-30));
        }
    }
    figure!("largest relative change of tau: {worst:.2e}");
    assert!(worst < 1e-5, "tau moved by {worst}");
}

/// More negative photons than a hit point holds: every hit point stays finite, no flux
/// channel goes negative, and no radius grows past its initial value.
fn clamps_hold_when_negative_photons_outnumber_the_count() {
    let (scene, p) = cornell(48, 2_000);
    let mut backend = CpuBackend::new();
    let mut render = warmed(&mut backend, scene.clone(), &p, 1);
    let compiled = compile_scene(&scene, p.width, p.height);
    let region = emitting_region(&compiled.lights, &tall_block(&scene), region_mode::AREA).unwrap();
    let b = render.backend().dynamic().expect("dynamic passes");
    // 200,000 compensation photons against 2,000 emitted: each hit point near the block
    // loses far more than it ever gathered.
    b.photon_pass(
        &PhotonPassParams {
            seed: p.seed,
            pass_index: 0,
            photon_count: 200_000,
            max_depth: 16,
            first_hit: first_hit::SKIP,
            ray_epsilon: pass_params::ray_epsilon(&p, compiled.extent),
            power_scale: -1.0,
            gather_kind: gather_kind::REGION_NEGATIVE,
            ..Default::default()
        },
        &PhotonSource::Region(region),
    )
    .unwrap();
    b.gather_pass(&GatherParams {
        alpha: p.alpha,
        emitted_increment: 0.0,
        kind: gather_kind::REGION_NEGATIVE,
        region_photons: 2_000.0,
    })
    .unwrap();
    let r2_initial = p.initial_radius * p.initial_radius;
    let hps = b.read_hit_points().unwrap();
    let emptied = hps
        .iter()
        .filter(|h| h.is_valid() && h.n == 0.0 && h.r2 == r2_initial)
        .count();
    for h in hps.iter().filter(|h| h.is_valid()) {
        assert!(h.n >= 0.0 && h.n.is_finite(), "{h:?}");
        assert!(h.r2 > 0.0 && h.r2 <= r2_initial, "{h:?}");
        assert!(h.tau.iter().all(|t| *t >= 0.0 && t.is_finite()), "{h:?}");
    }
    assert!(
        emptied > 100,
        "the case must empty hit points to test the clamp: {emptied}"
    );
    assert!(render.resolve().unwrap().is_finite());
}

/// After the tall block moves, area, difference and (with `sppm`) local modes' frames approach
/// the truth of the new pose as iterations continue, with either estimator: `sppm` against the path-traced
/// reference, `ppm` against a long `ppm` render of the new pose (it converges to the
/// radiance at its pixel centres, not to the pixel averages of the path tracer).
fn after_a_move_compensating_modes_converge_towards_the_new_pose() {
    for estimator in [Estimator::Sppm, Estimator::Ppm] {
        let (scene, mut p) = cornell(64, 30_000);
        p.estimator = estimator;
        p.direct_samples = estimator.default_direct_samples();
        let truth = match estimator {
            Estimator::Sppm => {
                let compiled = compile_scene(&scene.at_frame(1), p.width, p.height);
                let budget = ReferenceBudget {
                    spp: Some(256),
                    seconds: None,
                };
                render_reference(&compiled, 99, budget, &mut |_, _| ControlFlow::Continue(())).image
            }
            Estimator::Ppm => {
                let mut reference = p.clone();
                reference.passes = 64;
                reference.seed = 99;
                tests::render_cpu(&scene, 1, &reference, 2).0.image
            }
        };
        let local = (estimator == Estimator::Sppm).then_some(MoveMode::Local);
        for mode in [MoveMode::Area, MoveMode::Difference]
            .into_iter()
            .chain(local)
        {
            let mut backend = CpuBackend::new();
            let mut render = warmed(&mut backend, scene.at_frame(0), &p, 8);
            let stale = relative_rmse(&render.resolve().unwrap(), &truth);
            let moved = render.move_to(scene.at_frame(1), mode).unwrap();
            // Local mode records no guiding paths: its reset slots simply iterate on.
            let guided = mode == MoveMode::Local || moved.recorded_paths > 0;
            assert!(
                moved.updated > 0 && guided && moved.restarted.is_none(),
                "{moved:?}"
            );
            let errors = errors_every(&mut render, &truth, 3, 8);
            figure!(
                "{estimator:?} {mode:?}: stale frame 0: {stale:.4}; after the move, every 8 iterations: {errors:?}"
            );
            assert!(
                errors[3] < stale && errors[3] < errors[0],
                "{estimator:?} {mode:?}: the frame did not approach the new pose: stale {stale}, then {errors:?}"
            );
        }
    }
}

/// The harness's same-seed comparison passes on a compensated frame: every backend runs the
/// same move as the CPU (area, thesis and difference modes: compensation, testing and guided
/// photons; local mode: its resets) and agrees with it.
fn every_backend_agrees_with_the_cpu_on_a_compensated_frame(
    name: &str,
    mut other: Box<dyn Backend + Send>,
) {
    let (scene, mut p) = cornell(48, 20_000);
    p.direct_samples = 8;
    let dynamic = MoveParams {
        compensation_passes: 2,
        region_photons: 16_384,
        ..MoveParams::default()
    };
    let run = |backend: &mut dyn Backend, mode: MoveMode| {
        let name = backend.name().to_owned();
        let mut render = Renderer::start(backend, scene.at_frame(0), &p, &dynamic).unwrap();
        for _ in 0..3 {
            render.iteration().unwrap();
        }
        let moved = render.move_to(scene.at_frame(1), mode).unwrap();
        for _ in 0..4 {
            render.iteration().unwrap();
        }
        let image = render.resolve().unwrap();
        let hit_points = render.backend().read_hit_points().unwrap();
        (
            harness::diff::Recording {
                backend: name,
                passes: vec![hit_points],
                steps: vec!["iteration"],
                image,
            },
            moved,
        )
    };
    let modes = [
        MoveMode::Area,
        MoveMode::Thesis,
        MoveMode::Difference,
        MoveMode::Local,
    ];
    for mode in modes {
        let (cpu, cpu_move) = run(&mut CpuBackend::new(), mode);
        let (theirs, other_move) = run(other.as_mut(), mode);
        assert_eq!(
            (cpu_move.updated, cpu_move.direct_corrected),
            (other_move.updated, other_move.direct_corrected),
            "{mode:?}: different hit points reset"
        );
        assert_eq!(
            cpu_move.culled_share, other_move.culled_share,
            "{mode:?}: different difference paths culled"
        );
        assert_eq!(
            cpu_move.culled_share.is_some(),
            mode == MoveMode::Local,
            "{mode:?}: {cpu_move:?}"
        );
        let report = harness::diff::same_seed::compare(&cpu, &theirs, &p, 5);
        figure!(
            "{name} {mode:?}: recorded {} vs {} paths\n{}",
            cpu_move.recorded_paths,
            other_move.recorded_paths,
            harness::diff::same_seed::format(&report)
        );
        assert!(report.agree, "{mode:?}");
    }
}

/// Local mode resets every pixel the tall block newly covers (no eye path met the block there
/// before the move: the box that holds it in every pose finds them), keeps most others, and
/// keeps the direct light of those whose rays stayed clear of the box as it was.
fn a_local_move_resets_the_pixels_the_object_newly_covers() {
    const SIZE: u32 = 64;
    let (scene, p) = cornell(SIZE, 20_000);
    let block = scene.object_index("tall-block").unwrap() as u32;
    let (a, b) = (scene.at_frame(0), scene.at_frame(1));
    let (seen_a, seen_b) = (objects_seen(&a, SIZE), objects_seen(&b, SIZE));
    let newly: Vec<u32> = (0..SIZE * SIZE)
        .filter(|&i| seen_a[i as usize] != Some(block) && seen_b[i as usize] == Some(block))
        .collect();
    assert!(
        newly.len() > 20,
        "the move must uncover a test: {}",
        newly.len()
    );
    let mut backend = CpuBackend::new();
    let mut render = warmed(&mut backend, a, &p, 8);
    let before = render.backend().read_hit_points().unwrap();
    let moved = render.move_to(b, MoveMode::Local).unwrap();
    figure!("{moved:?}; {} pixels newly covered", newly.len());
    let slots = render.backend().read_hit_points().unwrap();
    for &i in &newly {
        let hp = &slots[i as usize];
        assert!(
            hp.flags & hit_flags::UPDATED != 0 && hp.iterations == 0 && hp.n == 0.0,
            "pixel {i} is newly covered but was kept: {hp:?}"
        );
    }
    // Kept slots keep their direct sums and iterations, but where a segment from what their
    // paths reached to the light may cross the block's box in either pose: there the paired
    // correction moves the sum, and a change weighs down its history (fewer iterations, the
    // same mean), while an unchanged sum keeps every iteration.
    let (mut untouched, mut weighed, mut unchanged) = (0, 0, 0);
    for (old, new) in before.iter().zip(&slots) {
        if new.flags & hit_flags::UPDATED != 0 {
            continue;
        }
        if new.flags & hit_flags::DIRECT_MAY_CHANGE == 0 {
            assert_eq!((old.direct, old.iterations), (new.direct, new.iterations));
            untouched += 1;
        } else if (new.direct, new.iterations) == (old.direct, old.iterations) {
            unchanged += 1;
        } else {
            assert!(new.iterations >= 1 && new.iterations <= old.iterations);
            assert!(new.direct.iter().all(|&d| d >= 0.0), "{new:?}");
            weighed += usize::from(new.iterations < old.iterations);
        }
    }
    figure!("{untouched} untouched, {unchanged} unchanged, {weighed} weighed down");
    assert!(
        moved.kept > moved.updated && untouched > 0 && unchanged > 0 && weighed > 0,
        "{moved:?}: {untouched} untouched, {unchanged} unchanged, {weighed} weighed down"
    );
}

/// After a local move, every other iteration the kept slots rest (no eye path, no direct
/// light; their last visible points gather the photons), while the slots the move reset
/// iterate every time; once those hold as many iterations as the kept ones, no slot rests.
/// On every backend.
fn after_a_local_move_kept_slots_rest_until_the_reset_ones_catch_up(
    _: &str,
    mut backend: Box<dyn Backend + Send>,
) {
    use ppm_core::layout::HitPoint;
    const WARM: u32 = 4;
    let (scene, p) = cornell(32, 10_000);
    let reset = |hp: &HitPoint| hp.flags & hit_flags::UPDATED != 0;
    let resting = |hp: &HitPoint| hp.flags & hit_flags::RESTING != 0;
    let check = |backend: &mut dyn Backend| {
        let name = backend.name().to_owned();
        let moves = MoveParams::default();
        let mut render = Renderer::start(backend, scene.at_frame(0), &p, &moves).unwrap();
        for _ in 0..WARM {
            render.iteration().unwrap();
        }
        render.move_to(scene.at_frame(1), MoveMode::Local).unwrap();
        let moved = render.backend().read_hit_points().unwrap();
        let kept = moved.iter().filter(|h| !reset(h)).count();
        assert!(kept > 0 && kept < moved.len(), "{name}: {kept} kept");
        let mut before = moved;
        // Every other iteration the slots that hold more iterations than the reset ones rest;
        // the reset slots (and kept ones whose corrected direct sums were weighed down below
        // that) gain one every time, the others every other time: they meet after 2 * WARM.
        for k in 0..2 * WARM {
            render.iteration().unwrap();
            let after = render.backend().read_hit_points().unwrap();
            for (old, new) in before.iter().zip(&after) {
                if reset(old) {
                    assert_eq!(old.iterations, k, "{name} {k}: {old:?}");
                }
                if k % 2 == 0 && old.iterations > k {
                    assert!(
                        resting(new) && new.emitted > old.emitted,
                        "{name} {k}: {new:?}"
                    );
                    let seen = |h: &HitPoint| (h.position, h.direct, h.iterations);
                    assert_eq!(seen(old), seen(new), "{name} {k}: a resting slot traced");
                } else {
                    assert!(
                        !resting(new) && new.iterations == old.iterations + 1,
                        "{name} {k}: {new:?}"
                    );
                }
            }
            before = after;
        }
        render.iteration().unwrap();
        let caught_up = render.backend().read_hit_points().unwrap();
        assert!(
            caught_up.iter().all(|h| !resting(h)),
            "{name}: a slot still rests"
        );
        assert!(
            caught_up.iter().all(|h| h.iterations == 2 * WARM + 1),
            "{name}"
        );
    };
    check(backend.as_mut());
}

/// Local mode moves several objects at once: both blocks of the Cornell box move, the pixels
/// either newly covers are reset, the frame converges to the path-traced truth of the new
/// pose, and both backends reset the same slots.
fn local_mode_moves_several_objects_at_once(name: &str, mut other: Box<dyn Backend + Send>) {
    use ppm_core::scene::Move;
    const SIZE: u32 = 48;
    let (mut scene, p) = cornell(SIZE, 20_000);
    let short = scene.object_index("short-block").unwrap();
    scene.moves.push(Move {
        object: short,
        translation: glam::Vec3::new(-40.0, 0.0, 60.0),
        rotation: glam::Quat::IDENTITY,
    });
    let (a, b) = (scene.at_frame(0), scene.at_frame(1));
    let (seen_a, seen_b) = (objects_seen(&a, SIZE), objects_seen(&b, SIZE));
    let movers: Vec<u32> = scene.moves.iter().map(|m| m.object as u32).collect();
    let newly: Vec<usize> = (0..(SIZE * SIZE) as usize)
        .filter(|&i| seen_a[i] != seen_b[i] && seen_b[i].is_some_and(|o| movers.contains(&o)))
        .collect();
    let covered = |o: u32| newly.iter().filter(|&&i| seen_b[i] == Some(o)).count();
    assert!(
        movers.iter().all(|&o| covered(o) > 5),
        "each block must newly cover pixels: {newly:?}"
    );
    let compiled = compile_scene(&b, SIZE, SIZE);
    let budget = ReferenceBudget {
        spp: Some(256),
        seconds: None,
    };
    let truth =
        render_reference(&compiled, 99, budget, &mut |_, _| ControlFlow::Continue(())).image;
    let run = |backend: &mut dyn Backend| {
        let name = backend.name().to_owned();
        let moves = MoveParams::default();
        let mut render = Renderer::start(backend, a.clone(), &p, &moves).unwrap();
        for _ in 0..6 {
            render.iteration().unwrap();
        }
        let moved = render.move_to(b.clone(), MoveMode::Local).unwrap();
        assert!(moved.restarted.is_none(), "{name}: {moved:?}");
        let slots = render.backend().read_hit_points().unwrap();
        for &i in &newly {
            assert!(
                slots[i].flags & hit_flags::UPDATED != 0,
                "{name}: pixel {i} is newly covered but was kept"
            );
        }
        let errors = errors_every(&mut render, &truth, 2, 12);
        figure!("{name}: {moved:?}; error every 12 iterations {errors:?}");
        assert!(
            errors[2] < errors[1] && errors[1] < errors[0],
            "{name}: {errors:?}"
        );
        moved
    };
    let cpu = run(&mut CpuBackend::new());
    let theirs = run(other.as_mut());
    assert_eq!(
        (cpu.updated, cpu.direct_corrected),
        (theirs.updated, theirs.direct_corrected),
        "{name}"
    );
}

/// Local mode's culling skips in pose B only the difference paths that store nothing there:
/// after a move of the tall block the statistics are bit for bit those of the same move with
/// every path traced in both poses.
fn culling_leaves_a_local_move_bit_for_bit() {
    let (scene, p) = cornell(64, 20_000);
    let run = |cull_uncrossed: bool| {
        let moves = MoveParams {
            cull_uncrossed,
            ..MoveParams::default()
        };
        let mut backend = CpuBackend::new();
        let mut render = Renderer::start(&mut backend, scene.at_frame(0), &p, &moves).unwrap();
        for _ in 0..4 {
            render.iteration().unwrap();
        }
        let moved = render.move_to(scene.at_frame(1), MoveMode::Local).unwrap();
        let slots = render.backend().read_hit_points().unwrap();
        (moved, render.report().rays.photon, slots)
    };
    let (culled, culled_rays, with) = run(true);
    let (traced, traced_rays, without) = run(false);
    figure!(
        "culled share {:?}; photon rays {culled_rays} with culling, {traced_rays} without",
        culled.culled_share
    );
    let share = culled.culled_share.unwrap();
    assert!(share > 0.0 && share < 1.0, "{culled:?}");
    assert_eq!(traced.culled_share, Some(0.0), "{traced:?}");
    assert!(culled_rays < traced_rays);
    assert_eq!(culled.changed_share, traced.changed_share);
    assert!(
        bytemuck::cast_slice::<_, u8>(&with) == bytemuck::cast_slice::<_, u8>(&without),
        "culling changed a statistic"
    );
}

/// With independent seeds, every backend's locally compensated frames and the CPU's are samples
/// of the same estimator: no tile's radiance, radius, count or direct light differs
/// significantly (Welch's t over runs, Holm-corrected at 1%).
fn every_backend_agrees_with_the_cpu_on_a_locally_compensated_frame_with_independent_seeds(
    name: &str,
    mut other: Box<dyn Backend + Send>,
) {
    use harness::diff::independent;
    const RUNS: u32 = 6;
    let (scene, p) = cornell(32, 10_000);
    let runs = |backend: &mut dyn Backend, first_seed: u32| {
        (first_seed..first_seed + RUNS)
            .map(|seed| {
                let p = RenderParams { seed, ..p.clone() };
                let moves = MoveParams::default();
                let mut render = Renderer::start(backend, scene.at_frame(0), &p, &moves).unwrap();
                for _ in 0..4 {
                    render.iteration().unwrap();
                }
                render.move_to(scene.at_frame(1), MoveMode::Local).unwrap();
                for _ in 0..4 {
                    render.iteration().unwrap();
                }
                let image = render.resolve().unwrap();
                let slots = render.backend().read_hit_points().unwrap();
                independent::tile_means(&image, &slots, &p)
            })
            .collect::<Vec<_>>()
    };
    let cpu = runs(&mut CpuBackend::new(), 0);
    let other = runs(other.as_mut(), 1000);
    let report = independent::compare(("cpu", &cpu), (name, &other), &p, 3);
    figure!("{}", independent::format(&report));
    assert!(report.agree, "{}", independent::format(&report));
}

/// Local mode keeps the pixels whose eye rays crossed the box the tall block sweeps but met
/// the block in neither pose (the floor and wall seen past it), which a test against the box
/// alone would reset, and resets every pixel that saw the block before the move.
fn a_local_move_keeps_the_pixels_that_only_saw_past_the_object() {
    const SIZE: u32 = 64;
    let (scene, p) = cornell(SIZE, 20_000);
    let block = scene.object_index("tall-block").unwrap() as u32;
    let (a, b) = (scene.at_frame(0), scene.at_frame(1));
    let (seen_a, seen_b) = (objects_seen(&a, SIZE), objects_seen(&b, SIZE));
    let compiled = compile_scene(&a, SIZE, SIZE);
    let data = backend_cpu::trace::SceneData::new(&compiled);
    let (a_lo, a_hi) = a.objects[block as usize].bounds();
    let (b_lo, b_hi) = b.objects[block as usize].bounds();
    let (lo, hi) = (a_lo.min(b_lo), a_hi.max(b_hi));
    let crosses_box = |i: usize| {
        let (x, y) = (
            (i as u32 % SIZE) as f32 + 0.5,
            (i as u32 / SIZE) as f32 + 0.5,
        );
        let dir = camera_ray(&compiled.camera, x, y);
        let eye = compiled.camera.eye.into();
        let t = data
            .closest_hit(eye, dir, f32::INFINITY)
            .map_or(f32::INFINITY, |h| h.t);
        ppm_core::geometry::segment_meets_box(eye, dir, t, lo, hi)
    };
    let pixels = 0..(SIZE * SIZE) as usize;
    let past: Vec<usize> = pixels
        .clone()
        .filter(|&i| {
            crosses_box(i)
                && around(i, SIZE, |j| {
                    seen_a[j] != Some(block) && seen_b[j] != Some(block)
                })
        })
        .collect();
    let saw: Vec<usize> = pixels
        .filter(|&i| around(i, SIZE, |j| seen_a[j] == Some(block)))
        .collect();
    assert!(
        past.len() > 20 && saw.len() > 20,
        "{} pixels see past the box, {} see the block",
        past.len(),
        saw.len()
    );
    let mut backend = CpuBackend::new();
    let mut render = warmed(&mut backend, a, &p, 8);
    let moved = render.move_to(b, MoveMode::Local).unwrap();
    figure!(
        "{moved:?}; {} past the block, {} on it",
        past.len(),
        saw.len()
    );
    let slots = render.backend().read_hit_points().unwrap();
    let reset = |i: usize| slots[i].flags & hit_flags::UPDATED != 0;
    assert!(
        past.iter().all(|&i| !reset(i)),
        "reset past the block: {:?}",
        past.iter().filter(|&&i| reset(i)).collect::<Vec<_>>()
    );
    assert!(
        saw.iter().all(|&i| reset(i)),
        "kept on the block: {:?}",
        saw.iter().filter(|&&i| !reset(i)).collect::<Vec<_>>()
    );
}

/// Of 16 eye rays through a 4x4 grid of points in pixel `i`, how many meet `object` in the
/// scene of `compiled` (`data`), following mirrors (wedding-band has no glass).
fn mirrored_paths_meeting(
    compiled: &CompiledScene,
    data: &backend_cpu::trace::SceneData,
    object: u32,
    i: u32,
    depth: u32,
) -> u32 {
    let size = compiled.camera.width;
    let mut met = 0;
    for k in 0..16 {
        let x = (i % size) as f32 + (k % 4) as f32 * 0.25 + 0.125;
        let y = (i / size) as f32 + (k / 4) as f32 * 0.25 + 0.125;
        let mut dir = camera_ray(&compiled.camera, x, y);
        let mut origin: glam::Vec3 = compiled.camera.eye.into();
        for _ in 0..=depth {
            let Some(hit) = data.closest_hit(origin, dir, f32::INFINITY) else {
                break;
            };
            let tri = &data.triangles[hit.triangle as usize];
            if tri.object == object {
                met += 1;
                break;
            }
            if data.materials[tri.material as usize].kind != material_kind::MIRROR {
                break;
            }
            let n = glam::Vec3::from(tri.normal);
            let n = if dir.dot(n) < 0.0 { n } else { -n };
            origin += dir * hit.t + n * 1e-3;
            dir = ppm_core::geometry::reflect(dir, n);
        }
    }
    met
}

/// Through mirrors: after the middle ring of wedding-band moves, local mode resets every
/// pixel a quarter of whose eye paths meet the ring in its new pose (directly, or mirrored
/// by the other rings: at 128x128 two pixels are found only by its probe), and keeps slots
/// whose mirrored paths only crossed the ring's box. Both backends reset the same slots.
fn a_local_move_probes_mirrored_paths_in_the_new_pose(
    name: &str,
    mut other: Box<dyn Backend + Send>,
) {
    const SIZE: u32 = 128;
    let scene = scenes::builtin("wedding-band").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    (p.width, p.height, p.photons_per_pass) = (SIZE, SIZE, 20_000);
    let (a, b) = (scene.at_frame(0), scene.at_frame(1));
    let ring = scene.moves[0].object as u32;
    let compiled_b = compile_scene(&b, SIZE, SIZE);
    let data_b = backend_cpu::trace::SceneData::new(&compiled_b);
    let meets_b: Vec<u32> = (0..SIZE * SIZE)
        .map(|i| mirrored_paths_meeting(&compiled_b, &data_b, ring, i, p.max_eye_depth))
        .collect();
    let run = |backend: &mut dyn Backend| {
        let mut render = Renderer::start(backend, a.clone(), &p, &MoveParams::default()).unwrap();
        for _ in 0..8 {
            render.iteration().unwrap();
        }
        let before = render.backend().read_hit_points().unwrap();
        let moved = render.move_to(b.clone(), MoveMode::Local).unwrap();
        let after = render.backend().read_hit_points().unwrap();
        let reset: Vec<bool> = after
            .iter()
            .map(|hp| hp.flags & hit_flags::UPDATED != 0)
            .collect();
        let chained_kept = before
            .iter()
            .zip(&reset)
            .filter(|(hp, r)| hp.flags & hit_flags::EYE_CHAINED != 0 && !**r)
            .count();
        figure!(
            "{}: {moved:?}; {chained_kept} mirrored slots kept",
            render.backend().name()
        );
        (reset, chained_kept)
    };
    let (cpu, chained_kept) = run(&mut CpuBackend::new());
    let missed: Vec<usize> = (0..meets_b.len())
        .filter(|&i| meets_b[i] >= 4 && !cpu[i])
        .collect();
    let meeting = meets_b.iter().filter(|&&m| m >= 8).count();
    assert!(meeting > 50, "{meeting} pixels meet the ring in pose B");
    assert!(
        missed.is_empty(),
        "kept, yet meet the ring in pose B: {missed:?}"
    );
    assert!(chained_kept > 0, "the probe kept no mirrored slot");
    let (theirs, _) = run(other.as_mut());
    let differ = cpu.iter().zip(&theirs).filter(|(c, o)| c != o).count();
    assert!(
        differ * 1000 <= cpu.len(),
        "{name}: {differ} slots reset on one backend only"
    );
}

/// The paired passes of a move trace both poses with the same random numbers, which must pick
/// the same point of the same light in both: every pose of every built-in scene lists its
/// lights alike, whatever order the rebuilt BVH puts the triangles in.
fn every_pose_lists_the_lights_alike() {
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().unwrap();
        let lights = |t: f32| compile_scene(&scene.at_time(t), 16, 16).lights;
        for t in [0.5, 1.0] {
            assert!(
                lights(0.0) == lights(t),
                "{}: the lights of the pose at {t} differ from frame 0's",
                builtin.name
            );
        }
    }
}

fn main() -> ExitCode {
    Suite::new()
        .test("a_negative_then_positive_region_pass_in_an_unchanged_scene_leaves_the_image", a_negative_then_positive_region_pass_in_an_unchanged_scene_leaves_the_image)
        .test("a_move_to_the_same_pose_leaves_the_statistics", a_move_to_the_same_pose_leaves_the_statistics)
        .test("clamps_hold_when_negative_photons_outnumber_the_count", clamps_hold_when_negative_photons_outnumber_the_count)
        .test("after_a_move_compensating_modes_converge_towards_the_new_pose", after_a_move_compensating_modes_converge_towards_the_new_pose)
        .against_the_cpu("every_backend_agrees_with_the_cpu_on_a_compensated_frame", every_backend_agrees_with_the_cpu_on_a_compensated_frame)
        .test("a_local_move_resets_the_pixels_the_object_newly_covers", a_local_move_resets_the_pixels_the_object_newly_covers)
        .on_every_backend("after_a_local_move_kept_slots_rest_until_the_reset_ones_catch_up", after_a_local_move_kept_slots_rest_until_the_reset_ones_catch_up)
        .against_the_cpu("local_mode_moves_several_objects_at_once", local_mode_moves_several_objects_at_once)
        .test("culling_leaves_a_local_move_bit_for_bit", culling_leaves_a_local_move_bit_for_bit)
        .against_the_cpu("every_backend_agrees_with_the_cpu_on_a_locally_compensated_frame_with_independent_seeds", every_backend_agrees_with_the_cpu_on_a_locally_compensated_frame_with_independent_seeds)
        .test("a_local_move_keeps_the_pixels_that_only_saw_past_the_object", a_local_move_keeps_the_pixels_that_only_saw_past_the_object)
        .against_the_cpu("a_local_move_probes_mirrored_paths_in_the_new_pose", a_local_move_probes_mirrored_paths_in_the_new_pose)
        .test("every_pose_lists_the_lights_alike", every_pose_lists_the_lights_alike)
        .run()
}
