//! Culling of local mode's difference paths on both backends ([`photon_flags::RECORD_CROSSED`]
//! in pose A, [`photon_flags::CULL_UNCROSSED`] in pose B): pose B skips exactly the paths that
//! crossed no mover's box in pose A, which would store nothing, so culling changes no
//! statistic, and both backends cull the same paths.
//!
//! The scene is the furnace, a closed cube: no photon leaves it, so a box outside it is
//! crossed by no path, and a box around it by every path.

use backend_cpu::CpuBackend;
use glam::Vec3;
use ppm_core::compile::{CompiledScene, compile_scene};
use ppm_core::layout::{
    EyePassParams, GatherParams, GpuBounds, HitPoint, PhotonPassParams, first_hit, gather_kind,
    photon_flags,
};
use ppm_core::passes::{DynamicBackend, PhotonStats};
use ppm_core::rng::DIFFERENCE_PASS_BASE;

const PHOTONS: u32 = 20_000;
/// Difference passes per pose: more than one, so each pass must find its own slot of the mask.
const PASSES: u32 = 3;

/// A difference "move" to the same pose, as local mode runs it.
struct DifferenceMove {
    pose_a: PhotonStats,
    pose_b: PhotonStats,
    before: Vec<HitPoint>,
    after: Vec<HitPoint>,
}

/// Loads the furnace with `movers` as the movers' boxes and traces its hit points.
fn load_furnace(backend: &mut dyn DynamicBackend, movers: &[GpuBounds]) -> CompiledScene {
    let scene = scenes::analytic::furnace(Vec3::splat(0.5), 1.0);
    let mut compiled = compile_scene(&scene, 16, 16);
    compiled.movers = movers.to_vec();
    backend.load_scene(&compiled).unwrap();
    backend
        .eye_pass(&EyePassParams {
            spp: 1,
            max_depth: 4,
            r2_initial: 0.04,
            ray_epsilon: 1e-5,
            ..Default::default()
        })
        .unwrap();
    compiled
}

/// Warms up the furnace with `movers` as the movers' boxes, then runs [`PASSES`] negative
/// difference passes, a scene update to the same pose and as many positive passes, storing
/// only what follows a box crossing; with `cull`, pose A records the crossings and pose B
/// traces only the paths that crossed.
fn difference_move(
    backend: &mut dyn DynamicBackend,
    movers: &[GpuBounds],
    cull: bool,
) -> DifferenceMove {
    let compiled = load_furnace(backend, movers);
    let photons = |pass_index, flags, mask_offset, power_scale| PhotonPassParams {
        pass_index,
        photon_count: PHOTONS,
        max_depth: 8,
        first_hit: first_hit::SKIP,
        ray_epsilon: 1e-5,
        power_scale,
        flags,
        mask_offset,
        ..Default::default()
    };
    let gather = |kind, emitted_increment, region_photons| GatherParams {
        alpha: 0.7,
        emitted_increment,
        kind,
        region_photons,
    };
    backend.photon_pass(&photons(0, 0, 0, 1.0)).unwrap();
    backend
        .gather_pass(&gather(gather_kind::ORDINARY, PHOTONS as f32, 0.0))
        .unwrap();
    let before = backend.read_hit_points().unwrap();
    let total = (PHOTONS * PASSES) as f32;
    let pose = |backend: &mut dyn DynamicBackend, sign: f32, kind: u32, flag: u32| {
        let mut sum = PhotonStats::default();
        for k in 0..PASSES {
            let flags = photon_flags::CHANGED_ONLY | if cull { flag } else { 0 };
            let params = photons(DIFFERENCE_PASS_BASE + k, flags, k * PHOTONS, sign);
            sum.add(&backend.photon_pass(&params).unwrap());
            backend
                .gather_pass(&gather(kind | gather_kind::DEFERRED, 0.0, total))
                .unwrap();
        }
        sum
    };
    let pose_a = pose(
        backend,
        -1.0,
        gather_kind::REGION_NEGATIVE,
        photon_flags::RECORD_CROSSED,
    );
    backend.update_scene(&compiled).unwrap();
    let pose_b = pose(
        backend,
        1.0,
        gather_kind::REGION_POSITIVE,
        photon_flags::CULL_UNCROSSED,
    );
    backend
        .gather_pass(&gather(gather_kind::REGION_APPLY, 0.0, 0.0))
        .unwrap();
    let after = backend.read_hit_points().unwrap();
    DifferenceMove {
        pose_a,
        pose_b,
        before,
        after,
    }
}

fn bytes(hit_points: &[HitPoint]) -> &[u8] {
    bytemuck::cast_slice(hit_points)
}

/// The backends the test runs on: the CPU's, and wgpu's when an adapter exists; `batched`
/// adds a wgpu backend whose passes are split into batches of paths.
fn backends(test: &str, batched: bool) -> Vec<(String, Box<dyn DynamicBackend>)> {
    let mut all: Vec<(String, Box<dyn DynamicBackend>)> =
        vec![("cpu".to_owned(), Box::new(CpuBackend::new()))];
    if let Some(gpu) = backend_wgpu::backend_or_skip(test) {
        all.push(("wgpu".to_owned(), Box::new(gpu)));
    }
    if batched && let Some(mut gpu) = backend_wgpu::backend_or_skip(test) {
        // 64 KiB holds 2,048 deposits: a pass of the partial box takes about three batches.
        gpu.set_photon_buffer_limit(64 * 1024);
        all.push(("wgpu, batched".to_owned(), Box::new(gpu)));
    }
    all
}

