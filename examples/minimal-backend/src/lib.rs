//! A backend for still frames and local moves, written only against ppm-core's public API: one
//! thread, plain loops, no acceleration beyond the scene's own BVH. It is the executable
//! specification of the `local` tier of the contract (README, "Writing a backend"): copy it,
//! then make each pass fast. Every pass follows docs/algorithm.md, and draws its random
//! numbers exactly as the passes key them ([`ppm_core::rng`]), so a same-seed render matches
//! the CPU backend's slot by slot. The per-item work is ppm-core's, traced through the compiled
//! pose's flattened tree ([`FlatPose`]), as a GPU backend traces it.
//!
//! What each trait asks, and where this file answers it:
//! - [`SceneUpload`]: keep the compiled scene (its buffers are already GPU-shaped).
//! - [`EyePass`]: one eye path per slot to its visible point ([`slot_eye_path`]), and the box
//!   of its vertices ([`extended_bounds`]), which a local move reads.
//! - [`DirectLight`]: emission seen plus light from the lights, and what the eye path's
//!   glossy bounces found ([`slot_direct_light`]).
//! - [`PhotonPass`]: photons from the lights, their deposits in path order
//!   ([`trace_photon_path`]); the thesis's other photon sources are refused.
//! - [`GatherPass`]: each slot's photons within its radius ([`found_in_disc`]), folded in by
//!   [`gather_rule`], which decides every gather kind's policy, for the kind the photon pass
//!   named ([`check_gather_kind`]).
//! - [`Resolve`], [`ReadBack`], [`RandomSource`]: the image, the buffers, the generator.
//! - [`LocalMoves`] (`local.rs`): a local move's passes, each slot by slot through
//!   [`ppm_core::local_move`], and its correction's photons and apply.
//!
//! [`Backend::dynamic`] stays `None`: a move in the thesis's modes restarts on this backend,
//! saying why.

#![warn(missing_docs)]

mod camera;
mod local;

use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::check::check_hit_points;
use ppm_core::compile::CompiledScene;
use ppm_core::direct_light::slot_direct_light;
use ppm_core::emission::PhotonSource;
use ppm_core::eye_path::{extended_bounds, slot_eye_path};
use ppm_core::image::Image;
use ppm_core::layout::{
    ChainLight, DirectLightParams, EyePassParams, GatherParams, GpuMaterial, HitPoint, Photon,
    PhotonPassParams, ResolveParams, SlotBounds, eye_flags,
};
use ppm_core::passes::{
    Backend, BackendError, DirectLight, DirectStats, EyePass, EyeStats, GatherPass, GatherStats,
    LocalMoves, PhotonPass, PhotonStats, RandomSource, ReadBack, Resolve, SceneUpload,
    check_gather_kind,
};
use ppm_core::photon_path::trace_photon_path;
use ppm_core::rng::{StreamKey, random_bits};
use ppm_core::trace::FlatPose;
use ppm_core::update::gather::{Found, SlotState, found_in_disc, gather_rule, gathers};
use ppm_core::update::pairing::Partner;
use ppm_core::update::radiance;

/// The backend's state: the scene, one hit point per slot, and the current photon map.
#[derive(Default)]
pub struct MinimalBackend {
    scene: Option<CompiledScene>,
    hit_points: Vec<HitPoint>,
    /// The box of each slot's eye-path vertices, which a local move reads.
    slot_bounds: Vec<SlotBounds>,
    /// What each slot's eye path found at glossy bounces, for the direct-light pass.
    chain_light: Vec<ChainLight>,
    /// Each slot's deferred sum; a still frame never defers, so it stays zero.
    pending: Vec<[f32; 4]>,
    photons: Vec<Photon>,
    /// The gather kind the last photon pass named (none before one).
    map_kind: Option<u32>,
    /// The last photon pass's `gather_r2_floor`.
    r2_floor: f32,
    /// The initial squared radius of the last fresh eye pass.
    r2_initial: f32,
    /// The local move in progress, from its first pass to the direct-light change.
    moving: Option<local::Moving>,
    /// A local move's correction photons, from pose A's to the apply.
    correction: Option<local::Correction>,
    /// The camera move in progress, from its first pass to the inheritance.
    camera_moving: Option<camera::CameraMoving>,
}

impl MinimalBackend {
    /// An empty backend; `load_scene` comes first.
    pub fn new() -> Self {
        Self::default()
    }
}

