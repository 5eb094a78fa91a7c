//! The wgpu backend: every pass of ppm-core's contract as WGSL compute shaders.
//!
//! Each pass is one WGSL file in `shaders/passes/`, assembled at build time with the shared
//! modules it imports (`shaders/shared/`, twins of ppm-core's `rng`, `sampling`, `geometry`,
//! `bsdf`, `update` and `grid`), so a same-seed run traces the CPU backend's paths up to
//! rounding. Only baseline WebGPU features are required: no f64, no float atomics; integer
//! atomics count and scatter, and every order that feeds a float sum is made deterministic.
//! Small per-pass counters are read back after each pass (rays, deposits, the first
//! non-finite slot); bulk buffers only when the harness asks ([`ReadBack`], [`Resolve`]).
//! Where the adapter offers timestamp queries (optional), each kernel's device time is
//! measured too ([`Backend::device_times`]).

#![warn(missing_docs)]

mod buffers;
mod camera_move;
mod context;
mod focus;
mod kept_paths;
mod kernel;
pub mod layout;
mod local_move;
mod move_kernels;
mod passes;
mod photon_grid;
mod photon_pass;
mod scan;
mod specialise;
pub mod table;
mod timestamps;

/// The assembled WGSL of every pass.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

use buffers::{SceneBuffers, read_back, storage_zeroed};
pub use context::{GpuContext, OPTIONAL_FEATURES};
pub use kept_paths::KEPT_SEGMENTS;
use kept_paths::KeptPaths;
use layout::UpdateParams;
use move_kernels::{MoveKernels, Preparing};
use passes::{
    CheckKernel, DirectLightKernel, EyeOutputs, EyePassKernel, GatherInputs, GatherKernel,
    GatherStage, HitPointUpdateKernel, LandingPathsKernel, Launch, PhotonPassKernel, PhotonTargets,
    ResolveKernel, RngVectorsKernel, Slots,
};
use photon_grid::{GridBuffers, PhotonGridKernels, PhotonMap, photon_bytes};
use ppm_core::bsdf::{BsdfCase, BsdfOutcome};
use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::check::check_hit_points;
use ppm_core::compile::{CompiledScene, SceneFeatures};
use ppm_core::device_time::DeviceTime;
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::{
    ChainLight, DirectLightParams, EyePassParams, GatherParams, GridParams, GridPhoton, HitPoint,
    PathDeposits, Photon, PhotonPassParams, ResolveParams, SlotBounds, emission_kind, eye_flags,
    photon_flags,
};
use ppm_core::local_move::{CorrectionPhotons, LocalMove, Pose};
use ppm_core::passes::{
    Backend, BackendError, DirectLight, DirectStats, DynamicBackend, EyePass, EyeStats, GatherPass,
    GatherStats, LocalMoveStats, LocalMoves, PhotonPass, PhotonStats, RandomSource, ReadBack,
    Resolve, SceneUpload, UpdateStats, check_gather_kind, crossed_mask_words,
};
use ppm_core::photon_path::KeptPass;
use ppm_core::update::gather::{GatherCase, SlotState, uses_pending};
use scan::Scan;
pub use specialise::Specialisation;
use std::sync::{Arc, Mutex};
use timestamps::{Encoder, Timer};

/// The buffers a photon pass appends its deposits to: records, their ranks in path order,
/// and their paths' weights (or pose-A partners), allocated when a region pass (or a pairing
/// pose B) first needs them (other passes bind `WgpuBackend::no_weights`).
struct DepositBuffers {
    photons: wgpu::Buffer,
    ranks: wgpu::Buffer,
    weights: Option<wgpu::Buffer>,
    capacity: u32,
}

/// Counter slots (`COUNTER_*` in layout.wgsl).
const COUNTER_RAYS: usize = 0;
const COUNTER_ITEMS: usize = 1;
const COUNTER_GATHERED: usize = 2;
const COUNTER_FIRST_BAD: usize = 3;
/// Photon passes count culled paths in the gathers' slot.
const COUNTER_CULLED: usize = 2;
/// A focus eye pass counts the slots it lists there too (focus.wgsl).
const COUNTER_LISTED: usize = 2;
const COUNTERS_RESET: [u32; 4] = [0, 0, 0, u32::MAX];

/// gather_pass.wgsl's `radii` uniform: the initial squared radius, and the photon pass's
/// `gather_r2_floor` (read by the accumulation only).
fn radii(ctx: &GpuContext, r2_initial: f32, r2_floor: f32) -> wgpu::Buffer {
    buffers::uniform(ctx, "radii", &[r2_initial, r2_floor, 0.0, 0.0])
}

/// Every pass's pipelines, compiled once per device.
struct Kernels {
    eye: EyePassKernel,
    /// A focus eye pass's rest test, compiled at the first.
    focus: focus::FocusKernel,
    direct: DirectLightKernel,
    /// Shared with the compilation ahead of moves, which compiles a correction's traces.
    photon: Arc<PhotonPassKernel>,
    grid: PhotonGridKernels,
    gather: GatherKernel,
    resolve: ResolveKernel,
    check: CheckKernel,
    rng: RngVectorsKernel,
    /// Compiled when a move first needs it: a still render never does.
    update: Option<HitPointUpdateKernel>,
    /// Compiled when a move first needs it.
    landing: Option<LandingPathsKernel>,
    /// Compiled when a move first needs them, or ahead ([`LocalMoves::prepare_moves`]).
    moves: Arc<MoveKernels>,
    scan: Scan,
}

