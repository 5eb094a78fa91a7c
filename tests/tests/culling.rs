//! Culling of local mode's difference paths on both backends ([`photon_flags::RECORD_CROSSED`]
//! in pose A, [`photon_flags::CULL_UNCROSSED`] in pose B): pose B skips exactly the paths that
//! crossed no mover's box in pose A, which would store nothing, so culling changes no
//! statistic, and both backends cull the same paths. The moves run through the driver.
//!
//! The scene is the furnace, a closed cube, with a grey mover made of two tiny triangles at
//! opposite corners of the box it should have ([`tests::furnace_with_mover`]): no photon
//! leaves the cube, so a box outside it is crossed by no path, and a box around it by every
//! path.

use backend_cpu::CpuBackend;
use glam::Vec3;
use harness::driver::{MoveReport, Renderer};
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{GpuBounds, HitPoint, PhotonPassParams, photon_flags};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::rng::DIFFERENCE_PASS_BASE;
use ppm_core::scene::Scene;
use std::process::ExitCode;
use tests::furnace_with_mover;
use tests::{BackendTrials, Suite, figure};

const PHOTONS: u32 = 20_000;

/// A local move after two iterations, culling or not: its report, the photon rays traced in
/// all, and the slots before and after it.
struct LocalMove {
    moved: MoveReport,
    photon_rays: u64,
    before: Vec<HitPoint>,
    after: Vec<HitPoint>,
}

fn local_move(backend: &mut dyn Backend, scene: &Scene, cull_uncrossed: bool) -> LocalMove {
    let mut p = RenderParams::for_scene(scene);
    (p.width, p.height, p.photons_per_pass) = (16, 16, PHOTONS);
    let moves = MoveParams {
        difference_passes: 3,
        cull_uncrossed,
        ..MoveParams::default()
    };
    let mut render = Renderer::start(backend, scene.at_frame(0), &p, &moves).unwrap();
    for _ in 0..2 {
        render.iteration().unwrap();
    }
    let before = render.backend().read_hit_points().unwrap();
    let moved = render.move_to(scene.at_frame(1), MoveMode::Local).unwrap();
    assert!(moved.restarted.is_none(), "{moved:?}");
    LocalMove {
        moved,
        photon_rays: render.report().rays.photon,
        before,
        after: render.backend().read_hit_points().unwrap(),
    }
}

/// What a slot holds, flags aside.
fn statistics(h: &HitPoint) -> ([f32; 3], f32, f32, f32, [f32; 3], u32) {
    (h.tau, h.n, h.r2, h.emitted, h.direct, h.iterations)
}

fn bytes(hit_points: &[HitPoint]) -> &[u8] {
    bytemuck::cast_slice(hit_points)
}

fn a_box_no_photon_reaches_culls_every_path_and_corrects_nothing(
    name: &str,
    mut backend: Box<dyn Backend + Send>,
) {
    // Far outside the closed cube [-1, 1]^3.
    let scene = furnace_with_mover(Vec3::splat(5.0), Vec3::splat(6.0), Vec3::X * 0.1);
    let m = local_move(backend.as_mut(), &scene, true);
    figure!("{name}: {:?}", m.moved);
    assert_eq!(
        m.moved.culled_share,
        Some(1.0),
        "{name}: pose B culls every path"
    );
    assert_eq!(
        (m.moved.updated, m.moved.direct_corrected),
        (0, 0),
        "{name}"
    );
    for (old, new) in m.before.iter().zip(&m.after) {
        assert_eq!(
            statistics(old),
            statistics(new),
            "{name}: the move changed a slot"
        );
    }
}

fn a_box_around_the_scene_culls_nothing(name: &str, mut backend: Box<dyn Backend + Send>) {
    let scene = furnace_with_mover(Vec3::splat(-2.0), Vec3::splat(2.0), Vec3::X * 0.1);
    let m = local_move(backend.as_mut(), &scene, true);
    figure!("{name}: {:?}", m.moved);
    assert_eq!(m.moved.culled_share, Some(0.0), "{name}");
    // Every path crossed the box: each stores all its deposits.
    assert!(
        m.moved.changed_share.is_some_and(|s| s > 0.9),
        "{name}: {:?}",
        m.moved
    );
}

/// A box that some paths cross and others miss: the backend culls the share of paths the CPU
/// backend culls, and the statistics after the move are bit for bit those without culling.
fn culling_changes_no_statistic_and_culls_what_the_cpu_culls(
    name: &str,
    mut backend: Box<dyn Backend + Send>,
) {
    let share = culled_share(name, backend.as_mut());
    let on_the_cpu = culled_share("cpu", &mut CpuBackend::new());
    assert_eq!(share, on_the_cpu, "{name} culled other paths than the CPU");
}

