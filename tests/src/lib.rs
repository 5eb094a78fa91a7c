//! Helpers shared by the workspace-level integration tests in `tests/tests/`.

#![warn(missing_docs)]

use backend_cpu::CpuBackend;
use glam::Vec3;
use harness::driver::{Budget, Outcome, Schedule, run};
use harness::registry::Registry;
use ppm_core::compile::{camera_ray, compile_scene};
use ppm_core::layout::{EyePassParams, GpuBounds};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::{Material, MaterialKind, Move, Object, Scene};
use ppm_core::trace::PoseQueries;
use std::sync::OnceLock;
pub use test_support::{Need, Suite, figure};

/// The wgpu adapter that wgpu-only tests need ([`Need::wgpu`]), probed once per binary by
/// opening a device.
pub fn wgpu() -> &'static Need {
    static NEED: OnceLock<Need> = OnceLock::new();
    NEED.get_or_init(|| {
        Need::wgpu(|| {
            backend_wgpu::GpuContext::new()
                .map(drop)
                .map_err(|e| e.to_string())
        })
    })
}

/// What running on the in-tree backend `name` needs: nothing for the CPU backend, an adapter
/// for wgpu, and for any other that it starts (`PPM_REQUIRE_<NAME>=1` requires it).
fn backend_need(name: &str) -> Option<Need> {
    match name {
        "cpu" => None,
        "wgpu" => Some(wgpu().clone()),
        other => {
            let started = other.to_owned();
            Some(Need::new(
                format!("the {other} backend"),
                format!("PPM_REQUIRE_{}", other.to_uppercase()),
                "what that backend needs",
                move || {
                    Registry::in_tree()
                        .start(&started)
                        .map(drop)
                        .map_err(|e| e.to_string())
                },
            ))
        }
    }
}

/// A test of one backend: its registry name and the backend, started.
pub type BackendTest = fn(&str, Box<dyn Backend + Send>);

/// Cross-backend tests as one test per backend, so that the summary counts each backend's
/// case on its own and shows one that cannot start here as ignored.
pub trait BackendTrials {
    /// Adds `NAME::BACKEND` for every backend [`Registry::in_tree`] registers, so a backend
    /// registered there joins every test added so.
    fn on_every_backend(self, name: &str, test: BackendTest) -> Self;
    /// As [`BackendTrials::on_every_backend`], for every backend but the CPU's, which is the
    /// reference each is compared with.
    fn against_the_cpu(self, name: &str, test: BackendTest) -> Self;
}

impl BackendTrials for Suite {
    fn on_every_backend(self, name: &str, test: BackendTest) -> Self {
        backend_trials(self, name, test, true)
    }

    fn against_the_cpu(self, name: &str, test: BackendTest) -> Self {
        backend_trials(self, name, test, false)
    }
}

fn backend_trials(mut suite: Suite, name: &str, test: BackendTest, with_cpu: bool) -> Suite {
    let registry = Registry::in_tree();
    for backend in registry.names() {
        if backend == "cpu" && !with_cpu {
            continue;
        }
        let need = backend_need(backend);
        let needs: Vec<&Need> = need.iter().collect();
        let backend = backend.to_owned();
        suite = suite.test_needing(&needs, format!("{name}::{backend}"), move || {
            let started = Registry::in_tree()
                .start(&backend)
                .unwrap_or_else(|e| panic!("backend '{backend}' cannot start: {e}"));
            test(&backend, started)
        });
    }
    suite
}

/// Renders `scene` at `frame` for `params.passes` iterations on the CPU backend in a pool of
/// `threads` workers; panics on a pass error, since a test render must not fail.
pub fn render_cpu(
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
    threads: usize,
) -> (Outcome, CpuBackend) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut backend = CpuBackend::new();
    let outcome = pool.install(|| render_on(&mut backend, scene, frame, params));
    (outcome, backend)
}

/// Renders `scene` at `frame` for `params.passes` iterations on `backend`; panics on a pass
/// error, since a test render must not fail.
pub fn render_on(
    backend: &mut dyn Backend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
) -> Outcome {
    let schedule = Schedule::frame(frame, Budget::iterations(params.passes));
    let outcome = run(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        &mut (),
    )
    .expect("render");
    if let Some(e) = &outcome.error {
        panic!("pass failed: {e}");
    }
    outcome
}

/// Luminance (Rec. 709 weights) of a linear RGB value.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Per pixel of a `size` x `size` image, the object an eye ray through its centre meets
/// first in `scene`.
pub fn objects_seen(scene: &Scene, size: u32) -> Vec<Option<u32>> {
    let compiled = compile_scene(scene, size, size);
    let data = backend_cpu::trace::SceneData::new(&compiled);
    (0..size * size)
        .map(|i| {
            let (x, y) = ((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
            let dir = camera_ray(&compiled.camera, x, y);
            data.closest_hit(compiled.camera.eye.into(), dir, f32::INFINITY)
                .map(|h| data.triangles[h.triangle as usize].object)
        })
        .collect()
}

/// Whether `f` holds for pixel `i` of a `size`-wide image and its eight neighbours (clipped
/// to the image): a pixel whose neighbours' centre rays agree has jittered rays that agree
/// too.
pub fn around(i: usize, size: u32, f: impl Fn(usize) -> bool) -> bool {
    let (x, y, size) = (
        (i as u32 % size) as i64,
        (i as u32 / size) as i64,
        size as i64,
    );
    (-1..=1).all(|dy| {
        (-1..=1).all(|dx| {
            let (nx, ny) = (x + dx, y + dy);
            !(0..size).contains(&nx) || !(0..size).contains(&ny) || f((ny * size + nx) as usize)
        })
    })
}

/// Loads the furnace (a closed grey cube) with `movers` as the movers' boxes and traces its
/// hit points at 16x16: for tests of the pass contract on a backend directly.
pub fn load_furnace(backend: &mut dyn Backend, movers: &[GpuBounds]) {
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
}

/// The furnace with a grey mover made of two tiny triangles at the corners `lo` and `hi` of the
/// box it should have, moved by `shift` in frame 1: a path crosses its box far more often than
/// it meets it.
pub fn furnace_with_mover(lo: Vec3, hi: Vec3, shift: Vec3) -> Scene {
    let mut scene = scenes::analytic::furnace(Vec3::splat(0.5), 1.0);
    let e = 0.01;
    scene.materials.push(Material {
        name: "grey".into(),
        kind: MaterialKind::Diffuse {
            albedo: Vec3::splat(0.5),
        },
        texture: None,
    });
    scene.objects.push(Object {
        name: "mover".into(),
        material: scene.materials.len() - 1,
        triangles: vec![
            [lo, lo + Vec3::X * e, lo + Vec3::Y * e],
            [hi, hi - Vec3::Z * e, hi - Vec3::Y * e],
        ],
        uvs: Vec::new(),
    });
    scene.moves.push(Move {
        object: scene.objects.len() - 1,
        translation: shift,
        rotation: glam::Quat::IDENTITY,
    });
    scene
}

/// The path tracer's truth of `scene` at `size` x `size`, `spp` samples a pixel (seed 5).
pub fn truth(scene: &Scene, size: u32, spp: u32) -> ppm_core::image::Image {
    let compiled = compile_scene(scene, size, size);
    let budget = harness::reference::ReferenceBudget {
        spp: Some(spp),
        seconds: None,
    };
    let reference = harness::reference::render_reference(&compiled, 5, budget, &mut |_, _| {
        std::ops::ControlFlow::Continue(())
    });
    assert!(reference.error.is_none(), "{:?}", reference.error);
    reference.image
}