/// The wgpu backend.
pub struct WgpuBackend {
    ctx: GpuContext,
    kernels: Kernels,
    counters: wgpu::Buffer,
    scene: Option<SceneBuffers>,
    hit_points: Option<(wgpu::Buffer, u32)>,
    /// Per hit point: the box of its eye paths' vertices (`slot_bounds` in eye_pass.wgsl).
    slot_bounds: Option<wgpu::Buffer>,
    /// Per hit point in a scene with glossy surfaces, else one element: what its eye path
    /// found at glossy bounces (`chain_light` in eye_pass.wgsl).
    chain_light: Option<wgpu::Buffer>,
    /// Per hit point: photons found, their power and weight so far in the current pass.
    accumulated: Option<wgpu::Buffer>,
    /// Per hit point: deferred region photons (the moves' deferred passes), allocated when a
    /// move or a deferred gather first needs it; until then passes bind `placeholder`.
    pending: Option<wgpu::Buffer>,
    /// Bound where `pending` would be by the passes that never touch it (every kind of
    /// gather but the deferred ones and their apply).
    placeholder: wgpu::Buffer,
    /// Bound where the deposits' weights would be by passes that neither write nor read them
    /// (all but region passes and their gathers).
    no_weights: wgpu::Buffer,
    /// The initial squared radius of the last eye pass.
    r2_initial: Option<f32>,
    /// The slots the last eye pass listed, where it was a focus pass, while they are those
    /// that do not rest: the direct light walks them alone. Every pass that may change which
    /// slots rest forgets it.
    focus: Option<focus::FocusList>,
    /// Bound where the eye and direct-light passes walk every slot.
    every_slot: focus::FocusList,
    /// Where photon passes append their deposits, kept from pass to pass.
    deposits: Option<DepositBuffers>,
    /// Deposits per path of the last photon pass: sizes the next pass's buffers.
    deposits_per_path: f64,
    /// The photon grid's working buffers, kept from pass to pass.
    grid_buffers: Option<GridBuffers>,
    map: Option<PhotonMap>,
    /// The gather kind the photon pass that built `map` named.
    map_kind: u32,
    /// The gather kind and floor (its bits) of the last photon pass while no eye pass or
    /// gather has consumed the sums it accumulated: what a pass with
    /// [`photon_flags::ADD_TO_MAP`] adds to.
    unconsumed: Option<(u32, u32)>,
    /// Batches the last photon pass took.
    batches: u32,
    /// Path indices of the last photon pass end here.
    last_pass_paths: u32,
    /// Cap on the bytes of one photon batch (see [`WgpuBackend::set_photon_buffer_limit`]).
    photon_buffer_limit: u64,
    /// The crossed-path mask (`crossed` in photon_pass.wgsl): one bit per path of the passes
    /// that record it, kept across scene updates so that pose B reads what pose A wrote.
    crossed: wgpu::Buffer,
    /// Pose A's first deposits of each path of a pairing correction (`partners` in
    /// photon_pass.wgsl, [`PathDeposits`] at the path's bit of the mask), kept across scene
    /// updates like the mask.
    partners: wgpu::Buffer,
    /// The paths a culling pass traces (`listed_paths` in photon_pass.wgsl), a word each;
    /// grown to the largest such pass.
    listed_paths: wgpu::Buffer,
    /// A correction's pose-A deposits, held for its pose B's to join in one map.
    held: Option<photon_pass::HeldDeposits>,
    /// Whether the next photon pass is a correction's pose A, which holds its deposits.
    hold_next: bool,
    /// The last photon pass's paths, where it kept them ([`kept_paths`]).
    kept_paths: Option<KeptPaths>,
    /// Their segments (kept_paths.wgsl), grown to the largest pass that kept them.
    path_segments: wgpu::Buffer,
    /// A kept pass's deposits, copied when a correction is answered from its paths.
    kept_photons: wgpu::Buffer,
    /// Whether each submission's wall time goes to stderr (`PPM_WGPU_TIMING=1`).
    timing: bool,
    /// Each kernel's device time, where the device has timestamp queries (behind a lock
    /// because passes record through `&self`).
    timer: Option<Mutex<Timer>>,
    /// The loaded scene's features, which specialise the eye and photon pipelines.
    features: Option<SceneFeatures>,
    /// Every pipeline built with everything compiled in ([`WgpuBackend::set_general`]).
    general: bool,
    /// The local move in progress, between its first pass and its last.
    moving: Option<local_move::MoveInProgress>,
    /// The buffers local moves reuse, allocated at the first.
    move_buffers: Option<local_move::MoveBuffers>,
    /// Whether a local move takes its pose-A pairs' light from the last move's pose B where
    /// that is its pose A ([`WgpuBackend::set_keep_pairs`]).
    keep_pairs: bool,
    /// Whether ordinary passes keep their paths where asked ([`WgpuBackend::set_keep_paths`]).
    keep_paths: bool,
    /// The camera move in progress, between its first pass and its last.
    camera_moving: Option<camera_move::CameraInProgress>,
    /// The old view's slots and boxes, copied when a camera move begins; allocated at the
    /// first and kept.
    camera_copies: Option<camera_move::Copies>,
    /// The move pipelines compiling ahead ([`LocalMoves::prepare_moves`]), until a move
    /// waits for them.
    preparing: Option<Preparing>,
}

