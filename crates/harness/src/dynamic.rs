//! Dynamic frames (ALGORITHM.md 2 and 3): a progressive render carried across object moves.
//!
//! [`Progressive`] owns the pass counters and the recorded paths of one render and drives a
//! [`DynamicBackend`] through them: ordinary passes, a move with compensation photons (thesis
//! or area mode), and the passes that follow a move (guided and ordinary, alternating). The
//! restart mode is simply a new [`Progressive`] on the new pose.

use ppm_core::compile::{CompiledScene, compile_scene};
use ppm_core::emission::ordinary_emission;
use ppm_core::image::Image;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, GatherParams, GpuLight, GpuMaterial, GuidedEmission,
    PhotonPassParams, RecordedPath, ResolveParams, first_hit, gather_kind, region_mode,
};
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::passes::{BackendError, DynamicBackend};
use ppm_core::region::{RegionError, emitting_region};
use ppm_core::rng::{PassKind, StreamKey};
use ppm_core::scene::Scene;
use serde::Serialize;
use std::time::Instant;

/// How a render follows a move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Start over from scratch on the new pose (plain PPM).
    Restart,
    /// The thesis: point light at the lights' centre, raw `M`, unweighted guided photons.
    Thesis,
    /// Ours: every light point, `M` in ordinary-photon units, defensively weighted guides.
    Area,
}

impl Mode {
    /// Every mode, in report order.
    pub const ALL: [Mode; 3] = [Mode::Restart, Mode::Thesis, Mode::Area];

    /// The mode's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Restart => "restart",
            Mode::Thesis => "thesis",
            Mode::Area => "area",
        }
    }
}

/// Settings of the dynamic passes.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicParams {
    /// Compensation passes (and as many positive region passes) per move.
    pub compensation_passes: u32,
    /// Photons per compensation or region pass (the thesis: 256 x 256).
    pub region_photons: u32,
    /// Half-angle of the guided photons' jitter cone, degrees (the thesis: within 10).
    pub cone_deg: f32,
    /// Probability of an ordinary direction in the defensive mixture.
    pub beta: f32,
    /// Recorded paths kept for guiding (a stride subsample beyond this).
    pub max_recorded: usize,
    /// Distance beyond which a hit point counts as moved, relative to the scene's extent.
    pub update_epsilon: f32,
}

impl Default for DynamicParams {
    fn default() -> Self {
        Self {
            compensation_passes: 4,
            region_photons: 256 * 256,
            cone_deg: 10.0,
            beta: 0.25,
            max_recorded: 1024,
            update_epsilon: 1e-4,
        }
    }
}

/// Photons emitted and deposited, per kind (the thesis's tables 4.1 and 4.2).
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhotonCounts {
    /// Ordinary photons emitted / deposited.
    pub ordinary: (u64, u64),
    /// Compensation (negative region) photons.
    pub compensation: (u64, u64),
    /// Positive region photons.
    pub region: (u64, u64),
    /// Testing photons.
    pub testing: (u64, u64),
    /// Guided photons.
    pub guided: (u64, u64),
}

/// What a move did.
#[derive(Clone, Debug, Serialize)]
pub struct MoveReport {
    /// Mode used.
    pub mode: Mode,
    /// Area of the emitting rectangle (0 when the move fell back to a restart).
    pub region_area: f32,
    /// Hit points reset by the update.
    pub updated: u64,
    /// Hit points that kept their statistics.
    pub kept: u64,
    /// Testing-photon paths recorded for guiding.
    pub recorded_paths: usize,
    /// Why the move restarted instead of compensating, if it did.
    pub restarted: Option<String>,
    /// Seconds the move took (compensation, update, region and testing passes).
    pub seconds: f64,
}

/// A progressive render that survives moves.
pub struct Progressive<'a> {
    backend: &'a mut dyn DynamicBackend,
    params: RenderParams,
    dynamic: DynamicParams,
    scene: Scene,
    lights: Vec<GpuLight>,
    materials: Vec<GpuMaterial>,
    extent: f32,
    frame: u32,
    photon_pass: u32,
    region_pass: u32,
    guided_pass: u32,
    steps_since_move: u32,
    guide: Option<(GuidedEmission, Vec<RecordedPath>)>,
    /// Photons emitted and deposited so far, per kind.
    pub counts: PhotonCounts,
}

/// Offset of new ray origins, relative to the scene's extent (as in [`crate::render`]).
const RAY_EPSILON_RELATIVE: f32 = 1e-5;

impl<'a> Progressive<'a> {
    /// Loads `scene` (already posed), and runs the eye pass and direct light.
    pub fn start(
        backend: &'a mut dyn DynamicBackend,
        scene: Scene,
        params: &RenderParams,
        dynamic: &DynamicParams,
    ) -> Result<Self, BackendError> {
        let mut p = Self {
            backend,
            params: params.clone(),
            dynamic: dynamic.clone(),
            scene: scene.clone(),
            lights: Vec::new(),
            materials: Vec::new(),
            extent: 0.0,
            frame: 0,
            photon_pass: 0,
            region_pass: 0,
            guided_pass: 0,
            steps_since_move: 0,
            guide: None,
            counts: PhotonCounts::default(),
        };
        p.reload(scene)?;
        Ok(p)
    }