#[test]
fn a_box_no_photon_reaches_culls_every_path_and_corrects_nothing() {
    // Far outside the closed cube [-1, 1]^3.
    let far = GpuBounds::new(Vec3::new(5.0, 5.0, 5.0), Vec3::new(6.0, 6.0, 6.0));
    for (name, mut backend) in backends(
        "a_box_no_photon_reaches_culls_every_path_and_corrects_nothing",
        false,
    ) {
        let m = difference_move(backend.as_mut(), &[far], true);
        println!("{name}: pose A {:?}, pose B {:?}", m.pose_a, m.pose_b);
        assert_eq!(m.pose_a.culled, 0, "{name}: pose A traces every path");
        assert_eq!(
            (m.pose_b.culled, m.pose_b.rays, m.pose_b.emitted),
            (u64::from(PHOTONS * PASSES), 0, u64::from(PHOTONS * PASSES)),
            "{name}: pose B culls every path and still counts it emitted"
        );
        assert_eq!((m.pose_a.deposited, m.pose_b.deposited), (0, 0), "{name}");
        assert!(
            bytes(&m.before) == bytes(&m.after),
            "{name}: the net correction moved a statistic"
        );
    }
}

#[test]
fn a_box_around_the_scene_culls_nothing() {
    let around = GpuBounds::new(Vec3::new(-2.0, -2.0, -2.0), Vec3::new(2.0, 2.0, 2.0));
    for (name, mut backend) in backends("a_box_around_the_scene_culls_nothing", false) {
        let m = difference_move(backend.as_mut(), &[around], true);
        println!("{name}: pose A {:?}, pose B {:?}", m.pose_a, m.pose_b);
        assert_eq!(m.pose_b.culled, 0, "{name}");
        // Every path crossed: each stores all its deposits, alike in both poses.
        assert!(m.pose_a.deposited > 0, "{name}");
        assert_eq!(
            (m.pose_b.deposited, m.pose_b.rays),
            (m.pose_a.deposited, m.pose_a.rays),
            "{name}: pose B traced other paths than pose A"
        );
    }
}

/// A box that some paths cross and others miss: the backends cull the same number of paths,
/// and on each backend the statistics after the move are bit for bit those without culling.
#[test]
fn both_backends_cull_the_same_paths_and_culling_changes_no_statistic() {
    let inside = GpuBounds::new(Vec3::new(0.2, -0.9, 0.2), Vec3::new(0.9, -0.2, 0.9));
    let mut culled = Vec::new();
    for (name, mut backend) in backends(
        "both_backends_cull_the_same_paths_and_culling_changes_no_statistic",
        true,
    ) {
        let with = difference_move(backend.as_mut(), &[inside], true);
        let without = difference_move(backend.as_mut(), &[inside], false);
        println!(
            "{name}: culled {} of {} pose-B paths; deposits {} (pose A) {} (pose B); rays {} vs {} unculled",
            with.pose_b.culled,
            with.pose_b.emitted,
            with.pose_a.deposited,
            with.pose_b.deposited,
            with.pose_b.rays,
            without.pose_b.rays
        );
        assert!(
            with.pose_b.culled > 0 && with.pose_b.culled < with.pose_b.emitted,
            "{name}: the box must split the paths to test anything: {:?}",
            with.pose_b
        );
        assert_eq!(without.pose_b.culled, 0, "{name}");
        assert_eq!(
            with.pose_b.deposited, without.pose_b.deposited,
            "{name}: culling dropped deposits"
        );
        assert!(with.pose_b.rays < without.pose_b.rays, "{name}");
        assert!(
            bytes(&with.after) == bytes(&without.after),
            "{name}: culling changed a statistic"
        );
        culled.push((name, with.pose_b.culled));
    }
    for (name, count) in &culled {
        assert_eq!(
            *count, culled[0].1,
            "{name} culled other paths than the CPU"
        );
    }
}

/// Bits no pass recorded count as crossed: a pass that culls where nothing was recorded
/// (before any record, or past the recorded slots) traces every path.
#[test]
fn a_pass_culls_only_paths_recorded_as_uncrossed() {
    let far = GpuBounds::new(Vec3::new(5.0, 5.0, 5.0), Vec3::new(6.0, 6.0, 6.0));
    for (name, mut backend) in backends("a_pass_culls_only_paths_recorded_as_uncrossed", false) {
        let backend = backend.as_mut();
        load_furnace(backend, &[far]);
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
        assert_eq!(backend.photon_pass(&cull(0)).unwrap().culled, 0, "{name}");
        let record = PhotonPassParams {
            flags: photon_flags::CHANGED_ONLY | photon_flags::RECORD_CROSSED,
            ..cull(0)
        };
        backend.photon_pass(&record).unwrap();
        assert_eq!(
            backend.photon_pass(&cull(0)).unwrap().culled,
            u64::from(PHOTONS),
            "{name}: the recorded slot culls every path"
        );
        assert_eq!(
            backend.photon_pass(&cull(PHOTONS)).unwrap().culled,
            0,
            "{name}: past the recorded slot nothing is culled"
        );
    }
}
