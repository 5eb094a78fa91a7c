//! The CPU backend: every pass of ppm-core's contract, parallel over rayon's thread pool.
//!
//! Each pass lives in a module of its own name whose `*_main` function works on the same flat
//! slices a GPU backend binds; [`CpuBackend`] only owns the buffers and calls them. Results do
//! not depend on the number of threads: work items draw counter-based random numbers and write
//! only their own slots, and photons are concatenated and filed in path order.

#![warn(missing_docs)]

mod camera_move;
mod direct_light;
mod eye_pass;
mod gather_pass;
mod hit_point_update;
mod local_move;
mod path_record;
mod photon_grid;
mod photon_pass;
mod photon_search;
mod resolve;
pub mod trace;

use camera_move::CameraInProgress;
use local_move::{KnownPairs, MoveInProgress, Stage};
use path_record::PathRecord;
use photon_grid::{MapContents, PhotonGrid, build_photon_grid};
use photon_pass::{Deposits, photon_pass_main};
use photon_search::{PhotonMap, for_photons_in_disc};
use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::check::check_hit_points;
use ppm_core::compile::CompiledScene;
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::{
    ChainLight, DirectLightParams, EyePassParams, GatherParams, GpuCamera, HitPoint, Photon,
    PhotonPassParams, ResolveParams, SlotBounds,
};
use ppm_core::layout::{eye_flags, hit_flags, photon_flags};
use ppm_core::local_move::LocalMove;
use ppm_core::passes::{
    Backend, BackendError, DirectLight, DirectStats, EyePass, EyeStats, GatherPass, GatherStats,
    PhotonPass, PhotonStats, RandomSource, ReadBack, Resolve, SceneUpload,
};
use ppm_core::passes::{
    DynamicBackend, LocalMoveStats, LocalMoves, UpdateStats, check_gather_kind, crossed_mask_words,
};
use ppm_core::photon_path::KeptPass;
use rayon::prelude::*;
use std::sync::atomic::AtomicU32;
use trace::SceneData;

/// The rayon backend. Runs on the current rayon pool: install it in a sized pool to choose the
/// thread count.
#[derive(Default)]
pub struct CpuBackend {
    scene: Option<(SceneData, GpuCamera)>,
    hit_points: Vec<HitPoint>,
    /// The box of each slot's eye-path vertices (eye passes that record it).
    slot_bounds: Vec<SlotBounds>,
    /// What each slot's eye path found at glossy bounces; empty for a scene without glossy
    /// surfaces.
    chain_light: Vec<ChainLight>,
    /// The loaded scene has glossy surfaces (`SceneFeatures::glossy`).
    glossy: bool,
    /// Squared radius new hit points start with (from the last eye pass).
    r2_initial: f32,
    photons: Vec<Photon>,
    /// Path weight per deposit, kept by region passes only.
    weights: Option<Vec<f32>>,
    /// Per deposit, its pose-A partner (position, luminance; zero for none) where a pass
    /// paired its deposits ([`photon_flags::PAIR_DEPOSITS`]).
    partners: Option<Vec<[f32; 4]>>,
    /// Deposits (indices into `photons`) the grid leaves out: both of each pair that cancels
    /// (`ppm_core::update::pairing::Partner::cancels`), which would add nothing but rounding
    /// to a gather (a third of a cornell-box drag step's correction).
    cancelled: Vec<u32>,
    /// The last photon pass's `gather_r2_floor`.
    r2_floor: f32,
    /// The gather kind the last photon pass named (none since the scene was loaded or
    /// updated).
    map_kind: Option<u32>,
    /// The gather kind and floor (its bits) of the last photon pass while no eye pass or
    /// gather has consumed it: what a pass with [`photon_flags::ADD_TO_MAP`] adds to.
    unconsumed: Option<(u32, u32)>,
    /// Deferred region photons per hit point (area mode).
    pending: Vec<gather_pass::Pending>,
    /// The photon map's grid: `Indexed` once built from the last pass's deposits (at the first
    /// gather after it, so a perturbation through [`CpuBackend::photons_mut`] reaches it).
    grid: PhotonIndex,
    /// The crossed-path mask: one bit per path of the passes that record it, kept across
    /// scene updates so that pose B reads what pose A wrote.
    crossed: Vec<AtomicU32>,
    /// Where the last photon pass's own deposits start in `photons` (after those of the pass
    /// it was added to, [`photon_flags::ADD_TO_MAP`]).
    last_pass_from: usize,
    /// Photon passes stored since the backend was made: names the pass whose deposits
    /// `photons` holds.
    passes_stored: u64,
    /// The paths of the last ordinary pass that asked to keep them, while the pose they were
    /// traced in is loaded, and the pass they are (their deposits are `photons` while
    /// `passes_stored` names it).
    paths: Option<(u64, PathRecord)>,
    /// The local move in progress, between its first pass and its last.
    moving: Option<MoveInProgress>,
    /// The pairs the last local move traced in its pose B, for the next move's pose A.
    known_pairs: Option<KnownPairs>,
    /// The camera move in progress, between its first pass and its last.
    camera_moving: Option<CameraInProgress>,
}