/// The loaded scene, or the error for a pass called before `load_scene`.
fn loaded<'a>(
    scene: &'a Option<CompiledScene>,
    pass: &'static str,
) -> Result<&'a CompiledScene, BackendError> {
    scene.as_ref().ok_or(BackendError::OutOfOrder {
        pass,
        needs: "load_scene",
    })
}

impl SceneUpload for MinimalBackend {
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.scene = Some(scene.clone());
        self.hit_points.clear();
        self.photons.clear();
        self.map_kind = None;
        self.moving = None;
        self.correction = None;
        Ok(())
    }
}

impl EyePass for MinimalBackend {
    fn eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError> {
        let scene = loaded(&self.scene, "eye")?;
        let camera = &scene.camera;
        let slots = (camera.width * camera.height * params.spp) as usize;
        let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
        if keep && self.hit_points.len() != slots {
            return Err(BackendError::OutOfOrder {
                pass: "eye",
                needs: "an eye pass that starts the slots fresh",
            });
        }
        if !keep {
            self.hit_points = vec![HitPoint::default(); slots];
            self.slot_bounds = vec![SlotBounds::NOTHING; slots];
            self.chain_light = vec![ChainLight::NONE; slots];
            self.pending = vec![[0.0; 4]; slots];
            self.r2_initial = params.r2_initial;
        }
        if let Some(moving) = &mut self.camera_moving {
            moving.traced = !keep;
        }
        let record = params.flags & eye_flags::RECORD_BOUNDS != 0;
        let mut stats = EyeStats::default();
        for (slot, ((hp, chain), bounds)) in self
            .hit_points
            .iter_mut()
            .zip(&mut self.chain_light)
            .zip(&mut self.slot_bounds)
            .enumerate()
        {
            let path = slot_eye_path(params, camera, &FlatPose::new(scene), slot as u32, hp);
            *chain = path.chain.unwrap_or(ChainLight::NONE);
            if record {
                *bounds = extended_bounds(*bounds, hp, path.vertices);
            }
            stats.rays += path.rays;
            stats.hit_points += u64::from(hp.is_valid());
        }
        check_hit_points("eye", &self.hit_points)?;
        Ok(stats)
    }
}

impl DirectLight for MinimalBackend {
    fn direct_light(&mut self, params: &DirectLightParams) -> Result<DirectStats, BackendError> {
        let scene = loaded(&self.scene, "direct light")?;
        let mut stats = DirectStats::default();
        for (slot, (hp, chain)) in self
            .hit_points
            .iter_mut()
            .zip(&self.chain_light)
            .enumerate()
        {
            stats.rays += slot_direct_light(params, &FlatPose::new(scene), hp, chain, slot as u32);
        }
        check_hit_points("direct light", &self.hit_points)?;
        Ok(stats)
    }
}

impl PhotonPass for MinimalBackend {
    fn photon_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        source.lights_only("minimal")?;
        let (photons, stats) = trace_photons(loaded(&self.scene, "photon")?, params, source)?;
        self.photons = photons;
        self.map_kind = Some(params.gather_kind);
        self.r2_floor = params.gather_r2_floor;
        Ok(stats)
    }
}

/// The photons of the pass `params` from `source` in `scene`, path by path
/// ([`trace_photon_path`]), in path order; refused where one is not finite.
fn trace_photons(
    scene: &CompiledScene,
    params: &PhotonPassParams,
    source: &PhotonSource<'_>,
) -> Result<(Vec<Photon>, PhotonStats), BackendError> {
    let mut stats = PhotonStats {
        emitted: u64::from(params.photon_count),
        ..Default::default()
    };
    let mut photons = Vec::new();
    // No light, no photon: the pass emits its count and deposits nothing.
    if !scene.lights.is_empty() {
        let pose = FlatPose::new(scene);
        for local in 0..params.photon_count {
            let key = StreamKey {
                seed: params.seed,
                kind: source.pass_kind(),
                pass_index: params.pass_index,
                path: params.first_path + local,
            };
            let emission = source.emit(&scene.lights, &scene.materials, &key);
            if emission.weight > 0.0 {
                let path = (&key, &emission);
                let (rays, _) =
                    trace_photon_path(&pose, params, &scene.movers, path, &mut photons, None);
                stats.rays += rays;
            }
        }
    }
    if let Some((index, p)) = photons
        .iter()
        .enumerate()
        .find(|(_, p)| !p.power.iter().chain(&p.position).all(|v| v.is_finite()))
    {
        return Err(BackendError::NonFinitePhoton {
            pass: "photon",
            index,
            path: p.path,
            value: format!("power {:?} at {:?}", p.power, p.position),
        });
    }
    stats.deposited = photons.len() as u64;
    Ok((photons, stats))
}