impl WgpuBackend {
    /// Opens the best available adapter and compiles the passes ([`WgpuBackend::on`]).
    pub fn new() -> Result<Self, BackendError> {
        Self::on(GpuContext::new()?)
    }

    /// Compiles the passes of a still render on `ctx` (for instance a [`GpuContext::baseline`]
    /// device); the eye and photon pipelines a scene needs, and a move's, when first used.
    pub fn on(ctx: GpuContext) -> Result<Self, BackendError> {
        let kernels = ctx.scoped("shader compilation", || Kernels {
            eye: EyePassKernel::new(&ctx),
            focus: focus::FocusKernel::new(&ctx),
            direct: DirectLightKernel::new(&ctx),
            photon: Arc::new(PhotonPassKernel::new(&ctx)),
            grid: PhotonGridKernels::new(&ctx),
            gather: GatherKernel::new(&ctx),
            resolve: ResolveKernel::new(&ctx),
            check: CheckKernel::new(&ctx),
            rng: RngVectorsKernel::new(&ctx),
            update: None,
            landing: None,
            moves: Arc::default(),
            scan: Scan::new(&ctx),
        })?;
        let counters = buffers::storage_init(&ctx, "counters", &COUNTERS_RESET);
        let crossed = buffers::storage_init(&ctx, "crossed", &[u32::MAX; 4]);
        let partners = buffers::storage_init(&ctx, "partners", &[PathDeposits::default()]);
        let listed_paths = buffers::storage_init(&ctx, "listed paths", &[0u32; 4]);
        let path_segments = buffers::storage_init(&ctx, "path segments", &[0.0f32; 4]);
        let kept_photons = buffers::storage_init(&ctx, "kept photons", &[Photon::default()]);
        let placeholder = buffers::storage_init(&ctx, "pending placeholder", &[0.0f32; 4]);
        let no_weights = buffers::storage_init(&ctx, "weights placeholder", &[0.0f32; 4]);
        let every_slot = focus::FocusList::every_slot(&ctx);
        let timer = Timer::new(&ctx).map(Mutex::new);
        Ok(Self {
            ctx,
            kernels,
            counters,
            scene: None,
            hit_points: None,
            slot_bounds: None,
            chain_light: None,
            accumulated: None,
            pending: None,
            placeholder,
            no_weights,
            r2_initial: None,
            focus: None,
            every_slot,
            deposits: None,
            deposits_per_path: 1.5,
            grid_buffers: None,
            map: None,
            map_kind: 0,
            unconsumed: None,
            batches: 0,
            last_pass_paths: 0,
            photon_buffer_limit: u64::MAX,
            crossed,
            partners,
            listed_paths,
            held: None,
            hold_next: false,
            kept_paths: None,
            path_segments,
            kept_photons,
            timing: std::env::var("PPM_WGPU_TIMING").as_deref() == Ok("1"),
            timer,
            features: None,
            general: false,
            moving: None,
            move_buffers: None,
            keep_pairs: true,
            keep_paths: true,
            camera_moving: None,
            camera_copies: None,
            preparing: None,
        })
    }

    /// Caps the bytes of photon records one batch may hold (default: the device's binding
    /// limit). A pass whose deposits exceed it is traced in several batches that still make
    /// one gather update; smaller caps trade speed for memory.
    pub fn set_photon_buffer_limit(&mut self, bytes: u64) {
        self.photon_buffer_limit = bytes;
    }

    /// Builds every pipeline from here on with everything compiled in, whatever the scene
    /// needs: the general build a benchmark and a test compare the specialised one with.
    pub fn set_general(&mut self, general: bool) {
        self.general = general;
    }

    /// The eye pass's pipelines compiled so far, and the photon pass's per emission kind
    /// (ordinary, region, guided).
    pub fn compiled_specialisations(&self) -> (Vec<Specialisation>, [Vec<Specialisation>; 3]) {
        let photon = [0, 1, 2].map(|e| self.kernels.photon.compiled(e));
        (self.kernels.eye.compiled(), photon)
    }

    /// What a pass that does (`movers`) or does not test the movers' boxes needs on the
    /// loaded scene.
    fn specialisation(&self, movers: bool) -> Specialisation {
        match (&self.features, self.general) {
            (Some(features), false) => Specialisation::for_scene(features, movers),
            _ => Specialisation::GENERAL,
        }
    }

    /// Batches the last photon pass was split into.
    pub fn last_pass_batches(&self) -> u32 {
        self.batches
    }

    /// The last photon map's deposits in the order a gather reads them, each as its bucket
    /// and its rank in path order, with the photon itself: a test of the grid's sort holds
    /// them to the CPU's order (buckets ascending, ranks ascending within one) and to the
    /// deposits the pass made.
    pub fn map_order(&mut self) -> Result<Vec<(u32, u32, GridPhoton)>, BackendError> {
        self.fold_held()?;
        let Some(map) = &self.map else {
            return Ok(Vec::new());
        };
        let grid: Vec<GridParams> = read_back(&self.ctx, &map.grid, 1)?;
        // The deposits filed: those the grid left out have no place in its order.
        let count = grid[0].photon_count as usize;
        let sorted: Vec<GridPhoton> = read_back(&self.ctx, &map.sorted, count)?;
        let order: Vec<u32> = read_back(&self.ctx, &map.order, count)?;
        let ranks: Vec<u32> = read_back(&self.ctx, &map.ranks, map.count as usize)?;
        let mask = grid[0].bucket_count - 1;
        Ok(sorted
            .into_iter()
            .zip(order)
            .map(|(p, i)| (p.cell & mask, ranks[i as usize], p))
            .collect())
    }

