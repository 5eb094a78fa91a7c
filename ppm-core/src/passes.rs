//! The pass contract every backend implements (docs/algorithm.md section 1).
//!
//! One trait per static pass, so that a harness, a conformance check or a debugging tool can
//! name exactly the pass it drives. Each pass takes its `#[repr(C)]` parameter struct from
//! [`crate::layout`], the same bytes a GPU backend uploads as a uniform, and returns counters.
//! A move's photons are the one photon pass with another [`PhotonSource`] and gather kind;
//! a local move's other passes are the methods of [`LocalMoves`], and those of the thesis's
//! modes (docs/algorithm.md section 2) the methods of [`DynamicBackend`]: a backend that
//! renders still frames only leaves both out.

use crate::camera_move::{CameraMove, CameraMoveStats};
use crate::compile::CompiledScene;
use crate::device_time::DeviceTime;
use crate::emission::PhotonSource;
use crate::image::Image;
use crate::layout::{
    DirectLightParams, EyePassParams, GatherParams, HitPoint, Photon, PhotonPassParams,
    ResolveParams, gather_kind,
};
use crate::local_move::{CorrectionApply, CorrectionPhotons, LocalMove};
use thiserror::Error;

/// Why a pass failed.
#[derive(Debug, Error)]
pub enum BackendError {
    /// A pass produced NaN or infinity: reported instead of carried into the image.
    #[error("{pass} pass: {field} of hit point {index} (pixel {pixel}) is not finite: {value}")]
    NonFinite {
        /// Pass that produced it.
        pass: &'static str,
        /// Field name.
        field: &'static str,
        /// Hit-point slot.
        index: usize,
        /// Pixel of the slot.
        pixel: u32,
        /// The value, printed.
        value: String,
    },
    /// A photon pass produced a photon with NaN or infinite power or position.
    #[error("{pass} pass: photon {index} (path {path}) is not finite: {value}")]
    NonFinitePhoton {
        /// Pass that produced it.
        pass: &'static str,
        /// Index of the deposit.
        index: usize,
        /// Path that made it.
        path: u32,
        /// Its power and position, printed.
        value: String,
    },
    /// A pass was called before what it needs (for example a gather before any photon pass).
    #[error("{pass} pass called out of order: {needs}")]
    OutOfOrder {
        /// Pass called.
        pass: &'static str,
        /// What must run first.
        needs: &'static str,
    },
    /// A gather pass named another kind than the photon pass that traced its map
    /// ([`PhotonPassParams::gather_kind`]).
    #[error(
        "gather pass of kind {gather:#x} on a photon map traced for kind {map:#x}: a photon pass names the gather that consumes it"
    )]
    GatherKind {
        /// The kind the photon pass named.
        map: u32,
        /// The kind the gather pass was given.
        gather: u32,
    },
    /// The backend does not implement what the parameters ask for.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The request does not fit the device (buffer size, memory).
    #[error("request exceeds a device limit: {0}")]
    Limit(String),
    /// The device reported an error.
    #[error("device error: {0}")]
    Device(String),
}

/// Counters of an eye pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct EyeStats {
    /// Rays traced (camera rays and specular continuations).
    pub rays: u64,
    /// Slots that now hold a hit point.
    pub hit_points: u64,
}

/// Counters of a direct-light pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct DirectStats {
    /// Shadow rays traced.
    pub rays: u64,
}

/// 32-bit words of the crossed-path mask that `params`'s paths reach (bit `mask_offset +
/// path`, [`crate::layout::photon_flags::RECORD_CROSSED`]); refused when a bit index would not
/// fit 32 bits, as the GPU indexes them.
pub fn crossed_mask_words(params: &PhotonPassParams) -> Result<u64, BackendError> {
    let paths = u64::from(params.first_path) + u64::from(params.photon_count);
    let bits = u64::from(params.mask_offset) + paths;
    if bits > 1 << 32 {
        return Err(BackendError::Limit(format!(
            "crossed-path mask: bit {bits} is past 2^32 (mask_offset {} + paths {paths})",
            params.mask_offset
        )));
    }
    Ok(bits.div_ceil(32))
}