/// [`culling_changes_no_statistic_and_culls_what_the_cpu_culls`] on a wgpu backend whose
/// passes are split into batches of paths.
fn batched_wgpu_culling_changes_no_statistic_and_culls_what_the_cpu_culls() {
    let mut gpu = backend_wgpu::WgpuBackend::new().unwrap();
    // 64 KiB holds 2,048 deposits: a pass of the partial box takes several batches.
    gpu.set_photon_buffer_limit(64 * 1024);
    culling_changes_no_statistic_and_culls_what_the_cpu_culls("wgpu, batched", Box::new(gpu));
}

/// The share of paths `backend` culls in a local move of a box that some paths cross and
/// others miss, checked to change no statistic.
fn culled_share(name: &str, backend: &mut dyn Backend) -> f64 {
    let scene = furnace_with_mover(
        Vec3::new(0.2, -0.9, 0.2),
        Vec3::new(0.9, -0.2, 0.9),
        Vec3::new(-0.05, 0.0, 0.0),
    );
    let with = local_move(backend, &scene, true);
    let without = local_move(backend, &scene, false);
    let share = with.moved.culled_share.unwrap();
    figure!(
        "{name}: culled share {share}; photon rays {} with culling, {} without",
        with.photon_rays,
        without.photon_rays
    );
    assert!(
        share > 0.0 && share < 1.0,
        "{name}: the box must split the paths to test anything: {share}"
    );
    assert_eq!(without.moved.culled_share, Some(0.0), "{name}");
    assert_eq!(
        with.moved.changed_share, without.moved.changed_share,
        "{name}"
    );
    assert!(with.photon_rays < without.photon_rays, "{name}");
    assert!(
        bytes(&with.after) == bytes(&without.after),
        "{name}: culling changed a statistic"
    );
    share
}

/// Bits no pass recorded count as crossed: a pass that culls where nothing was recorded
/// (before any record, or past the recorded slots) traces every path.
fn a_pass_culls_only_paths_recorded_as_uncrossed(name: &str, mut backend: Box<dyn Backend + Send>) {
    let far = GpuBounds::new(Vec3::new(5.0, 5.0, 5.0), Vec3::new(6.0, 6.0, 6.0));
    let backend = backend.as_mut();
    tests::load_furnace(backend, &[far]);
    let cull = |mask_offset| PhotonPassParams {
        pass_index: DIFFERENCE_PASS_BASE,
        photon_count: PHOTONS,
        max_depth: 8,
        ray_epsilon: 1e-5,
        power_scale: 1.0,
        flags: photon_flags::CHANGED_ONLY | photon_flags::CULL_UNCROSSED,
        mask_offset,
        ..Default::default()
    };
    assert_eq!(
        backend
            .photon_pass(&cull(0), &PhotonSource::Lights)
            .unwrap()
            .culled,
        0,
        "{name}"
    );
    let record = PhotonPassParams {
        flags: photon_flags::CHANGED_ONLY | photon_flags::RECORD_CROSSED,
        ..cull(0)
    };
    backend.photon_pass(&record, &PhotonSource::Lights).unwrap();
    assert_eq!(
        backend
            .photon_pass(&cull(0), &PhotonSource::Lights)
            .unwrap()
            .culled,
        u64::from(PHOTONS),
        "{name}: the recorded slot culls every path"
    );
    assert_eq!(
        backend
            .photon_pass(&cull(PHOTONS), &PhotonSource::Lights)
            .unwrap()
            .culled,
        0,
        "{name}: past the recorded slot nothing is culled"
    );
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "a_box_no_photon_reaches_culls_every_path_and_corrects_nothing",
            a_box_no_photon_reaches_culls_every_path_and_corrects_nothing,
        )
        .on_every_backend(
            "a_box_around_the_scene_culls_nothing",
            a_box_around_the_scene_culls_nothing,
        )
        .on_every_backend(
            "culling_changes_no_statistic_and_culls_what_the_cpu_culls",
            culling_changes_no_statistic_and_culls_what_the_cpu_culls,
        )
        .test_needing(
            &[tests::wgpu()],
            "culling_changes_no_statistic_and_culls_what_the_cpu_culls::wgpu-batched",
            batched_wgpu_culling_changes_no_statistic_and_culls_what_the_cpu_culls,
        )
        .on_every_backend(
            "a_pass_culls_only_paths_recorded_as_uncrossed",
            a_pass_culls_only_paths_recorded_as_uncrossed,
        )
        .run()
}
