//! A focus eye pass and the direct light after it walk only the slots behind (focus.rs): each
//! of those ends bit for bit as a pass over every slot leaves it, each slot ahead rests as it
//! was, and a pass with no slot behind traces nothing. A second focus pass at the same count
//! walks the first one's list again, and ends as one that lists the slots anew.

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::compile::compile_scene;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, HitPoint, direct_accumulate, eye_flags, hit_flags,
};
use ppm_core::passes::{DirectLight, EyePass, EyeStats, ReadBack, SceneUpload};
use std::process::ExitCode;
use test_support::{Need, Suite};

const EYE: EyePassParams = EyePassParams {
    seed: 7,
    spp: 2,
    max_depth: 4,
    iteration: 0,
    r2_initial: 1.0,
    ray_epsilon: 1e-3,
    flags: eye_flags::JITTER | eye_flags::RECORD_BOUNDS | eye_flags::SAMPLE_LIGHTS,
    rest_at: 0,
};

const DIRECT: DirectLightParams = DirectLightParams {
    seed: 7,
    samples: 1,
    iteration: 0,
    ray_epsilon: 1e-3,
    accumulate: direct_accumulate::ADD,
    _pad0: 0,
    _pad1: 0,
    _pad2: 0,
};

/// An eye pass with `flags` added at `iteration`, and the direct light after it: the slots
/// after, and the eye pass's stats.
fn iteration(
    backend: &mut WgpuBackend,
    flags: u32,
    rest_at: u32,
    iteration: u32,
) -> (Vec<HitPoint>, EyeStats) {
    let eye = EyePassParams {
        flags: EYE.flags | flags,
        rest_at,
        iteration,
        ..EYE
    };
    let stats = backend.eye_pass(&eye).unwrap();
    let direct = DirectLightParams {
        iteration,
        ..DIRECT
    };
    backend.direct_light(&direct).unwrap();
    (backend.read_hit_points().unwrap(), stats)
}

fn bytes(hp: &HitPoint) -> &[u8] {
    bytemuck::bytes_of(hp)
}

/// A backend with two iterations of cornell-box at 24x20, and its slots.
fn two_iterations() -> (WgpuBackend, Vec<HitPoint>) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut backend = WgpuBackend::new().unwrap();
    backend.load_scene(&compile_scene(&scene, 24, 20)).unwrap();
    iteration(&mut backend, 0, 0, 0);
    let (slots, _) = iteration(&mut backend, eye_flags::KEEP_STATISTICS, 0, 1);
    (backend, slots)
}

fn a_focus_pass_leaves_the_slots_behind_as_a_whole_pass_and_rests_the_others() {
    let (mut backend, mut start) = two_iterations();
    // One slot in seven falls behind, as a move's resets scatter them.
    for hp in start.iter_mut().step_by(7) {
        hp.iterations = 1;
    }
    let keep = eye_flags::KEEP_STATISTICS;
    backend.write_hit_points(&start).unwrap();
    let (whole, whole_stats) = iteration(&mut backend, keep, 0, 2);
    backend.write_hit_points(&start).unwrap();
    let (focused, stats) = iteration(&mut backend, keep | eye_flags::FOCUS, 2, 2);
    let mut behind = 0;
    for ((before, after), whole) in start.iter().zip(&focused).zip(&whole) {
        if before.iterations < 2 {
            behind += 1;
            assert_eq!(bytes(after), bytes(whole), "a slot behind differs");
        } else {
            let rested = HitPoint {
                flags: before.flags | hit_flags::RESTING,
                ..*before
            };
            assert_eq!(bytes(after), bytes(&rested), "a resting slot changed");
        }
    }
    assert_eq!(behind, start.len().div_ceil(7));
    let valid = |s: &[HitPoint]| s.iter().filter(|h| h.flags & hit_flags::VALID != 0).count();
    assert_eq!(stats.hit_points, valid(&focused) as u64);
    assert!(stats.rays > 0 && stats.rays < whole_stats.rays, "{stats:?}");

    // Every slot ahead: nothing traced, nothing lit.
    let (rested, stats) = iteration(&mut backend, keep | eye_flags::FOCUS, 0, 3);
    assert_eq!(stats.rays, 0);
    assert_eq!(stats.hit_points, valid(&focused) as u64);
    for (before, after) in focused.iter().zip(&rested) {
        assert_eq!(before.direct, after.direct);
        assert_eq!(before.iterations, after.iterations);
    }
}

/// Two focus passes at the same count, the second walking the first one's list (the
/// catch-up's passes of one iteration), leave every slot and count as when the second lists
/// the slots anew: a slot one behind traces in the first and rests in the second.
fn a_list_walked_again_rests_the_slots_that_caught_up() {
    let (mut backend, mut start) = two_iterations();
    // Slots two behind and slots one behind a rest at three direct samples; the others ahead.
    for (i, hp) in start.iter_mut().enumerate() {
        hp.iterations = match (i % 7, i % 5) {
            (0, _) => 1,
            (_, 0) => 2,
            _ => 5,
        };
    }
    let focus = eye_flags::KEEP_STATISTICS | eye_flags::FOCUS;
    backend.write_hit_points(&start).unwrap();
    iteration(&mut backend, focus, 3, 2);
    let (again, again_stats) = iteration(&mut backend, focus, 3, 3);
    backend.write_hit_points(&start).unwrap();
    let (first, _) = iteration(&mut backend, focus, 3, 2);
    // Written back, the slots are the same and the list is gone: the next pass lists anew.
    backend.write_hit_points(&first).unwrap();
    let (anew, anew_stats) = iteration(&mut backend, focus, 3, 3);
    for (a, b) in again.iter().zip(&anew) {
        assert_eq!(bytes(a), bytes(b), "a slot differs");
    }
    assert_eq!(
        (again_stats.rays, again_stats.hit_points),
        (anew_stats.rays, anew_stats.hit_points)
    );
    // The slots one behind caught up in the first pass, and rest as they were in the second.
    let mut caught_up = 0;
    for ((start, first), again) in start.iter().zip(&first).zip(&again) {
        if start.iterations == 2 && first.iterations == 3 {
            caught_up += 1;
            let rested = HitPoint {
                flags: first.flags | hit_flags::RESTING,
                ..*first
            };
            assert_eq!(
                bytes(again),
                bytes(&rested),
                "a slot that caught up changed"
            );
        }
    }
    assert!(caught_up > 0);
    assert!(again_stats.rays > 0);
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "a_focus_pass_leaves_the_slots_behind_as_a_whole_pass_and_rests_the_others",
            a_focus_pass_leaves_the_slots_behind_as_a_whole_pass_and_rests_the_others,
        )
        .test_needing(
            &[&adapter],
            "a_list_walked_again_rests_the_slots_that_caught_up",
            a_list_walked_again_rests_the_slots_that_caught_up,
        )
        .run()
}
