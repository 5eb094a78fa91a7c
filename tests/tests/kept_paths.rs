//! Kept paths ([`photon_flags::KEEP_PATHS`]) on the CPU and wgpu backends: a local move's
//! pose-A correction, a [`photon_flags::CHANGED_ONLY`] pass with an ordinary pass's random
//! numbers in the pose that pass was traced in, is answered by testing the kept segments
//! against the movers' boxes (the CPU keeps every segment; wgpu keeps a path's first few and
//! traces the longer paths again). The answer must be, bit for bit, what tracing the paths
//! again gives: the deposits, their order and sign, and the crossed-path mask pose B culls by.

use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use harness::driver::{Renderer, pass_params};
use ppm_core::compile::{CompiledScene, compile_scene, mover_boxes};
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{Photon, PhotonPassParams, gather_kind, photon_flags};
use ppm_core::params::{MoveMode, RenderParams};
use ppm_core::passes::{Backend, LocalMoves, PhotonStats};
use std::process::ExitCode;
use tests::Suite;

/// A backend that keeps paths, as the tests drive it.
trait Keeps: Backend + LocalMoves {}
impl<B: Backend + LocalMoves> Keeps for B {}

/// Makes a fresh backend of one kind.
type NewBackend = fn() -> Box<dyn Keeps>;

/// A test, run on each kind of backend.
type Case = fn(NewBackend);

fn cpu() -> Box<dyn Keeps> {
    Box::new(CpuBackend::new())
}

fn wgpu() -> Box<dyn Keeps> {
    Box::new(WgpuBackend::new().expect("an adapter"))
}

const PHOTONS: u32 = 20_000;
/// The ordinary pass whose paths the corrections draw.
const PASS: u32 = 7;

/// Cornell-box's two poses, each with the boxes of its declared move, pose A also without
/// (as ordinary passes see it), and the parameters of its ordinary passes.
struct Poses {
    bare: CompiledScene,
    a: CompiledScene,
    b: CompiledScene,
    params: RenderParams,
}

fn poses() -> Poses {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let (before, after) = (scene.at_frame(0), scene.at_frame(1));
    let moved: Vec<usize> = scene.moves.iter().map(|m| m.object).collect();
    // Pose A is the pose the ordinary passes saw, with the movers' boxes added, as the
    // driver updates it at a move's start.
    let bare = compile_scene(&before, 16, 16);
    let mut a = bare.clone();
    let mut b = compile_scene(&after, 16, 16);
    let movers = mover_boxes(&before, &after, &moved, a.extent);
    (a.movers, b.movers) = (movers.clone(), movers);
    let mut params = RenderParams::for_scene(&scene);
    params.photons_per_pass = PHOTONS;
    Poses { bare, a, b, params }
}

impl Poses {
    /// Pass [`PASS`] with `flags` and `power_scale`.
    fn pass(&self, flags: u32, power_scale: f32) -> PhotonPassParams {
        let p = pass_params::photon_pass(
            &self.params,
            self.a.extent,
            PASS,
            PHOTONS,
            power_scale,
            gather_kind::REGION_NEGATIVE | gather_kind::DEFERRED,
        );
        PhotonPassParams { flags, ..p }
    }

    /// The ordinary pass, asked to keep its paths.
    fn ordinary(&self) -> PhotonPassParams {
        let p = pass_params::photon_pass(
            &self.params,
            self.a.extent,
            PASS,
            PHOTONS,
            1.0,
            gather_kind::ORDINARY,
        );
        PhotonPassParams {
            flags: photon_flags::KEEP_PATHS,
            ..p
        }
    }
}

/// `backend` with `pose` loaded and slots to gather into (the wgpu backend's photon pass
/// folds its photons into them).
fn loaded(new: NewBackend, pose: &CompiledScene, params: &RenderParams) -> Box<dyn Keeps> {
    let mut backend = new();
    backend.load_scene(pose).unwrap();
    let eye = pass_params::eye_pass(params, pose.extent, 0, false);
    backend.eye_pass(&eye).unwrap();
    backend
}

/// A pass's counters and deposits.
fn run(backend: &mut dyn Keeps, params: &PhotonPassParams) -> (PhotonStats, Vec<Photon>) {
    let stats = backend.photon_pass(params, &PhotonSource::Lights).unwrap();
    (stats, backend.read_photons().unwrap())
}

fn bytes(photons: &[Photon]) -> &[u8] {
    bytemuck::cast_slice(photons)
}

/// Pose A's correction, then pose B's culled twin, on `backend` (pose A loaded, with or
/// without kept paths).
fn correct(backend: &mut dyn Keeps, poses: &Poses) -> [(PhotonStats, Vec<Photon>); 2] {
    let a = poses.pass(
        photon_flags::CHANGED_ONLY | photon_flags::RECORD_CROSSED,
        -1.0,
    );
    backend.update_scene(&poses.a).unwrap();
    let in_a = run(backend, &a);
    backend.update_scene(&poses.b).unwrap();
    let b = poses.pass(
        photon_flags::CHANGED_ONLY | photon_flags::CULL_UNCROSSED,
        1.0,
    );
    [in_a, run(backend, &b)]
}