    /// Whether [`Backend::device_times`] measures anything: the device has timestamp queries.
    pub fn has_device_times(&self) -> bool {
        self.timer.is_some()
    }

    /// The adapter that runs the passes, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    pub fn adapter_name(&self) -> String {
        let a = &self.ctx.adapter;
        format!("{} ({:?})", a.name, a.backend)
    }

    /// The device the passes run on (a viewer draws on it too).
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Resolves the image into `target` on the device, with no read-back: `width * height`
    /// RGB triples of f32, rows from the top, as [`Resolve::resolve`] returns them. `target`
    /// must be a storage buffer of this backend's device at least that large.
    pub fn resolve_into(
        &mut self,
        params: &ResolveParams,
        target: &wgpu::Buffer,
    ) -> Result<(), BackendError> {
        let needed = u64::from(params.width) * u64::from(params.height) * 12;
        if target.size() < needed {
            return Err(BackendError::Limit(format!(
                "resolve target holds {} bytes, the {}x{} image needs {needed}",
                target.size(),
                params.width,
                params.height
            )));
        }
        let (hit_points, _) = self.hit_points("resolve")?;
        self.run("resolve", |encoder| {
            self.kernels
                .resolve
                .record(&self.ctx, encoder, params, hit_points, target);
            Ok(())
        })
        .map(|_| ())
    }

    fn scene(&self, pass: &'static str) -> Result<&SceneBuffers, BackendError> {
        self.scene.as_ref().ok_or(BackendError::OutOfOrder {
            pass,
            needs: "load_scene",
        })
    }

    /// The per-hit-point gather state the eye pass allocates: accumulator, pending sums and
    /// the initial squared radius.
    fn gather_state(
        &self,
        pass: &'static str,
    ) -> Result<(&wgpu::Buffer, &wgpu::Buffer, f32), BackendError> {
        match (&self.accumulated, self.r2_initial) {
            (Some(a), Some(r)) => Ok((a, self.pending.as_ref().unwrap_or(&self.placeholder), r)),
            _ => Err(BackendError::OutOfOrder {
                pass,
                needs: "an eye pass",
            }),
        }
    }

    /// Allocates the pending sums (zero) if they are not yet: before a pass that writes or
    /// reads them.
    fn allocate_pending(&mut self, pass: &'static str) -> Result<(), BackendError> {
        if self.pending.is_none() {
            let (_, slots) = self.hit_points(pass)?;
            let bytes = u64::from(*slots) * 16;
            self.pending = Some(storage_zeroed(&self.ctx, "pending", bytes)?);
        }
        Ok(())
    }

    fn hit_points(&self, pass: &'static str) -> Result<&(wgpu::Buffer, u32), BackendError> {
        self.hit_points.as_ref().ok_or(BackendError::OutOfOrder {
            pass,
            needs: "an eye pass",
        })
    }

    /// Submits the commands `record` writes, with the counters reset first, then reads the
    /// counters back; with `PPM_WGPU_TIMING=1`, prints the submission's wall time. On a
    /// device with timestamp queries, each compute pass is timed under `pass`.
    fn run(
        &self,
        pass: &'static str,
        record: impl FnOnce(&mut Encoder<'_>) -> Result<(), BackendError>,
    ) -> Result<[u32; 4], BackendError> {
        self.run_from(pass, COUNTERS_RESET, record)
    }

    /// [`WgpuBackend::run`] with the counters starting at `from` (a pass that counts on from
    /// the submission before).
    fn run_from(
        &self,
        pass: &'static str,
        from: [u32; 4],
        record: impl FnOnce(&mut Encoder<'_>) -> Result<(), BackendError>,
    ) -> Result<[u32; 4], BackendError> {
        let start = std::time::Instant::now();
        self.ctx
            .queue
            .write_buffer(&self.counters, 0, bytemuck::cast_slice(&from));
        let mut timer = self.timer.as_ref().map(lock);
        if let Some(timer) = timer.as_deref_mut() {
            timer.begin(&self.ctx, pass)?;
        }
        self.ctx.scoped(pass, || -> Result<(), BackendError> {
            let mut encoder = Encoder::new(&self.ctx.device, pass, timer.as_deref_mut());
            record(&mut encoder)?;
            self.ctx.queue.submit([encoder.finish()]);
            Ok(())
        })??;
        let counters = read_back::<u32>(&self.ctx, &self.counters, 4)?;
        if self.timing {
            eprintln!("wgpu {pass}: {:.2} ms", start.elapsed().as_secs_f64() * 1e3);
        }
        Ok([counters[0], counters[1], counters[2], counters[3]])
    }

    /// Fails with the field and value when check.wgsl flagged a slot.
    fn check(&self, pass: &'static str, counters: &[u32; 4]) -> Result<(), BackendError> {
        let slot = counters[COUNTER_FIRST_BAD];
        if slot == u32::MAX {
            return Ok(());
        }
        let hps = read_back::<HitPoint>(&self.ctx, &self.hit_points(pass)?.0, slot as usize + 1)?;
        match check_hit_points(pass, &hps[slot as usize..]) {
            Err(BackendError::NonFinite {
                field,
                pixel,
                value,
                ..
            }) => Err(BackendError::NonFinite {
                pass,
                field,
                index: slot as usize,
                pixel,
                value,
            }),
            _ => Err(BackendError::Device(format!(
                "{pass} pass: slot {slot} flagged non-finite but reads back finite"
            ))),
        }
    }
}

impl SceneUpload for WgpuBackend {
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        let buffers = self
            .ctx
            .scoped("scene upload", || SceneBuffers::new(&self.ctx, scene, None))??;
        self.scene = Some(buffers);
        self.features = Some(scene.features);
        self.moving = None;
        self.move_buffers = None;
        self.camera_moving = None;
        self.camera_copies = None;
        self.hit_points = None;
        self.slot_bounds = None;
        self.chain_light = None;
        self.accumulated = None;
        self.pending = None;
        self.map = None;
        self.unconsumed = None;
        self.focus = None;
        Ok(())
    }
}