    /// Starts over on `scene`: fresh hit points, eye pass and direct light.
    fn reload(&mut self, scene: Scene) -> Result<(), BackendError> {
        let compiled = compile_scene(&scene, self.params.width, self.params.height);
        self.backend.load_scene(&compiled)?;
        self.adopt(scene, &compiled);
        self.guide = None;
        self.backend.eye_pass(&self.eye_params())?;
        self.direct_light()
    }

    fn adopt(&mut self, scene: Scene, compiled: &CompiledScene) {
        self.scene = scene;
        self.lights = compiled.lights.clone();
        self.materials = compiled.materials.clone();
        self.extent = compiled.extent;
    }

    fn ray_epsilon(&self) -> f32 {
        RAY_EPSILON_RELATIVE * self.extent
    }

    fn eye_params(&self) -> EyePassParams {
        EyePassParams {
            seed: self.params.seed,
            spp: self.params.spp,
            max_depth: self.params.max_eye_depth,
            frame: self.frame,
            r2_initial: self.params.initial_radius * self.params.initial_radius,
            ray_epsilon: self.ray_epsilon(),
            ..Default::default()
        }
    }

    fn direct_light(&mut self) -> Result<(), BackendError> {
        let samples = match self.params.direct {
            DirectMode::Explicit => self.params.direct_samples,
            DirectMode::Photons => 0,
        };
        self.backend.direct_light(&DirectLightParams {
            seed: self.params.seed,
            samples,
            frame: self.frame,
            ray_epsilon: self.ray_epsilon(),
        })?;
        Ok(())
    }

    fn photon_params(
        &self,
        pass_index: u32,
        photon_count: u32,
        power_scale: f32,
    ) -> PhotonPassParams {
        PhotonPassParams {
            seed: self.params.seed,
            pass_index,
            photon_count,
            max_depth: self.params.max_photon_depth,
            first_hit: match self.params.direct {
                DirectMode::Explicit => first_hit::SKIP,
                DirectMode::Photons => first_hit::DEPOSIT,
            },
            ray_epsilon: self.ray_epsilon(),
            power_scale,
            first_path: 0,
        }
    }

    fn gather(
        &mut self,
        kind: u32,
        emitted_increment: f32,
        region_photons: f32,
    ) -> Result<(), BackendError> {
        self.backend.gather_pass(&GatherParams {
            alpha: self.params.alpha,
            emitted_increment,
            kind,
            region_photons,
        })?;
        Ok(())
    }

    /// One ordinary photon pass, gathered by every hit point.
    pub fn ordinary_pass(&mut self) -> Result<(), BackendError> {
        let n = self.params.photons_per_pass;
        let stats = self
            .backend
            .photon_pass(&self.photon_params(self.photon_pass, n, 1.0))?;
        self.photon_pass += 1;
        self.counts.ordinary.0 += stats.emitted;
        self.counts.ordinary.1 += stats.deposited;
        self.gather(gather_kind::ORDINARY, n as f32, 0.0)
    }

    /// One pass after a move: guided and ordinary passes alternate while there are recorded
    /// paths (guided first); ordinary passes only otherwise.
    pub fn step(&mut self) -> Result<(), BackendError> {
        let guided_turn = self.steps_since_move.is_multiple_of(2);
        self.steps_since_move += 1;
        match &self.guide {
            Some((guide, paths)) if guided_turn => {
                let (guide, paths) = (*guide, paths.clone());
                let n = self.params.photons_per_pass;
                let stats = self.backend.guided_photon_pass(
                    &self.photon_params(self.guided_pass, n, 1.0),
                    &guide,
                    &paths,
                )?;
                self.guided_pass += 1;
                self.counts.guided.0 += stats.emitted;
                self.counts.guided.1 += stats.deposited;
                self.gather(gather_kind::GUIDED, n as f32, 0.0)
            }
            _ => self.ordinary_pass(),
        }
    }