/// Counters of a photon pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PhotonStats {
    /// Photons emitted.
    pub emitted: u64,
    /// Deposits stored in the photon map.
    pub deposited: u64,
    /// Ray segments traced.
    pub rays: u64,
    /// Paths not traced because they would store nothing
    /// ([`crate::layout::photon_flags::CULL_UNCROSSED`]); counted in `emitted` all the same.
    pub culled: u64,
}

impl PhotonStats {
    /// Adds another pass's counters.
    pub fn add(&mut self, other: &PhotonStats) {
        self.emitted += other.emitted;
        self.deposited += other.deposited;
        self.rays += other.rays;
        self.culled += other.culled;
    }
}

/// Counters of a gather pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct GatherStats {
    /// Hit points that found at least one photon.
    pub hit_points_reached: u64,
    /// Photon-to-hit-point contributions summed.
    pub photons_gathered: u64,
}

/// Counters of a hit-point update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct UpdateStats {
    /// Hit points reset because their surface moved or changed.
    pub updated: u64,
    /// Hit points that kept their statistics.
    pub kept: u64,
    /// Eye rays traced.
    pub rays: u64,
}

/// Counters of a local move's passes ([`LocalMoves::local_resets`],
/// [`LocalMoves::local_direct_change`]): what the driver reads back of a move, never the
/// slots.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LocalMoveStats {
    /// Slots started over.
    pub reset: u64,
    /// Slots that kept their statistics.
    pub kept: u64,
    /// Kept slots whose direct light the move may change: their direct sums are corrected.
    pub direct_corrected: u64,
    /// Pixels whose paths past a mirror or glass were probed in pose B.
    pub probed: u64,
    /// Rays traced (probes and paired samples).
    pub rays: u64,
}

/// Receives the scene's buffers (and rebuilds whatever the backend derives from them).
pub trait SceneUpload {
    /// Replaces the scene; hit points and photon map are cleared.
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError>;
}

/// Eye pass (docs/algorithm.md 1.1): the visible point of every slot, `width * height * spp`.
pub trait EyePass {
    /// Traces one eye path per slot and writes its visible point. Without
    /// [`crate::layout::eye_flags::KEEP_STATISTICS`] the slots start fresh (`r2 =
    /// params.r2_initial`, all else zero, the buffer allocated to the camera's size); with it
    /// they keep their statistics (and the `UPDATED` flag) and only the visible point changes.
    /// With [`crate::layout::eye_flags::SAMPLE_LIGHTS`], a path takes a light sample at each
    /// glossy bounce ([`crate::bsdf::glossy_lobe`]) and keeps, beside its slot, what they found
    /// and the weight of the emission at its visible point ([`crate::layout::ChainLight`]),
    /// for the direct-light pass.
    fn eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError>;
}

/// Direct light at every visible point (docs/algorithm.md 1.2).
pub trait DirectLight {
    /// Estimates emission seen (times its [`crate::layout::ChainLight`] weight) plus
    /// reflected direct light at each visible point, times the eye path's throughput (zero
    /// for a slot without one), plus what the path's glossy bounces found, and adds it to the
    /// slot's direct sum as one more iteration, or replaces the sum with it
    /// (`params.accumulate`).
    fn direct_light(&mut self, params: &DirectLightParams) -> Result<DirectStats, BackendError>;
}

/// Photon pass (docs/algorithm.md 1.3, and 2.2, 2.5, 2.6 for a move's photons): emits,
/// traces and stores this pass's photon map, for the gather that `params.gather_kind` names.
pub trait PhotonPass {
    /// Replaces the photon map with the deposits of paths started by `source`, indexed for
    /// gathering. A backend that renders still frames only may refuse every source but
    /// [`PhotonSource::Lights`] ([`PhotonSource::lights_only`]).
    fn photon_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError>;
}

impl PhotonSource<'_> {
    /// Refuses every source but ordinary photons, naming the backend: for a backend whose
    /// [`Backend::dynamic`] is `None`, which the driver never asks for others.
    pub fn lights_only(&self, backend: &str) -> Result<(), BackendError> {
        match self {
            PhotonSource::Lights => Ok(()),
            _ => Err(BackendError::Unsupported(format!(
                "backend '{backend}' traces ordinary photons only, not {} photons",
                self.name()
            ))),
        }
    }
}

