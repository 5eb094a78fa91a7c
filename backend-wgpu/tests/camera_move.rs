//! camera_move.wgsl's `inherit_slot` reproduces ppm_core's on chosen cases over one old
//! view (a plane seen square-on, each earlier slot's statistics its own): a camera that did
//! not move, pans of half a pixel and less, dollies both ways, an edge (an earlier slot
//! whose paths met two objects), a pixel at the border, textured, coated and chained
//! materials, another object or normal, and a point behind the earlier camera, with one
//! and two slots per pixel. Each slot inherits or not as on the CPU, and what it inherits
//! agrees within rounding; its `on_an_edge` finds the same edges of a new view (another
//! object, a crease, the void, a reflection, a coated patch, a step) as ppm_core's; a camera
//! move's passes refuse to run out of order.

use backend_wgpu::layout::{InheritCase, InheritOutcome};
use backend_wgpu::{GpuContext, WgpuBackend};
use glam::Vec3;
use ppm_core::camera_move::{CameraMove, inherit_slot, on_an_edge};
use ppm_core::compile::{compile_scene, gpu_camera};
use ppm_core::eye_path::camera_segment;
use ppm_core::layout::{
    EyePassParams, GpuBounds, GpuCamera, GpuMaterial, HitPoint, hit_flags, material_kind,
};
use ppm_core::passes::{BackendError, EyePass, LocalMoves, SceneUpload};
use ppm_core::scene::Camera;
use std::process::ExitCode;
use test_support::{Need, Suite, figure};

/// Pixels a side of the old view.
const SIZE: u32 = 16;
/// The old view's object, whose group its slots' paths met.
const OBJECT: u32 = 7;

/// Relative difference allowed between what the two sides inherit: each field is a handful
/// of weighted sums of four sources (eight with two slots a pixel) whose bilinear shares
/// come from a projection, a subtraction of nearby pixel coordinates (which loses about
/// five bits at 16 pixels) and a footprint ratio; WGSL may fuse multiplies and adds and
/// divide within 2.5 ulps. 1e-4 is a hundred times that, and far below any change of rule.
const RELATIVE: f32 = 1e-4;

/// A camera at `eye` looking down -z at `(at, 0)` over `SIZE` x `SIZE` pixels.
fn camera(eye: Vec3, at: Vec3) -> GpuCamera {
    let c = Camera {
        eye,
        look_at: at,
        up: Vec3::Y,
        fov_deg: 40.0,
        width: SIZE,
        height: SIZE,
    };
    gpu_camera(&c, SIZE, SIZE)
}

/// Where `camera`'s ray through point `jitter` of `pixel` meets the plane z = 0.
fn on_plane(camera: &GpuCamera, pixel: u32, jitter: (f32, f32)) -> Vec3 {
    let (eye, dir) = camera_segment(camera, pixel, jitter);
    eye + dir * (-eye.z / dir.z)
}

/// The old view: `spp` slots per pixel of `camera`, each with statistics of its own (so
/// that the weights matter), one slot's paths having met another object too (an edge).
fn old_view(camera: &GpuCamera, spp: u32, edge: u32) -> (Vec<HitPoint>, Vec<GpuBounds>) {
    let slots = SIZE * SIZE * spp;
    let slot = |i: u32| {
        let pixel = i / spp;
        let jitter = (0.3 + 0.4 * (i % spp) as f32, 0.5);
        let iterations = 150 + 7 * (i % 6);
        let f = |k: u32, step: f32| 1.0 + step * (i % k) as f32;
        HitPoint {
            position: on_plane(camera, pixel, jitter).into(),
            normal: [0.0, 0.0, 1.0],
            material: 0,
            throughput: [1.0; 3],
            r2: 1e-4 * f(3, 0.1),
            tau: (Vec3::new(3e-3, 2e-3, 1e-3) * f(5, 0.05)).into(),
            n: 400.0 + 10.0 * (i % 4) as f32,
            discounted: 50.0 * (i % 2) as f32,
            direct: (Vec3::new(0.5, 0.25, 0.1) * iterations as f32 * f(7, 0.02)).into(),
            emitted: 1e6,
            iterations,
            flags: hit_flags::VALID | hit_flags::FRONT | (OBJECT << hit_flags::OBJECT_SHIFT),
            eye_met: 1 << OBJECT | if pixel == edge { 1 << 3 } else { 0 },
            ..HitPoint::empty(pixel)
        }
    };
    let before: Vec<HitPoint> = (0..slots).map(slot).collect();
    let bounds = before
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let p = Vec3::from(h.position);
            GpuBounds::new(p - Vec3::splat(0.1 * (i % 4) as f32), p + Vec3::Y)
        })
        .collect();
    (before, bounds)
}