impl GatherPass for MinimalBackend {
    fn gather_pass(&mut self, params: &GatherParams) -> Result<GatherStats, BackendError> {
        let scene = loaded(&self.scene, "gather")?;
        check_gather_kind(self.map_kind, params)?;
        let map = Map {
            photons: &self.photons,
            partners: &[],
            r2_floor: self.r2_floor,
        };
        let stats = fold(
            params,
            (&mut self.hit_points, &mut self.pending),
            (&scene.materials, self.r2_initial),
            &map,
        );
        check_hit_points("gather", &self.hit_points)?;
        Ok(stats)
    }
}

/// Photons a gather folds in: each with its pose-A partner where a correction paired them,
/// and the floor of the disc a slot searches at least.
struct Map<'a> {
    photons: &'a [Photon],
    /// Empty, or one per photon.
    partners: &'a [Option<Partner>],
    r2_floor: f32,
}

/// One gather of `params.kind` over every slot: what each finds in its disc, every photon
/// tested ([`found_in_disc`]), folded in by [`gather_rule`], which decides every kind's
/// policy.
fn fold(
    params: &GatherParams,
    (hit_points, pending): (&mut [HitPoint], &mut [[f32; 4]]),
    (materials, r2_initial): (&[GpuMaterial], f32),
    map: &Map,
) -> GatherStats {
    let mut stats = GatherStats::default();
    let weights = vec![1.0; map.photons.len()];
    let none = vec![None; map.photons.len()];
    let partners = if map.partners.is_empty() {
        &none[..]
    } else {
        map.partners
    };
    for (hp, pending) in hit_points.iter_mut().zip(pending.iter_mut()) {
        let mut found = Found::default();
        let mut reflectance = [0.0; 3];
        if gathers(hp.flags, params.kind) {
            found = found_in_disc(hp, (map.photons, &weights, partners), map.r2_floor);
            stats.hit_points_reached += u64::from(found.count > 0.0);
            stats.photons_gathered += found.count as u64;
            let f = bsdf::visible_point_f(&materials[hp.material as usize]);
            reflectance = (Vec3::from(hp.throughput) * f).into();
        }
        let before = SlotState::of(hp, *pending);
        let after = gather_rule(params, r2_initial, reflectance, before, &found);
        after.store(hp);
        *pending = after.pending;
    }
    stats
}

impl Resolve for MinimalBackend {
    fn resolve(&mut self, params: &ResolveParams) -> Result<Image, BackendError> {
        let spp = params.spp.max(1) as usize;
        let pixels = self
            .hit_points
            .chunks(spp)
            .map(|slots| {
                let mut sum = [0.0f32; 3];
                for hp in slots {
                    let (direct, flux) = (hp.direct_mean(), radiance(hp.tau, hp.r2, hp.emitted));
                    sum = [0, 1, 2].map(|c| sum[c] + (direct[c] + flux[c]));
                }
                sum.map(|s| s / spp as f32)
            })
            .collect();
        Ok(Image {
            width: params.width,
            height: params.height,
            pixels,
        })
    }
}

impl ReadBack for MinimalBackend {
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError> {
        Ok(self.hit_points.clone())
    }

    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError> {
        Ok(self.photons.clone())
    }

    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError> {
        if hit_points.len() != self.hit_points.len() {
            return Err(BackendError::Unsupported(format!(
                "{} slots written, {} held",
                hit_points.len(),
                self.hit_points.len()
            )));
        }
        check_hit_points("write hit points", hit_points)?;
        self.hit_points = hit_points.to_vec();
        Ok(())
    }
}

impl RandomSource for MinimalBackend {
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError> {
        Ok(keys
            .iter()
            .map(|k| random_bits(k[0], k[1], k[2], k[3], k[4]))
            .collect())
    }

    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError> {
        Ok(keys
            .iter()
            .map(|k| ppm_core::qmc::sobol_pair_bits(k[0], k[1]))
            .collect())
    }
}

impl Backend for MinimalBackend {
    fn name(&self) -> &str {
        "minimal"
    }

    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        Some(self)
    }
}