/// Gather pass (docs/algorithm.md 1.4): folds the current photon map into the slots, by
/// [`crate::update::gather::gather_rule`].
pub trait GatherPass {
    /// Updates `n`, `r2` and `tau` of the slots that gather this pass's kind and have a
    /// visible point (flux times throughput times BRDF), and adds the pass's photons to
    /// `emitted` of every slot the kind serves, visible point or not (a slot whose eye path
    /// escaped this iteration still counts the photons: its estimate averages over
    /// iterations); fails on a non-finite result, and on a kind other than the one the photon
    /// pass named ([`check_gather_kind`]).
    fn gather_pass(&mut self, params: &GatherParams) -> Result<GatherStats, BackendError>;
}

/// Whether a gather of `params.kind` may consume the map of a photon pass that named
/// `map_kind` (`None`: no photon pass yet). Only [`gather_kind::REGION_APPLY`], which reads
/// no photons, needs no map of its own kind.
pub fn check_gather_kind(map_kind: Option<u32>, params: &GatherParams) -> Result<(), BackendError> {
    if params.kind & gather_kind::KIND_MASK == gather_kind::REGION_APPLY {
        return Ok(());
    }
    match map_kind {
        None => Err(BackendError::OutOfOrder {
            pass: "gather",
            needs: "a photon pass",
        }),
        Some(map) if map != params.kind => Err(BackendError::GatherKind {
            map,
            gather: params.kind,
        }),
        Some(_) => Ok(()),
    }
}

/// Resolve (docs/algorithm.md 1.5): the image from the slots' statistics.
pub trait Resolve {
    /// Averages `direct / iterations + tau / (pi r2 emitted)` over each pixel's slots.
    fn resolve(&mut self, params: &ResolveParams) -> Result<Image, BackendError>;
}

/// Read-back of the buffers a harness compares across backends.
pub trait ReadBack {
    /// The hit-point buffer, slot by slot.
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError>;
    /// The last photon pass's deposits, in path order (of a pass added to the one before it,
    /// [`crate::layout::photon_flags::ADD_TO_MAP`], its own).
    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError>;
    /// Replaces the hit-point buffer (same slot count): seeds extreme states for the stress
    /// suite, resumes a checkpoint and lets a debugging tool replay a recorded state. Slots
    /// with a field that is not finite are refused ([`BackendError::NonFinite`], pass "write
    /// hit points", as [`crate::check::check_hit_points`] names it) and nothing is written:
    /// every pass screens only what it writes, so what is written here is screened here.
    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError>;
}

/// The backend's own twins of [`crate::rng::random_bits`] and [`crate::qmc::sobol_pair_bits`],
/// so a conformance check can pin them to [`crate::rng::TEST_VECTORS`] and
/// [`crate::qmc::TEST_VECTORS`].
pub trait RandomSource {
    /// `random_bits(seed, kind, pass_index, path, dimension)` for each key, computed where the
    /// backend's passes compute it (on the GPU for a GPU backend).
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError>;
    /// `sobol_pair_bits(scramble, index)` for each key, computed where the passes compute it.
    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError>;
}

/// A complete backend: every static pass, read-back, and its random generator.
pub trait Backend:
    SceneUpload + EyePass + DirectLight + PhotonPass + GatherPass + Resolve + ReadBack + RandomSource
{
    /// Short name for reports (`cpu`, `wgpu`).
    fn name(&self) -> &str;

    /// The backend as its own type, for callers that use what it offers beyond this contract
    /// (the viewer draws the wgpu backend's image on its device, with no read-back). `None`
    /// unless the backend opts in.
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        None
    }

    /// The backend's local-move passes (docs/algorithm.md 3b, 3c), for local mode, the move
    /// that keeps what it did not change: a backend that has them returns `Some(self)` (the
    /// conformance suite's `local` tier); one that renders still frames only keeps the
    /// default `None`, and every move then restarts on it.
    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        None
    }

    /// The passes of the thesis's modes besides (docs/algorithm.md 2: region, testing and
    /// guided photons, the hit-point update, the landing paths): a backend that has them
    /// returns `Some(self)` (the `dynamic` tier); without them those modes restart.
    fn dynamic(&mut self) -> Option<&mut dyn DynamicBackend> {
        None
    }

    /// What the backend has not compiled or allocated so far because nothing needed it (a
    /// still render needs no move's pipelines), one line each, bytes named: the render's
    /// report lists it under `left_out`.
    fn not_created(&self) -> Vec<String> {
        Vec::new()
    }

    /// The time the device spent in each kernel of each pass since the last call, as the
    /// device measured it (timestamp queries); `None` where the backend cannot measure it (a
    /// CPU backend, an adapter without timestamps), never zeros.
    fn device_times(&mut self) -> Result<Option<Vec<DeviceTime>>, BackendError> {
        Ok(None)
    }
}

