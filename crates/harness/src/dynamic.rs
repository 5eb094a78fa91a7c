//! Dynamic frames (ALGORITHM.md 2 and 3): a progressive render carried across object moves.
//!
//! [`Progressive`] owns the pass counters and the recorded paths of one render and drives a
//! [`DynamicBackend`] through them: ordinary passes, a move with compensation photons (thesis,
//! area or difference mode), and the passes that follow a move (guided and ordinary,
//! alternating). The restart mode is simply a new [`Progressive`] on the new pose.
//!
//! Difference mode is ours (ALGORITHM.md 3, "Convergence", names the gap it closes): region
//! photons only cover paths whose first segment crosses the emitting rectangle, so light that
//! meets the object after a bounce stays stale. Ordinary photons traced in pose A (negative)
//! and pose B (positive) with the same random numbers coincide wherever the move changed
//! nothing, so their deferred sum is exactly the change of every path: unbiased, at the price
//! of tracing the whole emission twice.

use glam::Vec3;
use ppm_core::compile::{CompiledScene, compile_scene};
use ppm_core::emission::ordinary_emission;
use ppm_core::image::Image;
use ppm_core::layout::{
    DirectLightParams, EmissionRegion, EyePassParams, GatherParams, GpuLight, GpuMaterial,
    GuidedEmission, PhotonPassParams, RecordedPath, ResolveParams, first_hit, gather_kind,
    region_mode,
};
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::passes::{BackendError, DynamicBackend};
use ppm_core::region::{RegionError, emitting_region};
use ppm_core::rng::{DIFFERENCE_PASS_BASE, PassKind, StreamKey};
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
    /// Ours, unbiased: area mode's guided passes, but the compensation traces ordinary photons
    /// in both poses with the same random numbers, so every path the move changed is removed
    /// and re-added, not only those whose first segment crosses the emitting rectangle.
    Difference,
}

impl Mode {
    /// Every mode, in report order.
    pub const ALL: [Mode; 4] = [Mode::Restart, Mode::Thesis, Mode::Area, Mode::Difference];

    /// The mode's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Restart => "restart",
            Mode::Thesis => "thesis",
            Mode::Area => "area",
            Mode::Difference => "difference",
        }
    }
}

/// What compensates a move: region photons through the emitting rectangle (thesis and area
/// modes) or difference photons over the whole emission (difference mode).
enum Compensation {
    Region {
        region: EmissionRegion,
        /// Thesis mode's raw counts applied pass by pass; otherwise weighted and deferred.
        raw: bool,
    },
    Difference,
}

/// Settings of the dynamic passes.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicParams {
    /// Compensation passes (and as many positive region passes) per move (thesis and area).
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
    /// Difference passes per move (each one negative and one positive ordinary pass).
    pub difference_passes: u32,
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
            difference_passes: 8,
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
    difference_pass: u32,
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
            difference_pass: 0,
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
        let plan = match self.compensation_plan(mode, &vertices) {
            Ok(plan) => plan,
            Err(why) => {
                self.frame += 1;
                self.reload(next)?;
                report.restarted = Some(why);
                report.seconds = start.elapsed().as_secs_f64();
                return Ok(report);
            }
        };
        if let Compensation::Region { region, .. } = &plan {
            report.region_area = region.area;
        }
        // Negative photons in pose A, then (same random numbers) positive ones in pose B:
        // where nothing changed their paths coincide and the two cancel almost exactly.
        self.compensate(&plan, gather_kind::REGION_NEGATIVE)?;
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
        self.compensate(&plan, gather_kind::REGION_POSITIVE)?;
        // Deferred passes are applied once, as a net change (none when none ran).
        let (ran, deferred) = match plan {
            Compensation::Region { raw, .. } => {
                self.region_pass += self.dynamic.compensation_passes;
                (self.dynamic.compensation_passes, !raw)
            }
            Compensation::Difference => {
                self.difference_pass += self.dynamic.difference_passes;
                (self.dynamic.difference_passes, true)
            }
        };
        if deferred && ran > 0 {
            self.gather(gather_kind::REGION_APPLY, 0.0, 0.0)?;
        }
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
                weighted: u32::from(mode != Mode::Thesis),
            };
            (guide, paths)
        });
        self.steps_since_move = 0;
        report.seconds = start.elapsed().as_secs_f64();
        Ok(report)
    }

    /// How `mode` compensates a move of `vertices` (both poses), or why it must restart.
    fn compensation_plan(&self, mode: Mode, vertices: &[Vec3]) -> Result<Compensation, String> {
        let kind = match mode {
            Mode::Restart => return Err("restart mode".to_owned()),
            Mode::Difference if vertices.is_empty() => return Err("nothing moves".to_owned()),
            Mode::Difference => return Ok(Compensation::Difference),
            Mode::Thesis => region_mode::POINT,
            Mode::Area => region_mode::AREA,
        };
        match emitting_region(&self.lights, vertices, kind) {
            Ok(region) => Ok(Compensation::Region {
                region,
                raw: mode == Mode::Thesis,
            }),
            Err(RegionError::Empty) => Err("nothing moves".to_owned()),
            Err(RegionError::Unbounded) => {
                Err("the moving object surrounds a light point".to_owned())
            }
        }
    }

    /// All negative (pose A) or all positive (pose B) passes of a move, gathered as `kind`.
    /// Together the passes of one sign remove (or re-add) their share once: each gathers with
    /// the photons of all of them as its `N_c`.
    fn compensate(&mut self, plan: &Compensation, kind: u32) -> Result<(), BackendError> {
        let sign = if kind == gather_kind::REGION_NEGATIVE {
            -1.0
        } else {
            1.0
        };
        match plan {
            Compensation::Region { region, raw } => {
                // Thesis: raw counts, each pass applied as it comes (eqs 5-7, then 1-3). Area:
                // weighted counts, deferred and applied once as a net change.
                let flag = if *raw {
                    gather_kind::RAW_COUNT
                } else {
                    gather_kind::DEFERRED
                };
                let nc = self.dynamic.region_photons;
                let total = (nc * self.dynamic.compensation_passes) as f32;
                for k in 0..self.dynamic.compensation_passes {
                    let params = self.photon_params(self.region_pass + k, nc, sign);
                    let stats = self.backend.region_photon_pass(&params, region)?;
                    self.count_compensation(kind, stats.emitted, stats.deposited);
                    self.gather(kind | flag, 0.0, total)?;
                }
            }
            Compensation::Difference => {
                // Ordinary photons, each standing for `emitted / total` ordinary photons (path
                // weight 1); deferred, so only the paths the move changed leave a net change.
                let n = self.params.photons_per_pass;
                let total = (n * self.dynamic.difference_passes) as f32;
                for k in 0..self.dynamic.difference_passes {
                    let index = DIFFERENCE_PASS_BASE + self.difference_pass + k;
                    let stats = self
                        .backend
                        .photon_pass(&self.photon_params(index, n, sign))?;
                    self.count_compensation(kind, stats.emitted, stats.deposited);
                    self.gather(kind | gather_kind::DEFERRED, 0.0, total)?;
                }
            }
        }
        Ok(())
    }

    fn count_compensation(&mut self, kind: u32, emitted: u64, deposited: u64) {
        let counts = if kind == gather_kind::REGION_NEGATIVE {
            &mut self.counts.compensation
        } else {
            &mut self.counts.region
        };
        counts.0 += emitted;
        counts.1 += deposited;
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