/// Whether the current photons are indexed yet.
#[derive(Default)]
enum PhotonIndex {
    /// No photon pass since the scene was loaded or updated.
    #[default]
    NoPass,
    /// A photon pass ran; its deposits are not filed yet.
    Pending,
    /// Its deposits, filed.
    Indexed(PhotonGrid),
}

impl CpuBackend {
    /// A backend with no scene loaded.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current photon map's records, writable: lets a debugging tool or a test perturb
    /// a pass between photon tracing and gathering (the grid keeps indexing the same slots).
    pub fn photons_mut(&mut self) -> &mut [Photon] {
        &mut self.photons
    }
}

/// [`check_hit_points`] over the slots in parallel chunks: the first failing chunk, by slot
/// order, is reported, so the error is the same whatever the threads.
fn check_slots(pass: &'static str, hit_points: &[HitPoint]) -> Result<(), BackendError> {
    const CHUNK: usize = 4096;
    let bad = hit_points
        .par_chunks(CHUNK)
        .position_first(|chunk| check_hit_points(pass, chunk).is_err());
    match bad {
        None => Ok(()),
        Some(c) => match check_hit_points(pass, &hit_points[c * CHUNK..]) {
            Err(BackendError::NonFinite {
                field,
                index,
                pixel,
                value,
                ..
            }) => Err(BackendError::NonFinite {
                pass,
                field,
                index: c * CHUNK + index,
                pixel,
                value,
            }),
            other => other,
        },
    }
}

/// The loaded scene, or the error for a pass called before `load_scene`.
fn loaded<'a>(
    scene: &'a Option<(SceneData, GpuCamera)>,
    pass: &'static str,
) -> Result<&'a (SceneData, GpuCamera), BackendError> {
    scene.as_ref().ok_or(BackendError::OutOfOrder {
        pass,
        needs: "load_scene",
    })
}

impl SceneUpload for CpuBackend {
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.scene = Some((SceneData::new(scene), scene.camera));
        self.glossy = scene.features.glossy;
        self.hit_points.clear();
        self.slot_bounds.clear();
        self.chain_light.clear();
        self.photons.clear();
        self.last_pass_from = 0;
        self.weights = None;
        self.partners = None;
        self.cancelled.clear();
        self.grid = PhotonIndex::NoPass;
        self.map_kind = None;
        self.unconsumed = None;
        self.paths = None;
        self.moving = None;
        self.known_pairs = None;
        self.camera_moving = None;
        Ok(())
    }
}

impl CpuBackend {
    /// Grows the crossed-path mask to hold the bits a pass that records it writes; the new
    /// bits are set, so a pass that culls without its record traces every path.
    fn fit_crossed_mask(&mut self, params: &PhotonPassParams) -> Result<(), BackendError> {
        if params.flags & photon_flags::RECORD_CROSSED == 0 {
            return Ok(());
        }
        let words = crossed_mask_words(params)? as usize;
        if self.crossed.len() < words {
            self.crossed.resize_with(words, || AtomicU32::new(u32::MAX));
        }
        Ok(())
    }