fn a_correction_answered_from_kept_paths_is_the_one_traced(new: NewBackend) {
    let poses = poses();
    let mut kept = loaded(new, &poses.bare, &poses.params);
    let (ordinary, _) = run(kept.as_mut(), &poses.ordinary());
    let [(kept_a, kept_a_photons), (kept_b, kept_b_photons)] = correct(kept.as_mut(), &poses);

    let mut traced = loaded(new, &poses.a, &poses.params);
    let [(traced_a, traced_a_photons), (traced_b, traced_b_photons)] =
        correct(traced.as_mut(), &poses);

    println!(
        "ordinary pass: {} deposits; pose A: {} stored ({} rays kept, {} traced); \
         pose B: {} culled, {} stored",
        ordinary.deposited,
        kept_a.deposited,
        kept_a.rays,
        traced_a.rays,
        kept_b.culled,
        kept_b.deposited
    );
    // Only the paths too long to keep, a few per cent, are traced again.
    assert!(
        kept_a.rays * 5 < traced_a.rays,
        "pose A was not answered from the kept paths"
    );
    assert!(
        kept_a.deposited > 0 && kept_a.deposited < ordinary.deposited,
        "the boxes must split the deposits to test anything"
    );
    assert_eq!(kept_a.deposited, traced_a.deposited);
    assert!(
        bytes(&kept_a_photons) == bytes(&traced_a_photons),
        "pose A's deposits differ from the traced ones"
    );
    assert!(
        kept_a_photons
            .iter()
            .all(|p| p.power.iter().all(|&v| v <= 0.0))
    );
    // Pose B culls by the mask pose A wrote: the same paths, so the same deposits.
    assert!(kept_b.culled > 0);
    assert_eq!(
        (kept_b.culled, kept_b.deposited),
        (traced_b.culled, traced_b.deposited)
    );
    assert!(bytes(&kept_b_photons) == bytes(&traced_b_photons));
}

/// Kept paths answer only in the pose they were traced in, only the pass whose numbers they
/// hold, and only while their pass's deposits are the photon map.
fn kept_paths_answer_nothing_in_another_pose_for_another_pass_or_after_another_pass(
    new: NewBackend,
) {
    let poses = poses();
    let changed_only = poses.pass(photon_flags::CHANGED_ONLY, -1.0);
    let another = PhotonPassParams {
        pass_index: PASS + 1,
        ..changed_only
    };
    for (pose, params, pass_between) in [
        (&poses.b, changed_only, false),
        (&poses.a, another, false),
        (&poses.a, changed_only, true),
    ] {
        let mut kept = loaded(new, &poses.bare, &poses.params);
        run(kept.as_mut(), &poses.ordinary());
        if pass_between {
            run(kept.as_mut(), &another);
        }
        kept.update_scene(pose).unwrap();
        let (stats, photons) = run(kept.as_mut(), &params);
        let mut traced = loaded(new, pose, &poses.params);
        let (traced_stats, traced_photons) = run(traced.as_mut(), &params);
        assert!(stats.rays > 0, "answered from paths that do not hold it");
        assert_eq!(stats.rays, traced_stats.rays);
        assert!(bytes(&photons) == bytes(&traced_photons));
    }
}

/// Through the driver: after a first local move, ordinary passes keep their paths, so a drag
/// step's pose A traces (almost) no photon ray and the step traces mostly pose B's culled
/// paths.
fn a_drag_step_after_the_first_traces_pose_a_from_the_kept_paths(new: NewBackend) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let declared = scene.moves[0];
    let step = ppm_core::scene::Move {
        translation: declared.translation / 30.0,
        rotation: glam::Quat::IDENTITY,
        ..declared
    };
    let mut p = RenderParams::for_scene(&scene);
    (p.width, p.height, p.photons_per_pass) = (32, 32, PHOTONS);
    let mut backend = new();
    let moves = ppm_core::params::MoveParams::default();
    let mut render = Renderer::start(backend.as_mut(), scene, &p, &moves).unwrap();
    let mut step_rays = Vec::new();
    for _ in 0..3 {
        render.iteration().unwrap();
        let before = render.report().rays.photon;
        let moved = render.move_objects(&[step], MoveMode::Local).unwrap();
        assert!(moved.restarted.is_none(), "{moved:?}");
        step_rays.push(render.report().rays.photon - before);
    }
    println!("photon rays per step: {step_rays:?}");
    // The first step traces pose A in full; the next ones only pose B's culled paths.
    assert!(
        step_rays[1] * 2 < step_rays[0] && step_rays[2] * 2 < step_rays[0],
        "{step_rays:?}"
    );
}

fn main() -> ExitCode {
    let cases: [(&str, Case); 3] = [
        (
            "a_correction_answered_from_kept_paths_is_the_one_traced",
            a_correction_answered_from_kept_paths_is_the_one_traced,
        ),
        (
            "kept_paths_answer_nothing_in_another_pose_for_another_pass_or_after_another_pass",
            kept_paths_answer_nothing_in_another_pose_for_another_pass_or_after_another_pass,
        ),
        (
            "a_drag_step_after_the_first_traces_pose_a_from_the_kept_paths",
            a_drag_step_after_the_first_traces_pose_a_from_the_kept_paths,
        ),
    ];
    let mut suite = Suite::new();
    for (name, case) in cases {
        suite = suite
            .test(format!("{name}::cpu"), move || case(cpu))
            .test_needing(&[tests::wgpu()], format!("{name}::wgpu"), move || {
                case(wgpu)
            });
    }
    suite.run()
}