/// The materials the cases name: white, textured and coated.
fn materials() -> Vec<GpuMaterial> {
    let white = GpuMaterial {
        albedo: [0.5; 3],
        kind: material_kind::DIFFUSE,
        ..GpuMaterial::default()
    };
    vec![
        white,
        GpuMaterial {
            texture: 1,
            ..white
        },
        GpuMaterial {
            kind: material_kind::COATED,
            ..white
        },
    ]
}

/// A case: its name, whether the core's slot inherits, and the input.
type Case = (&'static str, bool, InheritCase);

/// A fresh slot of `after`'s pixel `(x, y)` through point `jitter`, on the plane, edited.
fn case(
    name: &'static str,
    inherits: bool,
    (before, after, spp): (&GpuCamera, &GpuCamera, u32),
    (x, y, jitter): (u32, u32, (f32, f32)),
    edit: impl Fn(&mut HitPoint),
) -> Case {
    let pixel = y * SIZE + x;
    let mut slot = HitPoint {
        position: on_plane(after, pixel, jitter).into(),
        normal: [0.0, 0.0, 1.0],
        material: 0,
        throughput: [1.0; 3],
        r2: 4e-4,
        flags: hit_flags::VALID | hit_flags::FRONT | (OBJECT << hit_flags::OBJECT_SHIFT),
        eye_met: 1 << OBJECT,
        ..HitPoint::empty(pixel)
    };
    edit(&mut slot);
    let p = Vec3::from(slot.position);
    let request = CameraMove {
        before: *before,
        after: *after,
        spp,
    };
    let input = InheritCase {
        slot,
        bounds: GpuBounds::new(p, p),
        request: request.params(),
    };
    (name, inherits, input)
}

/// The cases over a view of one slot per pixel whose pixel `edge` saw an edge.
fn single_sample_cases(edge: (u32, u32)) -> Vec<Case> {
    let near = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    // A pixel's side on the plane: the pans below are fractions of it.
    let side = 2.0 * 5.0 * Vec3::from(near.up).length() / SIZE as f32;
    let panned = |px: f32, py: f32| {
        let by = Vec3::new(px * side, py * side, 0.0);
        camera(Vec3::new(0.0, 0.0, 5.0) + by, by)
    };
    let same = (&near, &near, 1);
    let half = panned(0.5, 0.0);
    let some = panned(0.3, -0.2);
    let farther = camera(Vec3::new(0.0, 0.0, 5.5), Vec3::ZERO);
    let nearer = camera(Vec3::new(0.0, 0.0, 4.6), Vec3::ZERO);
    let behind = camera(Vec3::new(0.0, 0.0, 12.0), Vec3::ZERO);
    let centre = (0.5, 0.5);
    let (ex, ey) = edge;
    vec![
        case("unmoved camera", true, same, (5, 7, centre), |_| {}),
        case(
            "unmoved, off centre",
            true,
            same,
            (9, 4, (0.2, 0.8)),
            |_| {},
        ),
        case(
            "unmoved, at the left border",
            true,
            same,
            (0, 6, (0.7, 0.4)),
            |_| {},
        ),
        case(
            "half-pixel pan",
            true,
            (&near, &half, 1),
            (6, 8, (0.3, 0.6)),
            |_| {},
        ),
        case(
            "oblique pan",
            true,
            (&near, &some, 1),
            (10, 3, (0.6, 0.3)),
            |_| {},
        ),
        case(
            "dolly out",
            true,
            (&near, &farther, 1),
            (8, 9, (0.4, 0.5)),
            |_| {},
        ),
        case(
            "dolly in",
            true,
            (&near, &nearer, 1),
            (4, 11, (0.5, 0.2)),
            |_| {},
        ),
        case("edge", false, same, (ex, ey, centre), |_| {}),
        case(
            "beside an edge",
            false,
            (&near, &half, 1),
            (ex - 1, ey, (0.5, 0.5)),
            |_| {},
        ),
        case(
            "pan past the border",
            false,
            (&near, &half, 1),
            (SIZE - 1, 5, centre),
            |_| {},
        ),
        case("textured", false, same, (5, 7, centre), |h| h.material = 1),
        case("coated", false, same, (5, 7, centre), |h| h.material = 2),
        case("chained", false, same, (5, 7, centre), |h| {
            h.flags |= hit_flags::EYE_CHAINED
        }),
        case("escaped", false, same, (5, 7, centre), |h| {
            h.flags &= !hit_flags::VALID
        }),
        case("another object", false, same, (5, 7, centre), |h| {
            h.flags ^= 1 << hit_flags::OBJECT_SHIFT
        }),
        case("another normal", false, same, (5, 7, centre), |h| {
            h.normal = [0.0, 0.6, 0.8]
        }),
        case(
            "far from the old points",
            false,
            same,
            (5, 7, centre),
            |h| h.position[2] = 2.0,
        ),
        case(
            "behind the old camera",
            false,
            (&near, &behind, 1),
            (8, 8, centre),
            |h| h.position = [0.1, 0.1, 6.0],
        ),
    ]
}

/// The cases over a view of two slots per pixel.
fn two_sample_cases() -> Vec<Case> {
    let near = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let side = 2.0 * 5.0 * Vec3::from(near.up).length() / SIZE as f32;
    let half = camera(
        Vec3::new(0.5 * side, 0.0, 5.0),
        Vec3::new(0.5 * side, 0.0, 0.0),
    );
    let farther = camera(Vec3::new(0.0, 0.0, 5.5), Vec3::ZERO);
    vec![
        case(
            "two samples, unmoved",
            true,
            (&near, &near, 2),
            (5, 7, (0.3, 0.5)),
            |_| {},
        ),
        case(
            "two samples, half-pixel pan",
            true,
            (&near, &half, 2),
            (6, 8, (0.7, 0.4)),
            |_| {},
        ),
        case(
            "two samples, dolly out",
            true,
            (&near, &farther, 2),
            (9, 9, (0.4, 0.6)),
            |_| {},
        ),
    ]
}

fn relative(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(f32::MIN_POSITIVE)
}

/// Compares the WGSL outcome of `case` with the core's over `before`; returns whether it
/// inherited.
fn compare(
    (name, inherits, input): &Case,
    wgsl: &InheritOutcome,
    (before, before_bounds): (&[HitPoint], &[GpuBounds]),
) -> bool {
    let request = CameraMove {
        before: input.request.before,
        after: input.request.after,
        spp: input.request.spp,
    };
    let (mut hp, mut bounds) = (input.slot, input.bounds);
    let took = inherit_slot(
        &mut hp,
        Some(&mut bounds),
        &request,
        &materials(),
        (before, before_bounds),
    );
    assert_eq!(
        took, *inherits,
        "{name}: the core's answer is not the case's"
    );
    assert_eq!(wgsl.inherited, u32::from(took), "{name}: inherited");
    if !took {
        assert_eq!(
            wgsl.slot, input.slot,
            "{name}: a slot that does not inherit is untouched"
        );
        assert_eq!(wgsl.bounds, input.bounds, "{name}: its box too");
        return false;
    }
    let (w, c) = (&wgsl.slot, &hp);
    // Minima and maxima of the same boxes: exact.
    assert_eq!(wgsl.bounds, bounds, "{name}: the box");
    // The weighted mean iteration count is floored: rounding may part one step.
    assert!(
        w.iterations.abs_diff(c.iterations) <= 1,
        "{name}: iterations {} against {}",
        w.iterations,
        c.iterations
    );
    let estimate = |h: &HitPoint| Vec3::from(h.tau) / h.r2 / h.emitted;
    let direct = |h: &HitPoint| Vec3::from(h.direct) / h.iterations as f32;
    let fields = [
        ("r2", w.r2, c.r2),
        ("n", w.n, c.n),
        ("emitted", w.emitted, c.emitted),
        // Compared with the count it is a share of.
        ("discounted", w.discounted / w.n, c.discounted / c.n),
        ("estimate.r", estimate(w).x, estimate(c).x),
        ("estimate.b", estimate(w).z, estimate(c).z),
        ("direct mean.r", direct(w).x, direct(c).x),
        ("direct mean.b", direct(w).z, direct(c).z),
    ];
    for (field, a, b) in fields {
        assert!(
            relative(a, b) <= RELATIVE || (a - b).abs() <= RELATIVE,
            "{name}: {field} {a} against {b}"
        );
    }
    assert_eq!(w.correction_r2, 0.0, "{name}: correction_r2");
    assert_eq!(
        (
            w.position, w.normal, w.flags, w.eye_met, w.pixel, w.material
        ),
        (
            c.position, c.normal, c.flags, c.eye_met, c.pixel, c.material
        ),
        "{name}: the visible point"
    );
    true
}

/// A new view of the plane with `spp` fresh slots a pixel, and edges of each kind in it:
/// another object, a crease, the void, a mirror's reflection, a coated patch and a step of
/// the same object in front of itself; the move to it from nearer.
fn view_with_edges(spp: u32) -> (Vec<HitPoint>, CameraMove) {
    let near = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let after = camera(Vec3::new(0.3, 0.1, 5.5), Vec3::ZERO);
    let (mut slots, _) = old_view(&after, spp, u32::MAX);
    for hp in &mut slots {
        let (x, y) = (hp.pixel % SIZE, hp.pixel / SIZE);
        match (x, y) {
            (10..=12, 4..=7) => hp.flags ^= 1 << hit_flags::OBJECT_SHIFT,
            (3, 3) => hp.normal = [0.0, 0.6, 0.8],
            (5, 12) => hp.flags &= !hit_flags::VALID,
            (8, 12) => hp.flags |= hit_flags::EYE_CHAINED,
            (13, 13) => hp.material = 2,
            (2..=4, 8..=10) => hp.position[2] += 0.5,
            _ => {}
        }
    }
    let request = CameraMove {
        before: near,
        after,
        spp,
    };
    (slots, request)
}

fn the_wgsl_inheritance_of_a_camera_move_is_the_core_s() {
    let gpu = WgpuBackend::new().unwrap();
    let near = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let edge = (12, 3);
    let mut batches = vec![(
        old_view(&near, 1, edge.1 * SIZE + edge.0),
        single_sample_cases(edge),
    )];
    batches.push((old_view(&near, 2, u32::MAX), two_sample_cases()));
    let (mut inherited, mut cases, mut edges) = (0, 0, 0);
    for ((before, before_bounds), batch) in &batches {
        let inputs: Vec<InheritCase> = batch.iter().map(|c| c.2).collect();
        let spp = inputs[0].request.spp;
        let (after, request) = view_with_edges(spp);
        let (got, wgsl_edges) = gpu
            .camera_move_vectors(
                (before, before_bounds),
                &materials(),
                &inputs,
                (&after, &request),
            )
            .unwrap();
        let core_edges: Vec<u32> = (0..after.len())
            .map(|slot| u32::from(on_an_edge(&after, slot, &request, &materials())))
            .collect();
        assert_eq!(wgsl_edges, core_edges, "edges with {spp} slots a pixel");
        edges += core_edges.iter().sum::<u32>();
        assert_eq!(got.len(), batch.len());
        for (case, wgsl) in batch.iter().zip(&got) {
            inherited += usize::from(compare(case, wgsl, (before, before_bounds)));
            cases += 1;
        }
    }
    figure!("{cases} cases, {inherited} inherited on both sides alike; {edges} slots on edges");
}

/// What a refused pass needs.
fn refused<T: std::fmt::Debug>(r: Result<T, BackendError>) -> &'static str {
    match r {
        Err(BackendError::OutOfOrder { needs, .. }) => needs,
        other => panic!("not refused: {other:?}"),
    }
}

