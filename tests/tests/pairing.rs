//! A local move's correction pairs each path's deposits in its two poses
//! ([`ppm_core::update::pairing`]) on both backends: its variance counts what a path's deposits
//! leave net (nothing for a pair that cancels), so a move that changes few paths costs the
//! kept slots little history, where counting each deposit alone gave up much of it.
//!
//! The scene is the furnace with a mover of two tiny triangles at the corners of a large box
//! ([`tests::furnace_with_mover`]): most correction paths cross the box without meeting the
//! mover, so they are the same in both poses and their deposits cancel.

use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use glam::Vec3;
use harness::driver::Renderer;
use ppm_core::layout::{HitPoint, Photon, hit_flags};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::{Backend, ReadBack};
use ppm_core::update::pairing::pose_a_partners;
use std::process::ExitCode;
use tests::furnace_with_mover;
use tests::{BackendTrials, Suite, figure};

/// Eight iterations of the furnace whose small mover most paths cross the box of without
/// meeting it, then its small local move, pairing deposits or not; returns the slots before
/// the move.
fn small_move(backend: &mut dyn Backend, pair_deposits: bool) -> Vec<HitPoint> {
    let scene = furnace_with_mover(
        Vec3::new(0.2, -0.9, 0.2),
        Vec3::new(0.9, -0.2, 0.9),
        Vec3::new(-0.02, 0.0, 0.0),
    );
    let mut p = RenderParams::for_scene(&scene);
    (p.width, p.height, p.photons_per_pass) = (16, 16, 20_000);
    let moves = MoveParams {
        pair_deposits,
        ..MoveParams::default()
    };
    let mut render = Renderer::start(backend, scene.at_frame(0), &p, &moves).unwrap();
    for _ in 0..8 {
        render.iteration().unwrap();
    }
    let before = render.backend().read_hit_points().unwrap();
    let moved = render.move_to(scene.at_frame(1), MoveMode::Local).unwrap();
    assert!(moved.restarted.is_none(), "{moved:?}");
    before
}

/// The share of their history the kept slots keep through [`small_move`] (their summed
/// `emitted` after over before), pairing deposits or not.
fn history_kept(backend: &mut dyn Backend, pair_deposits: bool) -> f64 {
    let before = small_move(backend, pair_deposits);
    let after = backend.read_hit_points().unwrap();
    let kept = |h: &&HitPoint| h.is_valid() && h.flags & hit_flags::UPDATED == 0;
    let sum = |slots: &[HitPoint], pick: &[bool]| -> f64 {
        slots
            .iter()
            .zip(pick)
            .filter(|(_, k)| **k)
            .map(|(h, _)| f64::from(h.emitted))
            .sum()
    };
    let pick: Vec<bool> = after.iter().map(|h| kept(&h)).collect();
    assert!(pick.iter().filter(|k| **k).count() > 100, "few slots kept");
    sum(&after, &pick) / sum(&before, &pick)
}

/// Paths that cross the mover's box without meeting it come out the same in both poses, so
/// their pairs cancel and count nothing (`Partner::cancels`): the kept slots give up less
/// than a tenth of the history they gave up counted deposit by deposit (0.011 against 0.182
/// when written). Every backend pairs as the CPU backend does.
fn paired_deposits_keep_the_history_a_small_move_did_not_change(
    name: &str,
    mut backend: Box<dyn Backend + Send>,
) {
    let paired = history_kept(backend.as_mut(), true);
    let alone = history_kept(backend.as_mut(), false);
    figure!("{name}: history kept {paired:.4} paired, {alone:.4} deposit by deposit");
    assert!(
        1.0 - paired < 0.1 * (1.0 - alone),
        "{name}: paired deposits kept {paired}, alone {alone}"
    );
    let mut cpu = CpuBackend::new();
    let (cpu_paired, cpu_alone) = (history_kept(&mut cpu, true), history_kept(&mut cpu, false));
    assert!(
        (paired - cpu_paired).abs() < 0.01 && (alone - cpu_alone).abs() < 0.01,
        "{name} kept {paired} and {alone}, the CPU {cpu_paired} and {cpu_alone}"
    );
}

/// The wgpu backend files a correction's two poses in one map, and leaves out both deposits
/// of each pair that cancels, as the CPU's map does: the map holds every other deposit the
/// poses made, each once. Pose A's deposits are its own: their power is negative.
fn the_joined_map_leaves_out_both_deposits_of_each_pair_that_cancels() {
    let mut backend = WgpuBackend::new().unwrap();
    assert!(
        MoveParams::default().pair_deposits,
        "local mode pairs by default"
    );
    small_move(&mut backend, true);
    // In path order by rank, which both poses share: each pose stays in path order.
    let (pose_a, pose_b): (Vec<Photon>, Vec<Photon>) = backend
        .read_photons()
        .unwrap()
        .into_iter()
        .partition(|d| d.power[0] < 0.0);
    let key = |d: &Photon| {
        let bits = |v: [f32; 3]| v.map(f32::to_bits);
        (bits(d.position), bits(d.power), d.normal_oct)
    };
    let mut expected: Vec<_> = pose_a.iter().chain(&pose_b).map(key).collect();
    // ppm-core's own pairing rule says which pairs cancel; a pair's pose-A deposit is the one
    // of its path at the same place.
    let mut cancelled = Vec::new();
    for (b, pair) in pose_b.iter().zip(pose_a_partners(&pose_a, &pose_b)) {
        if pair.is_some_and(|pair| pair.cancels(b)) {
            let first = pose_a.partition_point(|a| a.path < b.path);
            let a = pose_a[first..]
                .iter()
                .find(|a| a.position == b.position)
                .filter(|a| a.path == b.path)
                .expect("a pair that cancels has its pose-A deposit");
            cancelled.extend([key(a), key(b)]);
        }
    }
    for gone in &cancelled {
        let at = expected.iter().position(|k| k == gone).unwrap();
        expected.swap_remove(at);
    }
    let mut filed: Vec<_> = backend
        .map_order()
        .unwrap()
        .iter()
        .map(|(_, _, g)| {
            (
                g.position.map(f32::to_bits),
                g.power.map(f32::to_bits),
                g.normal_oct,
            )
        })
        .collect();
    figure!(
        "wgpu: {} deposits in pose A, {} in pose B, {} left out, {} filed",
        pose_a.len(),
        pose_b.len(),
        cancelled.len(),
        filed.len()
    );
    assert!(
        cancelled.len() > pose_b.len() / 2,
        "most paths cross the box without meeting the mover: {} of {} cancel",
        cancelled.len() / 2,
        pose_b.len()
    );
    expected.sort_unstable();
    filed.sort_unstable();
    assert!(
        expected == filed,
        "the map must hold the deposits but the pairs that cancel"
    );
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "paired_deposits_keep_the_history_a_small_move_did_not_change",
            paired_deposits_keep_the_history_a_small_move_did_not_change,
        )
        .test_needing(
            &[tests::wgpu()],
            "the_joined_map_leaves_out_both_deposits_of_each_pair_that_cancels",
            the_joined_map_leaves_out_both_deposits_of_each_pair_that_cancels,
        )
        .run()
}
