//! A local move reads back and writes no slot, and neither does a camera move: the driver
//! orders the backend's passes and reads back their counters. Every backend runs behind a
//! proxy that counts what crosses the contract's read-back ([`ReadBack`]) while a drag of
//! small moves, or an orbit of small camera steps, renders.

use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::compile::CompiledScene;
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, GatherParams, HitPoint, Photon, PhotonPassParams,
    ResolveParams,
};
use ppm_core::local_move::{CorrectionApply, CorrectionPhotons, LocalMove};
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::*;
use ppm_core::scene::Move;
use std::process::ExitCode;
use tests::{BackendTrials, Suite, figure};

/// A backend behind a proxy that counts the slots read back and written through the
/// contract.
struct Counted {
    inner: Box<dyn Backend + Send>,
    slots_read: usize,
    slots_written: usize,
}

impl SceneUpload for Counted {
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.inner.load_scene(scene)
    }
}
impl EyePass for Counted {
    fn eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError> {
        self.inner.eye_pass(params)
    }
}
impl DirectLight for Counted {
    fn direct_light(&mut self, params: &DirectLightParams) -> Result<DirectStats, BackendError> {
        self.inner.direct_light(params)
    }
}
impl PhotonPass for Counted {
    fn photon_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        self.inner.photon_pass(params, source)
    }
}
impl GatherPass for Counted {
    fn gather_pass(&mut self, params: &GatherParams) -> Result<GatherStats, BackendError> {
        self.inner.gather_pass(params)
    }
}
impl Resolve for Counted {
    fn resolve(&mut self, params: &ResolveParams) -> Result<Image, BackendError> {
        self.inner.resolve(params)
    }
}
impl ReadBack for Counted {
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError> {
        let slots = self.inner.read_hit_points()?;
        self.slots_read += slots.len();
        Ok(slots)
    }
    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError> {
        self.inner.read_photons()
    }
    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError> {
        self.slots_written += hit_points.len();
        self.inner.write_hit_points(hit_points)
    }
}
impl RandomSource for Counted {
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError> {
        self.inner.random_bits(keys)
    }
    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError> {
        self.inner.stratified_bits(keys)
    }
}
impl Backend for Counted {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        self.inner.local_moves()?;
        Some(self)
    }
}

impl Counted {
    /// The wrapped backend's local-move passes (the proxy claims them only where it has them).
    fn local(&mut self) -> &mut dyn LocalMoves {
        self.inner.local_moves().expect("claimed")
    }
}

impl LocalMoves for Counted {
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.local().update_scene(scene)
    }
    fn prepare_moves(&mut self) -> Result<(), BackendError> {
        self.local().prepare_moves()
    }
    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        self.local().begin_local_move(request)
    }
    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        self.local().local_resets()
    }
    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        self.local().local_direct_change()
    }
    fn correction_photons(
        &mut self,
        request: &CorrectionPhotons,
    ) -> Result<PhotonStats, BackendError> {
        self.local().correction_photons(request)
    }
    fn apply_correction(&mut self, request: &CorrectionApply) -> Result<GatherStats, BackendError> {
        self.local().apply_correction(request)
    }
    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        self.local().begin_camera_move(request)
    }
    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError> {
        self.local().inherit_light()
    }
}

/// A drag of the short block in cornell-box, eight small local moves an iteration apart,
/// transfers no slot through the read-back, on every backend, while the moves reset and
/// correct slots (they do work).
fn a_local_drag_transfers_no_slot(name: &str, backend: Box<dyn Backend + Send>) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height, params.photons_per_pass) = (48, 48, 10_000);
    let mut counted = Counted {
        inner: backend,
        slots_read: 0,
        slots_written: 0,
    };
    let step = Move {
        translation: scene.moves[0].translation / 30.0,
        rotation: glam::Quat::IDENTITY,
        ..scene.moves[0]
    };
    let mut render =
        harness::driver::Renderer::start(&mut counted, scene, &params, &MoveParams::default())
            .unwrap();
    for _ in 0..4 {
        render.iteration().unwrap();
    }
    let (mut reset, mut corrected) = (0, 0);
    for _ in 0..8 {
        let report = render.move_objects(&[step], MoveMode::Local).unwrap();
        assert!(report.restarted.is_none(), "{name}: {report:?}");
        reset += report.updated;
        corrected += report.direct_corrected;
        render.iteration().unwrap();
    }
    render.resolve().unwrap();
    drop(render);
    figure!(
        "{name}: {reset} slots reset and {corrected} corrected over 8 moves; {} slots read back, \
         {} written",
        counted.slots_read,
        counted.slots_written
    );
    assert!(reset > 0 && corrected > 0, "{name}: the moves must do work");
    assert_eq!(
        (counted.slots_read, counted.slots_written),
        (0, 0),
        "{name}: slots read back and written"
    );
}

/// An orbit of cornell-box's camera, eight steps of half a degree an iteration apart,
/// transfers no slot through the read-back, on every backend, while the steps keep light.
fn a_camera_orbit_transfers_no_slot(name: &str, backend: Box<dyn Backend + Send>) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height, params.photons_per_pass) = (48, 48, 10_000);
    let mut counted = Counted {
        inner: backend,
        slots_read: 0,
        slots_written: 0,
    };
    let mut camera = scene.camera.clone();
    let mut render =
        harness::driver::Renderer::start(&mut counted, scene, &params, &MoveParams::default())
            .unwrap();
    for _ in 0..4 {
        render.iteration().unwrap();
    }
    let mut kept = 0;
    for _ in 0..8 {
        camera = camera.orbited(0.5, 0.0);
        let report = render.move_camera(camera.clone(), MoveMode::Local).unwrap();
        assert!(report.restarted.is_none(), "{name}: {report:?}");
        kept += report.kept;
        render.iteration().unwrap();
    }
    render.resolve().unwrap();
    drop(render);
    figure!(
        "{name}: {kept} slots kept over 8 camera steps; {} slots read back, {} written",
        counted.slots_read,
        counted.slots_written
    );
    assert!(kept > 0, "{name}: the steps must keep light");
    assert_eq!(
        (counted.slots_read, counted.slots_written),
        (0, 0),
        "{name}: slots read back and written"
    );
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "a_local_drag_transfers_no_slot",
            a_local_drag_transfers_no_slot,
        )
        .on_every_backend(
            "a_camera_orbit_transfers_no_slot",
            a_camera_orbit_transfers_no_slot,
        )
        .run()
}