impl EyePass for WgpuBackend {
    fn eye_pass(&mut self, params: &EyePassParams) -> Result<EyeStats, BackendError> {
        let last_focus = self.focus.take();
        let camera = self.scene("eye")?.camera_value;
        let slots64 = u64::from(camera.width) * u64::from(camera.height) * u64::from(params.spp);
        let slots = u32::try_from(slots64)
            .map_err(|_| BackendError::Limit(format!("{slots64} hit-point slots exceed 2^32")))?;
        let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
        let hit_points = match self.hit_points.take() {
            Some((buffer, count)) if keep && count == slots => buffer,
            _ if keep => {
                return Err(BackendError::OutOfOrder {
                    pass: "eye",
                    needs: "an eye pass that starts the slots fresh",
                });
            }
            _ => storage_zeroed(
                &self.ctx,
                "hit_points",
                slots64 * size_of::<HitPoint>() as u64,
            )?,
        };
        if !keep || self.slot_bounds.is_none() {
            let bytes = slots64 * size_of::<SlotBounds>() as u64;
            self.slot_bounds = Some(storage_zeroed(&self.ctx, "slot bounds", bytes)?);
            let glossy = self.features.is_some_and(|f| f.glossy);
            let chained = if glossy { slots64 } else { 1 };
            let bytes = chained * size_of::<ChainLight>() as u64;
            self.chain_light = Some(storage_zeroed(&self.ctx, "chain light", bytes)?);
        }
        let outputs = EyeOutputs {
            bounds: self.slot_bounds.as_ref().expect("allocated above"),
            chain_light: self.chain_light.as_ref().expect("allocated above"),
        };
        let scene = self.scene("eye")?;
        let targets = Slots {
            hit_points: &hit_points,
            counters: &self.counters,
            count: slots,
        };
        let spec = self.specialisation(false);
        let focused = eye_flags::FOCUS | eye_flags::KEEP_STATISTICS;
        let (counters, focus) = if params.flags & focused == focused {
            let (counters, focus) =
                self.focus_eye_pass(params, scene, (&targets, &outputs), (spec, last_focus))?;
            (counters, Some(focus))
        } else {
            let counters = self.run("eye", |encoder| {
                let walk = (spec, &self.every_slot);
                self.kernels
                    .eye
                    .record(&self.ctx, encoder, params, scene, &targets, &outputs, walk);
                self.kernels.check.record(&self.ctx, encoder, &targets);
                Ok(())
            })?;
            (counters, None)
        };
        self.hit_points = Some((hit_points, slots));
        self.focus = focus;
        if !keep {
            self.accumulated = Some(storage_zeroed(&self.ctx, "accumulated", slots64 * 32)?);
            self.pending = None;
            self.r2_initial = Some(params.r2_initial);
        }
        self.map = None;
        self.unconsumed = None;
        if let Some(moving) = &mut self.camera_moving {
            moving.traced = !keep;
        }
        self.check("eye", &counters)?;
        Ok(EyeStats {
            rays: u64::from(counters[COUNTER_RAYS]),
            hit_points: u64::from(counters[COUNTER_ITEMS]),
        })
    }
}

impl DirectLight for WgpuBackend {
    fn direct_light(&mut self, params: &DirectLightParams) -> Result<DirectStats, BackendError> {
        let scene = self.scene("direct light")?;
        let (hit_points, slots) = self.hit_points("direct light")?;
        let targets = Slots {
            hit_points,
            counters: &self.counters,
            count: *slots,
        };
        let chain_light = self.chain_light.as_ref().ok_or(BackendError::OutOfOrder {
            pass: "direct light",
            needs: "an eye pass",
        })?;
        // After a focus eye pass, only the slots it listed do not rest.
        let walk = self.focus.as_ref().unwrap_or(&self.every_slot);
        let counters = self.run("direct light", |encoder| {
            self.kernels.direct.record(
                &self.ctx,
                encoder,
                params,
                scene,
                &targets,
                chain_light,
                walk,
            );
            self.kernels.check.record(&self.ctx, encoder, &targets);
            Ok(())
        })?;
        self.check("direct light", &counters)?;
        // The shader adds `samples` per valid slot; the CPU counts the same.
        Ok(DirectStats {
            rays: u64::from(counters[COUNTER_RAYS]),
        })
    }
}