    /// Files the deposits of the pass `params` as the current photon map.
    fn store(
        &mut self,
        params: &PhotonPassParams,
        deposits: Deposits,
    ) -> Result<PhotonStats, BackendError> {
        if let Some((i, p)) = deposits
            .photons
            .iter()
            .enumerate()
            .find(|(_, p)| !p.power.iter().chain(&p.position).all(|v| v.is_finite()))
        {
            return Err(BackendError::NonFinitePhoton {
                pass: "photon",
                index: i,
                path: p.path,
                value: format!("power {:?} at {:?}", p.power, p.position),
            });
        }
        self.grid = PhotonIndex::Pending;
        self.map_kind = Some(params.gather_kind);
        self.r2_floor = params.gather_r2_floor;
        if params.flags & photon_flags::ADD_TO_MAP != 0 {
            // Pose A's deposits are the last pass's, this pass's follow them.
            let from = self.last_pass_from as u32;
            self.cancelled
                .extend(deposits.cancelled.iter().map(|&i| from + i));
            self.last_pass_from = self.photons.len();
            if let Some(added) = deposits.partners {
                let mut partners = self.partners.take().unwrap_or_default();
                partners.resize(self.photons.len(), [0.0; 4]);
                partners.extend(added);
                self.partners = Some(partners);
            } else if let Some(partners) = &mut self.partners {
                partners.resize(partners.len() + deposits.photons.len(), [0.0; 4]);
            }
            self.photons.extend(deposits.photons);
        } else {
            // Pairs cancel in the map only where it holds both of them.
            self.last_pass_from = 0;
            self.photons = deposits.photons;
            self.partners = deposits.partners;
            self.cancelled.clear();
        }
        self.passes_stored += 1;
        let unweighted = deposits.weights.is_none();
        self.weights = deposits.weights;
        self.unconsumed =
            unweighted.then_some((params.gather_kind, params.gather_r2_floor.to_bits()));
        Ok(deposits.stats)
    }
}

impl EyePass for CpuBackend {
    fn eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError> {
        let (scene, camera) = loaded(&self.scene, "eye")?;
        let slots = camera.width as usize * camera.height as usize * params.spp as usize;
        let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
        if keep && self.hit_points.len() != slots {
            return Err(BackendError::OutOfOrder {
                pass: "eye",
                needs: "an eye pass that starts the slots fresh",
            });
        }
        self.unconsumed = None;
        let mut hit_points = std::mem::take(&mut self.hit_points);
        hit_points.resize(slots, HitPoint::default());
        self.slot_bounds.resize(slots, SlotBounds::NOTHING);
        self.chain_light
            .resize(if self.glossy { slots } else { 0 }, ChainLight::NONE);
        let stats = eye_pass::eye_pass_main(
            params,
            camera,
            scene,
            &mut hit_points,
            Some(&mut self.slot_bounds),
            self.glossy.then_some(&mut self.chain_light[..]),
        );
        self.hit_points = hit_points;
        if !keep {
            self.pending = vec![[0.0; 4]; slots];
            self.r2_initial = params.r2_initial;
        }
        if let Some(moving) = &mut self.camera_moving {
            moving.traced = !keep;
        }
        check_slots("eye", &self.hit_points)?;
        Ok(stats)
    }
}

impl DirectLight for CpuBackend {
    fn direct_light(&mut self, params: &DirectLightParams) -> Result<DirectStats, BackendError> {
        let (scene, _) = loaded(&self.scene, "direct light")?;
        let stats =
            direct_light::direct_light_main(params, scene, &mut self.hit_points, &self.chain_light);
        check_slots("direct light", &self.hit_points)?;
        Ok(stats)
    }
}

impl PhotonPass for CpuBackend {
    fn photon_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        self.fit_crossed_mask(params)?;
        let (scene, _) = loaded(&self.scene, "photon")?;
        let adds = params.flags & photon_flags::ADD_TO_MAP != 0;
        let same = Some((params.gather_kind, params.gather_r2_floor.to_bits()));
        if adds && (self.unconsumed != same || source.keeps_weights()) {
            return Err(BackendError::OutOfOrder {
                pass: "photon (added to the map)",
                needs: "an unconsumed photon pass of the same gather kind and floor, without path weights",
            });
        }
        let answer = self
            .paths
            .as_ref()
            .filter(|(pass, _)| *pass == self.passes_stored)
            .and_then(|(_, r)| Some((r, r.answers(params, source)?)));
        let mut deposits = match answer {
            Some((record, sign)) => {
                record.replay(params, scene, sign, &self.photons, &self.crossed)
            }
            None => {
                // A pass that keeps its paths writes them into the last record's memory.
                let spare = match KeptPass::wanted(params, source) {
                    true => self
                        .paths
                        .take()
                        .map_or_else(Vec::new, |(_, r)| r.into_batches()),
                    false => Vec::new(),
                };
                let pose_a = &self.photons[self.last_pass_from..];
                photon_pass_main(params, scene, source, &self.crossed, spare, pose_a)
            }
        };
        let paths = deposits.paths.take();
        let stats = self.store(params, deposits)?;
        if let Some(paths) = paths {
            self.paths = Some((self.passes_stored, paths));
        }
        Ok(stats)
    }
}

