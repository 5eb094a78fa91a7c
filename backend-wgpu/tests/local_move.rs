//! local_move.wgsl's per-slot decisions and screen_cover.wgsl's marking reproduce
//! ppm_core's on random cases: the segment test between boxes (`segments_may_meet`), a slot's
//! preparation in pose A (`prepare_slot`: its correction disc and whether its direct light
//! may change), what a move may do to what it sees (`view_test`), and the pixels a moved
//! triangle may cover (`covered_pixels`). Each decision is the same, bit for bit: a differing
//! one would reset or correct another slot than the CPU backend does.

use backend_wgpu::layout::{CoverCase, CoverParams, MoveDecisionCase};
use backend_wgpu::{GpuContext, WgpuBackend};
use glam::Vec3;
use ppm_core::compile::gpu_camera;
use ppm_core::eye_path::EyePathSettings;
use ppm_core::layout::{GpuBounds, GpuCamera, HitPoint, hit_flags};
use ppm_core::local_move::{LocalMove, View, prepare_slot, view_test};
use ppm_core::reach::{Aabb, segments_may_meet};
use ppm_core::rng::{PassKind, StreamKey};
use ppm_core::scene::Camera;
use ppm_core::screen_cover::covered_pixels;
use std::process::ExitCode;
use test_support::{Need, Suite, figure};

/// Units in the last place allowed between the correction discs: a square root and a clamp
/// of a distance that WGSL may sum with a fused multiply-add.
const ULPS: u32 = 4;

fn ulps_apart(a: f32, b: f32) -> u32 {
    if a == b {
        return 0;
    }
    if a.is_nan() || b.is_nan() || a.signum() != b.signum() {
        return u32::MAX;
    }
    a.to_bits().abs_diff(b.to_bits())
}

/// The random numbers of case `case`.
fn stream(seed: u32, case: u32) -> StreamKey {
    StreamKey {
        seed,
        kind: PassKind::Photon,
        pass_index: 0,
        path: case,
    }
}

/// A point of `[0, scale]^3` from dimensions `d` to `d + 2` of `k`.
fn point(k: &StreamKey, d: u32, scale: f32) -> Vec3 {
    Vec3::new(k.uniform(d), k.uniform(d + 1), k.uniform(d + 2)) * scale
}

/// A box within `[0, 13]^3` from dimensions `d` to `d + 5` of `k`.
fn random_box(k: &StreamKey, d: u32) -> Aabb {
    let lo = point(k, d, 10.0);
    Aabb::new(lo, lo + point(k, d + 3, 3.0))
}

fn bounds(b: &Aabb) -> GpuBounds {
    GpuBounds::new(b.lo, b.hi)
}

/// Case `i`: the slot's box (the box of nothing one case in eight), also a segment's start, the segment's end and
/// target boxes, and a move of one or two objects with lights filling the case's boxes.
fn decision_case(i: u32) -> (MoveDecisionCase, LocalMove, HitPoint, Aabb) {
    let k = stream(21, i);
    let slot = match k.bits(100) % 8 {
        0 => Aabb::new(Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX)),
        // Wide, so that moved boxes in pose B overlap it often.
        _ => {
            let lo = point(&k, 0, 10.0);
            Aabb::new(lo, lo + point(&k, 3, 8.0))
        }
    };
    let objects = 1 + k.bits(101) % 2;
    let lights = 1 + k.bits(102) % (5 - 2 * objects);
    let moved: Vec<Aabb> = (0..2 * objects)
        .map(|j| random_box(&k, 20 + 6 * j))
        .collect();
    let light_boxes: Vec<Aabb> = (0..lights).map(|j| random_box(&k, 50 + 6 * j)).collect();
    let flags = k.bits(103)
        & (hit_flags::VALID
            | hit_flags::UPDATED
            | hit_flags::RESTING
            | hit_flags::DIRECT_MAY_CHANGE);
    // Paths that bounced in three cases of four, and met the moved group in one of four.
    let chained = match k.bits(109) % 4 {
        0 => 0,
        _ => hit_flags::EYE_CHAINED,
    };
    let group = 1 << (k.bits(105) % 4);
    let met = match k.bits(110) % 4 {
        0 => group,
        _ => k.bits(104) & 0b1111 & !group,
    };
    let hp = HitPoint {
        position: point(&k, 80, 13.0).into(),
        eye_met: met,
        flags: flags | chained,
        ..HitPoint::empty(i)
    };
    let request = LocalMove {
        objects: (0..objects).collect(),
        groups: group,
        before: moved[..objects as usize].to_vec(),
        after: moved[objects as usize..].to_vec(),
        lights: light_boxes,
        seed: 0,
        paths: EyePathSettings {
            max_depth: 1,
            ray_epsilon: 0.0,
            sample_lights: false,
        },
        r2_initial: 1.0,
        r2_floor: 0.01 + k.uniform(106),
        widest: [1.0, 2.0, 4.0][k.bits(107) as usize % 3],
        direct_samples: 1,
    };
    let mut boxes = [GpuBounds::EMPTY; 8];
    boxes[0] = bounds(&slot);
    boxes[1] = bounds(&random_box(&k, 110));
    boxes[2] = bounds(&random_box(&k, 116));
    for (b, g) in boxes[3..].iter_mut().zip(request.boxes()) {
        *b = g;
    }
    let case = MoveDecisionCase {
        boxes,
        position: hp.position,
        // Covered in half the cases, where view_test's distances decide.
        covered: k.bits(108) % 2,
        eye: (point(&k, 90, 30.0) - Vec3::splat(8.0)).into(),
        eye_met: hp.eye_met,
        flags: hp.flags,
        groups: request.groups,
        r2_floor: request.r2_floor,
        widest: request.widest,
        objects,
        lights,
        _pad0: 0,
        _pad1: 0,
    };
    (case, request, hp, slot)
}