impl LocalMoves for WgpuBackend {
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        if let Some(moving) = self.moving.as_mut() {
            moving.scene_updated();
        }
        self.map = None;
        self.focus = None;
        // A refit of the pose held, or the same pose with new movers' boxes: written in place.
        if let Some(held) = self.scene.as_mut()
            && held.update(&self.ctx, scene)
        {
            return Ok(());
        }
        let buffers = self.ctx.scoped("scene update", || {
            SceneBuffers::new(&self.ctx, scene, self.scene.as_ref())
        })??;
        self.scene = Some(buffers);
        Ok(())
    }

    /// A correction's photons as the photon pass traces them ([`CorrectionPhotons::flagged_pass`]),
    /// but pose A's are held unfiled for pose B's to join: one grid and one search of the
    /// kept slots fold both, as on the CPU, instead of one each.
    fn correction_photons(
        &mut self,
        request: &CorrectionPhotons,
    ) -> Result<PhotonStats, BackendError> {
        self.hold_next = request.pose == Pose::A;
        let stats = self.trace_pass(&request.flagged_pass(), &PhotonSource::Lights);
        self.hold_next = false;
        stats
    }

    /// Compiles the pipelines of the moves in the scene held on a thread of their own
    /// (`move_kernels.rs`): the render goes on meanwhile, and a move waits only for what is
    /// still compiling.
    fn prepare_moves(&mut self) -> Result<(), BackendError> {
        if self.scene.is_none() {
            return Err(BackendError::OutOfOrder {
                pass: "move preparation",
                needs: "a scene",
            });
        }
        if self.preparing.is_none() {
            // The correction traces with the mover-box tests (`trace_pass`).
            let spec = self.specialisation(true);
            let k = &self.kernels;
            self.preparing = Some(Preparing::start(&self.ctx, &k.moves, &k.photon, spec)?);
        }
        Ok(())
    }

    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        self.focus = None;
        self.begin_move(request)
    }

    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        self.focus = None;
        self.move_resets()
    }

    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        self.focus = None;
        self.move_direct_change()
    }

    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        self.focus = None;
        self.begin_camera(request)
    }

    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError> {
        self.focus = None;
        self.inherit()
    }
}

impl DynamicBackend for WgpuBackend {
    fn update_hit_points(
        &mut self,
        params: &EyePassParams,
        epsilon: f32,
    ) -> Result<UpdateStats, BackendError> {
        if self.kernels.update.is_none() {
            let kernel = self.ctx.scoped("shader compilation", || {
                HitPointUpdateKernel::new(&self.ctx)
            })?;
            self.kernels.update = Some(kernel);
        }
        self.allocate_pending("hit-point update")?;
        self.focus = None;
        let scene = self.scene("hit-point update")?;
        let (hit_points, slots) = self.hit_points("hit-point update")?;
        let (_, pending, _) = self.gather_state("hit-point update")?;
        let bytes = u64::from(*slots) * size_of::<HitPoint>() as u64;
        let fresh = storage_zeroed(&self.ctx, "fresh hit points", bytes)?;
        let eye_targets = Slots {
            hit_points: &fresh,
            counters: &self.counters,
            count: *slots,
        };
        let targets = Slots {
            hit_points,
            counters: &self.counters,
            count: *slots,
        };
        let fresh_params = EyePassParams {
            flags: params.flags & !(eye_flags::KEEP_STATISTICS | eye_flags::RECORD_BOUNDS)
                | eye_flags::RETRACE,
            ..*params
        };
        let (Some(bounds), Some(chain_light)) = (&self.slot_bounds, &self.chain_light) else {
            return Err(BackendError::OutOfOrder {
                pass: "hit-point update",
                needs: "an eye pass",
            });
        };
        let outputs = EyeOutputs {
            bounds,
            chain_light,
        };
        let spec = self.specialisation(false);
        let eye = self.run("hit-point update eye", |encoder| {
            // Each slot's last sample again: the re-trace reads the stratum from the copy.
            encoder.copy_buffer_to_buffer(hit_points, 0, &fresh, 0, bytes);
            self.kernels.eye.record(
                &self.ctx,
                encoder,
                &fresh_params,
                scene,
                &eye_targets,
                &outputs,
                (spec, &self.every_slot),
            );
            Ok(())
        })?;
        let update = UpdateParams {
            epsilon,
            ..Default::default()
        };
        let counters = self.run("hit-point update", |encoder| {
            self.kernels
                .update
                .as_ref()
                .expect("compiled above")
                .record(&self.ctx, encoder, &update, &fresh, pending, &targets);
            self.kernels.check.record(&self.ctx, encoder, &targets);
            Ok(())
        })?;
        let slots = *slots;
        self.r2_initial = Some(params.r2_initial);
        self.check("hit-point update", &counters)?;
        let updated = u64::from(counters[COUNTER_ITEMS]);
        Ok(UpdateStats {
            updated,
            kept: u64::from(slots) - updated,
            rays: u64::from(eye[COUNTER_RAYS]),
        })
    }

    fn landing_paths(&mut self) -> Result<Vec<u32>, BackendError> {
        self.fold_held()?;
        if self.batches > 1 {
            return Err(BackendError::Limit(format!(
                "the last photon pass was split into {} batches; its landing paths were never in one map",
                self.batches
            )));
        }
        if self.kernels.landing.is_none() {
            let kernel = self
                .ctx
                .scoped("shader compilation", || LandingPathsKernel::new(&self.ctx))?;
            self.kernels.landing = Some(kernel);
        }
        let (hit_points, slots) = self.hit_points("landing paths")?;
        let map = self.map.as_ref().ok_or(BackendError::OutOfOrder {
            pass: "landing paths",
            needs: "a photon pass",
        })?;
        let paths = self.last_pass_paths;
        let landed = storage_zeroed(&self.ctx, "landed", u64::from(paths.max(1)) * 4)?;
        let targets = Slots {
            hit_points,
            counters: &self.counters,
            count: *slots,
        };
        self.run("landing paths", |encoder| {
            self.kernels
                .landing
                .as_ref()
                .expect("compiled above")
                .record(&self.ctx, encoder, map, &targets, &landed);
            Ok(())
        })?;
        let flags = read_back::<u32>(&self.ctx, &landed, paths as usize)?;
        Ok((0..paths).filter(|&p| flags[p as usize] != 0).collect())
    }
}