/// `inherit_light` before its move began, before the fresh eye pass, and before the new
/// camera, is refused naming what it needs; in order, it runs.
fn a_camera_move_out_of_order_is_refused() {
    let mut gpu = WgpuBackend::new().unwrap();
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut compiled = compile_scene(&scene, 16, 16);
    gpu.load_scene(&compiled).unwrap();
    let eye = |keep: bool| EyePassParams {
        spp: 1,
        max_depth: 4,
        r2_initial: 4.0,
        ray_epsilon: 1e-3,
        flags: if keep {
            ppm_core::layout::eye_flags::KEEP_STATISTICS
        } else {
            0
        },
        ..Default::default()
    };
    assert_eq!(
        refused(gpu.begin_camera_move(&CameraMove {
            before: compiled.camera,
            after: compiled.camera,
            spp: 1,
        })),
        "an eye pass"
    );
    gpu.eye_pass(&eye(false)).unwrap();
    let mut after = compiled.camera;
    after.eye[0] += 5.0;
    let request = CameraMove {
        before: compiled.camera,
        after,
        spp: 1,
    };
    assert!(refused(gpu.inherit_light()).starts_with("begin_camera_move"));
    gpu.begin_camera_move(&request).unwrap();
    gpu.eye_pass(&eye(false)).unwrap();
    assert_eq!(
        refused(gpu.inherit_light()),
        "the scene update to the new camera"
    );
    compiled.camera = after;
    gpu.update_scene(&compiled).unwrap();
    gpu.eye_pass(&eye(true)).unwrap();
    assert!(refused(gpu.inherit_light()).starts_with("begin_camera_move"));
    gpu.eye_pass(&eye(false)).unwrap();
    let stats = gpu.inherit_light().unwrap();
    assert_eq!(stats.inherited + stats.reset, 256);
    // The move is over: a second inheritance needs a move of its own.
    assert!(refused(gpu.inherit_light()).starts_with("begin_camera_move"));
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "the_wgsl_inheritance_of_a_camera_move_is_the_core_s",
            the_wgsl_inheritance_of_a_camera_move_is_the_core_s,
        )
        .test_needing(
            &[&adapter],
            "a_camera_move_out_of_order_is_refused",
            a_camera_move_out_of_order_is_refused,
        )
        .run()
}