    /// Moves to `next` (the same scene in its next pose) the way `mode` says.
    pub fn move_to(&mut self, next: Scene, mode: Mode) -> Result<MoveReport, BackendError> {
        let start = Instant::now();
        let mut report = MoveReport {
            mode,
            region_area: 0.0,
            updated: 0,
            kept: 0,
            recorded_paths: 0,
            restarted: None,
            seconds: 0.0,
        };
        let vertices: Vec<_> = self
            .scene
            .moving_vertices()
            .into_iter()
            .chain(next.moving_vertices())
            .collect();
        let region_kind = if mode == Mode::Thesis {
            region_mode::POINT
        } else {
            region_mode::AREA
        };
        let region = match (mode, emitting_region(&self.lights, &vertices, region_kind)) {
            (Mode::Restart, _) => Err("restart mode".to_owned()),
            (_, Err(RegionError::Empty)) => Err("nothing moves".to_owned()),
            (_, Err(RegionError::Unbounded)) => {
                Err("the moving object surrounds a light point".to_owned())
            }
            (_, Ok(region)) => Ok(region),
        };
        let region = match region {
            Ok(r) => r,
            Err(why) => {
                self.frame += 1;
                self.reload(next)?;
                report.restarted = Some(why);
                report.seconds = start.elapsed().as_secs_f64();
                return Ok(report);
            }
        };
        report.region_area = region.area;
        // Thesis mode: raw counts, each pass applied as it comes (eqs 5-7, then 1-3). Area
        // mode: weighted counts, and the passes deferred and applied once as a net change.
        let raw = if mode == Mode::Thesis {
            gather_kind::RAW_COUNT
        } else {
            gather_kind::DEFERRED
        };
        let nc = self.dynamic.region_photons;
        // All compensation passes together remove the region's share once: each gathers with
        // the photons of all of them as N_c (and likewise the region passes re-add it once).
        let total = (nc * self.dynamic.compensation_passes) as f32;
        // Compensation photons in pose A, then (same random numbers) positive ones in pose B:
        // where nothing changed their paths coincide and the two cancel almost exactly.
        for k in 0..self.dynamic.compensation_passes {
            let params = self.photon_params(self.region_pass + k, nc, -1.0);
            let stats = self.backend.region_photon_pass(&params, &region)?;
            self.counts.compensation.0 += stats.emitted;
            self.counts.compensation.1 += stats.deposited;
            self.gather(gather_kind::REGION_NEGATIVE | raw, 0.0, total)?;
        }
        let compiled = compile_scene(&next, self.params.width, self.params.height);
        self.backend.update_scene(&compiled)?;
        self.adopt(next, &compiled);
        self.frame += 1;
        let update = self.backend.update_hit_points(
            &self.eye_params(),
            self.dynamic.update_epsilon * self.extent,
        )?;
        report.updated = update.updated;
        report.kept = update.kept;
        self.direct_light()?;
        for k in 0..self.dynamic.compensation_passes {
            let params = self.photon_params(self.region_pass + k, nc, 1.0);
            let stats = self.backend.region_photon_pass(&params, &region)?;
            self.counts.region.0 += stats.emitted;
            self.counts.region.1 += stats.deposited;
            self.gather(gather_kind::REGION_POSITIVE | raw, 0.0, total)?;
        }
        if mode == Mode::Area {
            self.gather(gather_kind::REGION_APPLY, 0.0, total)?;
        }
        self.region_pass += self.dynamic.compensation_passes;
        // Testing photons: ordinary photons gathered by the updated hit points only; the
        // paths that reached them are rebuilt from their index and guide later passes.
        let n = self.params.photons_per_pass;
        let testing_index = self.photon_pass;
        let stats = self
            .backend
            .photon_pass(&self.photon_params(testing_index, n, 1.0))?;
        self.photon_pass += 1;
        self.counts.testing.0 += stats.emitted;
        self.counts.testing.1 += stats.deposited;
        let landed = self.backend.landing_paths()?;
        self.gather(gather_kind::GUIDED, n as f32, 0.0)?;
        let paths = self.recorded_paths(testing_index, &landed);
        report.recorded_paths = paths.len();
        self.guide = (!paths.is_empty()).then(|| {
            let guide = GuidedEmission {
                cos_cone: self.dynamic.cone_deg.to_radians().cos(),
                beta: self.dynamic.beta,
                paths: paths.len() as u32,
                weighted: u32::from(mode == Mode::Area),
            };
            (guide, paths)
        });
        self.steps_since_move = 0;
        report.seconds = start.elapsed().as_secs_f64();
        Ok(report)
    }

    /// The emissions of the testing paths `landed`, rebuilt from their random numbers; a
    /// stride subsample when there are more than `max_recorded`.
    fn recorded_paths(&self, pass_index: u32, landed: &[u32]) -> Vec<RecordedPath> {
        let stride = landed
            .len()
            .div_ceil(self.dynamic.max_recorded.max(1))
            .max(1);
        landed
            .iter()
            .step_by(stride)
            .map(|&path| {
                let key = StreamKey {
                    seed: self.params.seed,
                    kind: PassKind::Photon,
                    pass_index,
                    path,
                };
                let e = ordinary_emission(&self.lights, &self.materials, &key);
                RecordedPath {
                    origin: e.origin.into(),
                    light: e.light,
                    direction: e.direction.into(),
                    _pad0: 0,
                }
            })
            .collect()
    }

    /// The image of the current statistics.
    pub fn resolve(&mut self) -> Result<Image, BackendError> {
        self.backend.resolve(&ResolveParams {
            width: self.params.width,
            height: self.params.height,
            spp: self.params.spp,
            _pad0: 0,
        })
    }

    /// The backend, for read-back between passes.
    pub fn backend(&mut self) -> &mut dyn DynamicBackend {
        self.backend
    }
}