/// A local move's passes (docs/algorithm.md 3b, 3c), in this order: the scene update to
/// pose A with the movers' boxes, [`LocalMoves::begin_local_move`], the correction's pose-A
/// photons ([`LocalMoves::correction_photons`]), the scene update to pose B,
/// [`LocalMoves::local_resets`], [`LocalMoves::local_direct_change`], pose B's photons and
/// [`LocalMoves::apply_correction`]. Each says what it does in its request; a call out of
/// that order is refused by name. A camera move that keeps the light (docs/algorithm.md 3d)
/// is two more: [`LocalMoves::begin_camera_move`] and [`LocalMoves::inherit_light`]. A
/// backend that has them returns `Some(self)` from [`Backend::local_moves`].
pub trait LocalMoves: Backend {
    /// Swaps the geometry under the hit points when an object moves (docs/algorithm.md 2.3):
    /// replaces triangles, BVH, lights and mover boxes with `scene`'s, keeping hit points and
    /// statistics. No gather may follow before a photon pass, but the last pass's photons stay
    /// for one that adds to them ([`crate::layout::photon_flags::ADD_TO_MAP`]).
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError>;

    /// Says that moves (local or of the camera) will follow in the scene held: the backend
    /// may compile or allocate now what they need, so that the first move costs what the
    /// later ones do (the wgpu backend compiles their pipelines on a thread of their own,
    /// while the render goes on). Changes no result. By default nothing.
    fn prepare_moves(&mut self) -> Result<(), BackendError> {
        Ok(())
    }

    /// Starts a local move of `request`'s objects (docs/algorithm.md 3b), in the pose held:
    /// pose A, with the movers' boxes. Each slot gets the disc it gathers the correction
    /// within and, where its direct light may change, `DIRECT_MAY_CHANGE`
    /// ([`prepare_slot`](crate::local_move::prepare_slot)). What the direct-light change needs
    /// of pose A is the backend's to keep: pose A itself, or its half of the pairs traced now.
    /// Then come the correction's pose-A photons, [`LocalMoves::update_scene`] to pose B,
    /// [`LocalMoves::local_resets`] and [`LocalMoves::local_direct_change`].
    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError>;

    /// In pose B, after [`LocalMoves::begin_local_move`] and the scene update: starts over
    /// each slot whose view the move may change ([`view_test`](crate::local_move::view_test),
    /// with pose B's outline over the moved objects' triangles and the
    /// [`probe`](crate::local_move::probe_meets) of the pixels whose paths bounced near them)
    /// and flags it `UPDATED` ([`reset_slot`](crate::local_move::reset_slot)), so the
    /// correction leaves it out; a kept slot keeps everything. Refused out of that order.
    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError>;

    /// In pose B, after [`LocalMoves::local_resets`]: corrects each kept slot flagged
    /// `DIRECT_MAY_CHANGE` by the change of its direct light, estimated by paired samples
    /// in both poses ([`Pair`](crate::local_move::Pair)) and weighed against its history
    /// ([`apply_direct_change`](crate::local_move::apply_direct_change)). Ends the move's own
    /// passes; refused out of that order.
    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError>;

    /// One pose's photons of the move's correction ([`CorrectionPhotons`]): pose A's after
    /// [`LocalMoves::begin_local_move`], held for pose B's, which come after the direct-light
    /// change and join them. No gather reads the photon map between the two; a pose B without
    /// pose A's photons held is refused.
    ///
    /// By default this is the backend's own photon pass with the request's flags
    /// ([`CorrectionPhotons::flagged_pass`]); a backend that keeps the correction apart from its
    /// photon map (as the example backend does) overrides it.
    fn correction_photons(
        &mut self,
        request: &CorrectionPhotons,
    ) -> Result<PhotonStats, BackendError> {
        self.photon_pass(&request.flagged_pass(), &PhotonSource::Lights)
    }