impl GatherPass for WgpuBackend {
    fn gather_pass(&mut self, params: &GatherParams) -> Result<GatherStats, BackendError> {
        self.fold_held()?;
        // Only deferred gathers and their apply touch the pending sums.
        if uses_pending(params.kind) {
            self.allocate_pending("gather")?;
        }
        self.unconsumed = None;
        let scene = self.scene("gather")?;
        let (hit_points, slots) = self.hit_points("gather")?;
        let needs_photons = BackendError::OutOfOrder {
            pass: "gather",
            needs: "a photon pass",
        };
        check_gather_kind(self.map.as_ref().map(|_| self.map_kind), params)?;
        let map = self.map.as_ref().ok_or(needs_photons)?;
        let (accumulated, pending, r2_initial) = self.gather_state("gather")?;
        let radii = radii(&self.ctx, r2_initial, 0.0);
        let targets = Slots {
            hit_points,
            counters: &self.counters,
            count: *slots,
        };
        let inputs = GatherInputs {
            params,
            table: &scene.table,
            accumulated,
            pending,
            radii: &radii,
        };
        let counters = self.run("gather", |encoder| {
            self.kernels.gather.record(
                &self.ctx,
                encoder,
                &inputs,
                map,
                &targets,
                GatherStage::Apply,
            );
            self.kernels.check.record(&self.ctx, encoder, &targets);
            Ok(())
        })?;
        self.check("gather", &counters)?;
        Ok(GatherStats {
            hit_points_reached: u64::from(counters[COUNTER_ITEMS]),
            photons_gathered: u64::from(counters[COUNTER_GATHERED]),
        })
    }
}

impl Resolve for WgpuBackend {
    fn resolve(&mut self, params: &ResolveParams) -> Result<Image, BackendError> {
        let pixels = params.width as usize * params.height as usize;
        let image = storage_zeroed(&self.ctx, "image", pixels as u64 * 12)?;
        self.resolve_into(params, &image)?;
        let rgb = read_back::<[f32; 3]>(&self.ctx, &image, pixels)?;
        Ok(Image {
            width: params.width,
            height: params.height,
            pixels: rgb,
        })
    }
}

impl ReadBack for WgpuBackend {
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError> {
        match &self.hit_points {
            Some((buffer, slots)) => read_back(&self.ctx, buffer, *slots as usize),
            None => Ok(Vec::new()),
        }
    }

    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError> {
        self.focus = None;
        let (buffer, slots) = self.hit_points("write hit points")?;
        if hit_points.len() != *slots as usize {
            return Err(BackendError::OutOfOrder {
                pass: "write hit points",
                needs: "an eye pass with the same slot count",
            });
        }
        check_hit_points("write hit points", hit_points)?;
        self.ctx
            .queue
            .write_buffer(buffer, 0, bytemuck::cast_slice(hit_points));
        self.ctx.wait()
    }

    /// The last photon pass's deposits; refused when that pass had to be split into batches,
    /// since its deposits never sat in one buffer.
    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError> {
        self.fold_held()?;
        if self.batches > 1 {
            return Err(BackendError::Limit(format!(
                "the last photon pass was split into {} batches to fit the binding limit; its deposits were never held together",
                self.batches
            )));
        }
        let Some(map) = &self.map else {
            return Ok(Vec::new());
        };
        // Deposits were appended in whatever order the invocations ran: put them back in
        // path order by their ranks.
        let photons: Vec<Photon> = read_back(&self.ctx, &map.photons, map.count as usize)?;
        let ranks: Vec<u32> = read_back(&self.ctx, &map.ranks, map.count as usize)?;
        let mut ranked: Vec<(u32, Photon)> = ranks.into_iter().zip(photons).collect();
        ranked.sort_unstable_by_key(|(rank, _)| *rank);
        Ok(ranked.into_iter().map(|(_, p)| p).collect())
    }
}

impl RandomSource for WgpuBackend {
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError> {
        let words: Vec<u32> = keys.iter().flatten().copied().collect();
        self.evaluate_keys(&words, keys.len(), 1, false)
    }

    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError> {
        let words: Vec<u32> = keys.iter().flatten().copied().collect();
        let bits = self.evaluate_keys(&words, keys.len(), 2, true)?;
        Ok(bits.chunks_exact(2).map(|b| [b[0], b[1]]).collect())
    }
}

impl WgpuBackend {
    /// Runs rng_vectors.wgsl on `count` keys packed in `words`, `outputs` words each.
    fn evaluate_keys(
        &self,
        words: &[u32],
        count: usize,
        outputs: usize,
        stratified: bool,
    ) -> Result<Vec<u32>, BackendError> {
        let key_buffer = buffers::storage_init(&self.ctx, "rng keys", words);
        let bits = storage_zeroed(&self.ctx, "rng bits", (count * outputs) as u64 * 4)?;
        self.run("rng vectors", |encoder| {
            self.kernels.rng.record(
                &self.ctx,
                encoder,
                (&key_buffer, &bits),
                count as u32,
                stratified,
            );
            Ok(())
        })?;
        read_back(&self.ctx, &bits, count * outputs)
    }
}