/// The last photon pass's grid, built now if it is not yet.
fn indexed<'a>(
    index: &'a mut PhotonIndex,
    contents: MapContents,
    hit_points: &[HitPoint],
    r2_floor: f32,
    pass: &'static str,
) -> Result<&'a PhotonGrid, BackendError> {
    if let PhotonIndex::Pending = index {
        let grid = build_photon_grid(contents, hit_points, r2_floor);
        *index = PhotonIndex::Indexed(grid);
    }
    match index {
        PhotonIndex::Indexed(grid) => Ok(grid),
        _ => Err(BackendError::OutOfOrder {
            pass,
            needs: "a photon pass",
        }),
    }
}

impl LocalMoves for CpuBackend {
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        // The same pose with other movers' boxes (a local move's pose A) keeps its data and
        // the paths traced in it.
        match &mut self.scene {
            // A camera move changes no photon path: the paths kept stay the pass's.
            Some((data, camera)) if data.same_pose(scene) => {
                data.movers.clone_from(&scene.movers);
                *camera = scene.camera;
            }
            _ => {
                self.scene = Some((SceneData::new(scene), scene.camera));
                self.paths = None;
            }
        }
        // The photons stay for a pass that adds to them; until one does, nothing gathers them.
        self.grid = PhotonIndex::NoPass;
        self.map_kind = None;
        // A local move begun in pose A goes on in this pose, its pose B.
        if let Some(moving) = &mut self.moving
            && matches!(moving.stage, Stage::Begun)
        {
            moving.stage = Stage::PoseB;
        }
        Ok(())
    }

    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        let (scene, _) = loaded(&self.scene, "local move")?;
        if self.hit_points.is_empty() {
            return Err(BackendError::OutOfOrder {
                pass: "local move",
                needs: "an eye pass",
            });
        }
        local_move::begin_main(&mut self.hit_points, &self.slot_bounds, request);
        self.moving = Some(MoveInProgress {
            request: request.clone(),
            before: scene.clone(),
            stage: Stage::Begun,
        });
        Ok(())
    }

    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        let (scene, camera) = loaded(&self.scene, "local resets")?;
        let Some(moving) = self
            .moving
            .as_mut()
            .filter(|m| matches!(m.stage, Stage::PoseB))
        else {
            return Err(BackendError::OutOfOrder {
                pass: "local resets",
                needs: "a local move begun in pose A, then the scene updated to pose B",
            });
        };
        let (stats, finite) = local_move::resets_main(
            &mut self.hit_points,
            &self.slot_bounds,
            (scene, camera),
            &moving.request,
        );
        moving.stage = Stage::Reset;
        if !finite {
            check_slots("local resets", &self.hit_points)?;
        }
        Ok(stats)
    }

    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        let (scene, camera) = loaded(&self.scene, "local direct change")?;
        let Some(moving) = self.moving.take_if(|m| matches!(m.stage, Stage::Reset)) else {
            return Err(BackendError::OutOfOrder {
                pass: "local direct change",
                needs: "the local resets",
            });
        };
        let (stats, pairs, finite) = local_move::direct_change_main(
            &mut self.hit_points,
            (&moving.before, scene, camera),
            &moving.request,
            self.known_pairs.as_ref(),
        );
        self.known_pairs = Some(pairs);
        if !finite {
            check_slots("local direct change", &self.hit_points)?;
        }
        Ok(stats)
    }

    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        loaded(&self.scene, "camera move")?;
        if self.hit_points.is_empty() {
            return Err(BackendError::OutOfOrder {
                pass: "camera move",
                needs: "an eye pass",
            });
        }
        // Pairs were traced through the old view's pixels; a move in progress ends here.
        self.known_pairs = None;
        self.moving = None;
        self.camera_moving = Some(CameraInProgress {
            request: *request,
            before: self.hit_points.clone(),
            before_bounds: self.slot_bounds.clone(),
            traced: false,
        });
        Ok(())
    }

    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError> {
        let (scene, camera) = loaded(&self.scene, "inherit light")?;
        let moving = match self.camera_moving.take() {
            Some(m) if m.traced && *camera == m.request.after => m,
            Some(m) if m.traced => {
                self.camera_moving = Some(m);
                return Err(BackendError::OutOfOrder {
                    pass: "inherit light",
                    needs: "the scene update to the new camera",
                });
            }
            other => {
                self.camera_moving = other;
                return Err(BackendError::OutOfOrder {
                    pass: "inherit light",
                    needs: "begin_camera_move, then an eye pass that starts the slots fresh",
                });
            }
        };
        let stats = camera_move::inherit_main(
            &mut self.hit_points,
            &mut self.slot_bounds,
            &scene.materials,
            &moving,
        );
        check_slots("inherit light", &self.hit_points)?;
        Ok(stats)
    }
}