    /// Folds both poses' correction photons into every kept slot at once, each within its
    /// correction disc, into its flux alone (a correction brings no photons to shrink a
    /// radius with), and weighs the slot's history against the correction's variance
    /// ([`crate::update::history_kept`]). Ends the move.
    ///
    /// By default these are the backend's own gather passes of [`CorrectionApply::gathers`],
    /// returning the fold's counts.
    fn apply_correction(&mut self, request: &CorrectionApply) -> Result<GatherStats, BackendError> {
        let [fold, apply] = request.gathers();
        let folded = self.gather_pass(&fold)?;
        self.gather_pass(&apply)?;
        Ok(folded)
    }

    /// Starts a camera move (docs/algorithm.md 3d) in the view held: keeps the slots as they
    /// are (with their bounds, where the backend records them) for the new view to take
    /// over, and forgets what local moves kept of this view (pairs traced through its
    /// pixels). Then come the scene update to `request.after`, an eye pass that starts every
    /// slot fresh, and [`LocalMoves::inherit_light`].
    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError>;

    /// After [`LocalMoves::begin_camera_move`], the scene update to the new camera and an eye
    /// pass that started every slot fresh: each slot not on an edge of the new view
    /// ([`on_an_edge`](crate::camera_move::on_an_edge), tested on the fresh slots before any
    /// inherits) takes over the light of the earlier slots near its visible point
    /// ([`inherit_slot`](crate::camera_move::inherit_slot)), and the kept slots are let go.
    /// Refused out of that order.
    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError>;
}

/// The passes of the thesis's modes (docs/algorithm.md 2), besides the photon pass's other
/// sources ([`PhotonSource::Region`], [`PhotonSource::Guided`]) and gather kinds: a backend
/// that has them returns `Some(self)` from [`Backend::dynamic`].
pub trait DynamicBackend: LocalMoves {
    /// Hit-point update after a move (docs/algorithm.md 2.4): re-runs the eye pass on the
    /// current geometry (with `params` keyed as the last iteration's, so each slot traces the
    /// same sample); a slot whose visible point changed object, validity, or moved more than
    /// `epsilon` starts fresh and is flagged `UPDATED`; the others keep `n`, `r2`, `tau` and
    /// `emitted`. Every slot's direct sum restarts (direct light is recomputed for all).
    /// Flags of earlier updates are cleared.
    fn update_hit_points(
        &mut self,
        params: &EyePassParams,
        epsilon: f32,
    ) -> Result<UpdateStats, BackendError>;

    /// Which testing photons reached updated hit points (docs/algorithm.md 2.6): distinct
    /// path indices, ascending, of the current map's photons that lie within the radius of
    /// an updated hit point.
    fn landing_paths(&mut self) -> Result<Vec<u32>, BackendError>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gather_consumes_only_the_map_of_the_kind_its_photon_pass_named() {
        let gather = |kind| GatherParams {
            kind,
            ..Default::default()
        };
        let deferred = gather_kind::REGION_NEGATIVE | gather_kind::DEFERRED;
        assert!(check_gather_kind(Some(deferred), &gather(deferred)).is_ok());
        assert!(matches!(
            check_gather_kind(Some(gather_kind::REGION_NEGATIVE), &gather(deferred)),
            Err(BackendError::GatherKind {
                map: 1,
                gather: 0x201
            })
        ));
        assert!(matches!(
            check_gather_kind(None, &gather(gather_kind::ORDINARY)),
            Err(BackendError::OutOfOrder { .. })
        ));
        // An apply reads the pending sums, not the map.
        let apply = gather(gather_kind::REGION_APPLY | gather_kind::ADD_FLUX);
        assert!(check_gather_kind(Some(deferred), &apply).is_ok());
        assert!(check_gather_kind(None, &apply).is_ok());
    }

    #[test]
    fn a_still_frame_backend_refuses_a_move_s_photon_sources_by_name() {
        assert!(PhotonSource::Lights.lights_only("mine").is_ok());
        let refused = PhotonSource::Region(Default::default())
            .lights_only("mine")
            .unwrap_err()
            .to_string();
        assert_eq!(
            refused,
            "unsupported: backend 'mine' traces ordinary photons only, not region photons"
        );
    }
}