impl WgpuBackend {
    /// Runs update.wgsl's gather rule on `cases`, the slot after each: a test compares them
    /// with [`ppm_core::update::gather::gather_rule`] on
    /// [`ppm_core::update::gather::test_cases`]. Compiles its kernel on every call.
    pub fn gather_rule_vectors(
        &self,
        cases: &[GatherCase],
    ) -> Result<Vec<SlotState>, BackendError> {
        let shader = (
            "gather_vectors",
            shaders::GATHER_VECTORS,
            "gather_vectors_main",
        );
        self.run_vectors(shader, cases)
    }

    /// Runs bsdf.wgsl on `cases`: a test compares the outcomes with
    /// [`ppm_core::bsdf::BsdfCase::expected`] on [`ppm_core::bsdf::test_cases`]. Compiles its
    /// kernel on every call.
    pub fn bsdf_vectors(&self, cases: &[BsdfCase]) -> Result<Vec<BsdfOutcome>, BackendError> {
        let shader = ("bsdf_vectors", shaders::BSDF_VECTORS, "bsdf_vectors_main");
        self.run_vectors(shader, cases)
    }

    /// Runs a test-vector shader, (name, source, entry point), on `cases`, one output each.
    fn run_vectors<I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        (name, source, entry): (&'static str, &str, &'static str),
        cases: &[I],
    ) -> Result<Vec<O>, BackendError> {
        let kernel = passes::VectorsKernel::new(&self.ctx, name, source, entry);
        let input = buffers::storage_init(&self.ctx, name, cases);
        let size = (cases.len() * std::mem::size_of::<O>()) as u64;
        let results = storage_zeroed(&self.ctx, name, size)?;
        self.run(name, |encoder| {
            kernel.record(&self.ctx, encoder, (&input, &results), cases.len() as u32);
            Ok(())
        })?;
        read_back(&self.ctx, &results, cases.len())
    }
}

impl Backend for WgpuBackend {
    fn name(&self) -> &str {
        "wgpu"
    }

    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        Some(self)
    }

    fn dynamic(&mut self) -> Option<&mut dyn DynamicBackend> {
        Some(self)
    }

    /// The viewer reaches [`WgpuBackend::resolve_into`] through it.
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(self)
    }

    /// Read back from the timestamps every submission resolved since the last call.
    fn device_times(&mut self) -> Result<Option<Vec<DeviceTime>>, BackendError> {
        self.timer
            .as_ref()
            .map(|timer| lock(timer).take(&self.ctx))
            .transpose()
    }

    /// The move's pipelines until a move, the pending sums until a deferred gather, and the
    /// code the eye and photon pipelines were specialised without.
    fn not_created(&self) -> Vec<String> {
        let mut out = Vec::new();
        let (eye, photon) = self.compiled_specialisations();
        let all_photon: Vec<Specialisation> = photon.iter().flatten().copied().collect();
        for (pass, built) in [("eye", &eye), ("photon", &all_photon)] {
            if built.is_empty() || built.iter().any(|s| s.glass) {
                continue;
            }
            out.push(match built.iter().any(|s| s.specular) {
                true => {
                    format!("{pass} pass: refraction code not compiled (the scene has no glass)")
                }
                false => {
                    format!("{pass} pass: mirror, glass and conductor code not compiled (the scene has none)")
                }
            });
        }
        if !all_photon.is_empty() && !all_photon.iter().any(|s| s.movers) {
            out.push("photon pass: mover-box tests not compiled (no local move)".into());
        }
        // Only the thesis's modes (thesis, area, difference) re-trace the slots, test and
        // guide photons; thesis and area modes emit through a region. Local mode needs none.
        for (kind, name, modes) in [
            (emission_kind::REGION, "region", "thesis or area"),
            (
                emission_kind::GUIDED,
                "guided",
                "thesis, area or difference",
            ),
        ] {
            if photon[kind as usize].is_empty() {
                out.push(format!(
                    "photon pass, {name} emission: not compiled (no {modes} move)"
                ));
            }
        }
        let thesis_modes = "no thesis, area or difference move";
        if self.kernels.update.is_none() {
            out.push(format!(
                "hit-point update pipeline: not compiled ({thesis_modes})"
            ));
        }
        if self.kernels.landing.is_none() {
            out.push(format!(
                "landing-path pipeline: not compiled ({thesis_modes})"
            ));
        }
        out.extend(self.local_moves_not_created());
        out.extend(self.camera_moves_not_created());
        if let Some(d) = self.deposits.as_ref().filter(|d| d.weights.is_none()) {
            out.push(format!(
                "photon path weights: {} bytes not allocated (no region pass)",
                u64::from(d.capacity.max(1)) * 4
            ));
        }
        if let (None, Some((_, slots))) = (&self.pending, &self.hit_points) {
            out.push(format!(
                "pending sums: {} bytes not allocated (no deferred gather)",
                u64::from(*slots) * 16
            ));
        }
        out
    }
}

/// The timer, even if a pass panicked while holding it: the next submission drops the pairs
/// of one that never finished ([`Timer::begin`]).
fn lock(timer: &Mutex<Timer>) -> std::sync::MutexGuard<'_, Timer> {
    timer.lock().unwrap_or_else(|p| p.into_inner())
}