impl DynamicBackend for CpuBackend {
    fn update_hit_points(
        &mut self,
        params: &EyePassParams,
        epsilon: f32,
    ) -> Result<UpdateStats, BackendError> {
        let (scene, camera) = loaded(&self.scene, "hit-point update")?;
        if self.hit_points.is_empty() {
            return Err(BackendError::OutOfOrder {
                pass: "hit-point update",
                needs: "an eye pass",
            });
        }
        let stats = hit_point_update::update_hit_points_main(
            params,
            camera,
            scene,
            epsilon,
            &mut self.hit_points,
            &mut self.pending,
            (!self.chain_light.is_empty()).then_some(&mut self.chain_light[..]),
        );
        self.r2_initial = params.r2_initial;
        check_slots("hit-point update", &self.hit_points)?;
        Ok(stats)
    }

    fn landing_paths(&mut self) -> Result<Vec<u32>, BackendError> {
        let grid = indexed(
            &mut self.grid,
            MapContents {
                photons: &self.photons,
                partners: self.partners.as_deref(),
                left_out: &self.cancelled,
            },
            &self.hit_points,
            self.r2_floor,
            "landing paths",
        )?;
        let map = PhotonMap {
            grid,
            weights: None,
            r2_floor: self.r2_floor,
        };
        let mut paths: Vec<u32> = self
            .hit_points
            .par_iter()
            .filter(|h| h.is_valid() && h.flags & hit_flags::UPDATED != 0)
            .flat_map_iter(|hp| {
                let mut found = Vec::new();
                for_photons_in_disc(hp, &map, |i, _, _| found.push(self.photons[i].path));
                found
            })
            .collect();
        paths.sort_unstable();
        paths.dedup();
        Ok(paths)
    }
}

impl GatherPass for CpuBackend {
    fn gather_pass(&mut self, params: &GatherParams) -> Result<GatherStats, BackendError> {
        let (scene, _) = loaded(&self.scene, "gather")?;
        check_gather_kind(self.map_kind, params)?;
        self.unconsumed = None;
        let grid = indexed(
            &mut self.grid,
            MapContents {
                photons: &self.photons,
                partners: self.partners.as_deref(),
                left_out: &self.cancelled,
            },
            &self.hit_points,
            self.r2_floor,
            "gather",
        )?;
        let map = PhotonMap {
            grid,
            weights: self.weights.as_deref(),
            r2_floor: self.r2_floor,
        };
        self.pending.resize(self.hit_points.len(), [0.0; 4]);
        let (stats, finite) = gather_pass::gather_pass_main(
            params,
            &scene.materials,
            &map,
            self.r2_initial,
            &mut self.hit_points,
            &mut self.pending,
        );
        if !finite {
            check_slots("gather", &self.hit_points)?;
        }
        Ok(stats)
    }
}

impl Resolve for CpuBackend {
    fn resolve(&mut self, params: &ResolveParams) -> Result<Image, BackendError> {
        Ok(resolve::resolve_main(params, &self.hit_points))
    }
}

impl ReadBack for CpuBackend {
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError> {
        Ok(self.hit_points.clone())
    }

    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError> {
        Ok(self.photons[self.last_pass_from..].to_vec())
    }

    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError> {
        if hit_points.len() != self.hit_points.len() {
            return Err(BackendError::OutOfOrder {
                pass: "write hit points",
                needs: "an eye pass with the same slot count",
            });
        }
        check_slots("write hit points", hit_points)?;
        self.hit_points.copy_from_slice(hit_points);
        Ok(())
    }
}

impl RandomSource for CpuBackend {
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError> {
        Ok(keys
            .iter()
            .map(|k| ppm_core::rng::random_bits(k[0], k[1], k[2], k[3], k[4]))
            .collect())
    }

    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError> {
        Ok(keys
            .iter()
            .map(|k| ppm_core::qmc::sobol_pair_bits(k[0], k[1]))
            .collect())
    }
}

impl Backend for CpuBackend {
    fn name(&self) -> &str {
        "cpu"
    }

    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        Some(self)
    }

    fn dynamic(&mut self) -> Option<&mut dyn DynamicBackend> {
        Some(self)
    }
}