fn the_wgsl_decisions_of_a_local_move_are_the_core_s() {
    let gpu = WgpuBackend::new().unwrap();
    let cases: Vec<_> = (0..4000).map(decision_case).collect();
    let inputs: Vec<MoveDecisionCase> = cases.iter().map(|c| c.0).collect();
    let got = gpu.local_move_vectors(&inputs).unwrap();
    assert_eq!(got.len(), cases.len());
    let (mut meets, mut may_change, mut views) = (0, 0, [0; 3]);
    for ((case, request, hp, slot), wgsl) in cases.iter().zip(&got) {
        let to = Aabb::new(case.boxes[1].min.into(), case.boxes[1].max.into());
        let target = Aabb::new(case.boxes[2].min.into(), case.boxes[2].max.into());
        let meet = segments_may_meet(slot, &to, &target);
        assert_eq!(wgsl.meets, u32::from(meet), "segments: {case:?}");
        let mut prepared = *hp;
        prepare_slot(&mut prepared, slot, request, &request.moved());
        assert_eq!(wgsl.flags, prepared.flags, "prepare_slot's flags: {case:?}");
        assert!(
            ulps_apart(wgsl.correction_r2, prepared.correction_r2) <= ULPS,
            "correction_r2: WGSL {}, core {}: {case:?}",
            wgsl.correction_r2,
            prepared.correction_r2
        );
        let eye = Vec3::from(case.eye);
        let view = view_test(
            hp,
            slot,
            case.covered != 0,
            (eye, request.nearest_after(eye)),
            request,
        );
        let view = match view {
            View::Changes => 0,
            View::Probe => 1,
            View::Kept => 2,
        };
        assert_eq!(wgsl.view, view, "view_test: {case:?}");
        meets += usize::from(meet);
        may_change += usize::from(prepared.flags & hit_flags::DIRECT_MAY_CHANGE != 0);
        views[view as usize] += 1;
    }
    figure!(
        "{} cases: {meets} segments met, {may_change} slots' direct light may change, views (changes, probe, kept) {views:?}",
        cases.len()
    );
    // The cases reach every answer.
    let n = cases.len();
    assert!(meets > n / 20 && meets < n * 19 / 20, "{meets} of {n} met");
    assert!(
        may_change > n / 10 && may_change < n * 9 / 10,
        "{may_change} of {n}"
    );
    assert!(views.iter().all(|&v| v > n / 40), "{views:?}");
}

/// Case `i`: a camera over an image of at most 16x16 pixels, and a triangle in front of it,
/// partly off the image, behind the eye, seen edge-on or tiny.
fn cover_case(i: u32) -> (CoverCase, GpuCamera) {
    let k = stream(22, i);
    let (width, height) = (4 + k.bits(0) % 13, 4 + k.bits(1) % 13);
    let camera = Camera {
        eye: point(&k, 2, 2.0) + Vec3::new(0.0, 0.0, 8.0),
        look_at: point(&k, 5, 1.0),
        up: Vec3::Y,
        fov_deg: 30.0 + 40.0 * k.uniform(8),
        width,
        height,
    };
    let gpu = gpu_camera(&camera, width, height);
    let centre = point(&k, 10, 4.0) - Vec3::splat(2.0);
    let size = match k.bits(9) % 4 {
        0 => 0.05,
        1 => 6.0,
        _ => 2.0,
    };
    let mut v = [0, 1, 2].map(|j| centre + (point(&k, 20 + 3 * j, 2.0) - Vec3::ONE) * size);
    match k.bits(13) % 8 {
        // Edge-on: the third vertex on the line of the first two.
        0 => v[2] = v[0] + (v[1] - v[0]) * 0.3,
        // A vertex behind the eye.
        1 => v[1] = camera.eye + (camera.eye - camera.look_at),
        _ => {}
    }
    let case = CoverCase {
        cover: CoverParams::new(&gpu),
        v0: v[0].into(),
        v1: v[1].into(),
        v2: v[2].into(),
        ..Default::default()
    };
    (case, gpu)
}

fn the_wgsl_screen_cover_marks_the_core_s_pixels() {
    let gpu = WgpuBackend::new().unwrap();
    let cases: Vec<(CoverCase, GpuCamera)> = (0..1500).map(cover_case).collect();
    let inputs: Vec<CoverCase> = cases.iter().map(|c| c.0).collect();
    let got = gpu.screen_cover_vectors(&inputs).unwrap();
    let (mut marked, mut everything, mut none) = (0, 0, 0);
    for ((case, camera), wgsl) in cases.iter().zip(&got) {
        let expected = covered_pixels(camera, &[[case.v0, case.v1, case.v2].map(Vec3::from)]);
        let bits: Vec<bool> = (0..expected.len())
            .map(|p| wgsl.words[p / 32] >> (p % 32) & 1 != 0)
            .collect();
        assert_eq!(bits, expected, "{case:?}");
        let count = expected.iter().filter(|&&b| b).count();
        marked += usize::from(count > 0 && count < expected.len());
        everything += usize::from(count == expected.len());
        none += usize::from(count == 0);
    }
    figure!(
        "{} triangles: {marked} mark some pixels, {everything} all, {none} none",
        cases.len()
    );
    assert!(marked > 300 && everything > 100 && none > 30);
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "the_wgsl_decisions_of_a_local_move_are_the_core_s",
            the_wgsl_decisions_of_a_local_move_are_the_core_s,
        )
        .test_needing(
            &[&adapter],
            "the_wgsl_screen_cover_marks_the_core_s_pixels",
            the_wgsl_screen_cover_marks_the_core_s_pixels,
        )
        .run()
}
