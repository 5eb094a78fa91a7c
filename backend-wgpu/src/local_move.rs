//! A local move's passes on the device (docs/algorithm.md 3b, 3c): the twin of backend-cpu's
//! local_move.rs, local_move.wgsl's kernels running ppm_core::local_move's per-slot functions
//! (their WGSL twins) over the slots where they lie. No slot is read back or written from the
//! host: what crosses are the request (a uniform, its boxes and its objects' indices) and
//! small counters.
//!
//! The backend holds one pose at a time, so pose A's half of each pair is traced when the
//! move begins and kept until pose B's: per slot listed then (its direct light may change
//! and it holds a direct sum), each pair's direct light in pose A, `3 direct_samples` words.
//! A pair whose eye path goes straight past every moved box, and whose visible point's rays to
//! the lights cannot cross one, is the same in both poses
//! (`ppm_core::local_move::Pair::difference`): pose A traces its path only and marks it, and
//! pose B skips it. The slots are counted first and only those get a record: a move that may
//! change nobody's direct light allocates nothing. Pose B's lights are kept in a second store
//! for the next move, whose pose A that pose is, as backend-cpu keeps them: along a drag, pose
//! A copies what the last move evaluated instead of evaluating it again. The pairs pose A
//! cannot copy are listed first and traced by a kernel of their own, so that the few a drag
//! step traces do not hold up workgroups of slots that trace nothing; pose B, whose pairs
//! mostly trace, walks the listed slots. Two stores of 12 bytes a pair and a list of 4: with
//! every slot of a 768x768 image listed, 66 MB for a drag step's 4 pairs, 264 MB for
//! [`ppm_core::local_move::MOST_SAMPLES`].

mod kernels;

use kernels::MoveBindings;
pub use kernels::{LocalMoveKernels, MoveStage};

use crate::WgpuBackend;
use crate::buffers::{self, read_back, storage_zeroed};
use crate::layout::{
    CoverCase, CoverOutcome, CoverParams, ListParams, MoveDecisionCase, MoveDecisionOutcome,
};
use crate::passes::Slots;
use ppm_core::local_move::LocalMove;
use ppm_core::passes::{BackendError, LocalMoveStats};

/// Slots of the move counters (`MOVE_*` in local_move.wgsl).
const MOVE_RESET: usize = 0;
const MOVE_CORRECTED: usize = 1;
const MOVE_PROBED: usize = 2;
const MOVE_LISTED: usize = 3;
const MOVE_RAYS: usize = 4;
const MOVE_PAIRS: usize = 5;
/// Words of the move counters.
const MOVE_COUNTERS: usize = 8;

/// Where a local move stands between its passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Begun in pose A; the scene update to pose B comes next.
    Begun,
    /// In pose B; the resets come next.
    PoseB,
    /// Resets done; the direct-light change comes next.
    Reset,
}

/// A local move in progress: its request on the device, and the slots listed in pose A.
pub struct MoveInProgress {
    stage: Stage,
    /// The request's [`ppm_core::layout::LocalMoveParams`].
    params: wgpu::Buffer,
    /// How many slots the pair kernels walk ([`ListParams`]).
    list: wgpu::Buffer,
    /// Slots listed in pose A, whose records pose B reads.
    listed: u32,
    /// Moved objects.
    objects: u32,
    /// Its boxes ([`LocalMove::boxes`]).
    boxes: wgpu::Buffer,
    /// Its objects' indices.
    object_ids: wgpu::Buffer,
    /// What keyed and traced its pairs.
    keys: PairKeys,
    /// Rays pose A's pairs traced, reported with pose B's.
    rays_before: u64,
}

impl MoveInProgress {
    /// The scene was updated: a move begun in pose A goes on in this pose, its pose B.
    pub fn scene_updated(&mut self) {
        if self.stage == Stage::Begun {
            self.stage = Stage::PoseB;
        }
    }
}

/// What a move's pairs depend on besides their slot: the pose they were traced in, and the
/// request's seed, paths and count of pairs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PairKeys {
    pose: u64,
    seed: u32,
    max_depth: u32,
    ray_epsilon: u32,
    direct_samples: u32,
}

/// The buffers local moves reuse, allocated at the first for the slots and pixels of the
/// render, the stores grown when a move lists more slots.
pub struct MoveBuffers {
    /// Slots of the render they serve.
    slots: u32,
    /// A word per slot: the listed slots (`listed` in local_move.wgsl).
    listed: wgpu::Buffer,
    /// A bit per pixel and one more word (`covered`).
    covered: wgpu::Buffer,
    /// `move_counters`.
    counters: wgpu::Buffer,
    /// The pairs' records of this move's listed slots in pose A (`pair_store`).
    store: wgpu::Buffer,
    /// Those of the last move's in its pose B (`known_store`), which pose B writes once pose
    /// A has read them.
    known_store: wgpu::Buffer,
    /// A word per slot: where the last move's record of it lies in its store (`known`).
    known: wgpu::Buffer,
    /// What keyed the last move's pairs in its pose B, when it traced any.
    known_keys: Option<PairKeys>,
    /// A word per slot: the slots the probe decides (`probes`).
    probes: wgpu::Buffer,
    /// A word per pair of the listed slots: the pairs traced (`pair_list`).
    pair_list: wgpu::Buffer,
}

impl MoveBuffers {
    fn new(ctx: &crate::GpuContext, slots: u32, pixels: u32) -> Result<Self, BackendError> {
        Ok(Self {
            slots,
            listed: storage_zeroed(ctx, "listed slots", u64::from(slots) * 4)?,
            covered: storage_zeroed(ctx, "covered pixels", covered_bytes(pixels))?,
            counters: storage_zeroed(ctx, "move counters", MOVE_COUNTERS as u64 * 4)?,
            store: storage_zeroed(ctx, "pair store", 16)?,
            known_store: storage_zeroed(ctx, "known pair store", 16)?,
            known: storage_zeroed(ctx, "known pairs", u64::from(slots) * 4)?,
            known_keys: None,
            probes: storage_zeroed(ctx, "probed slots", u64::from(slots) * 4)?,
            pair_list: storage_zeroed(ctx, "listed pairs", 16)?,
        })
    }
}

impl MoveBuffers {
    /// Forgets the last move's pairs in its pose B: a camera move began, and they were
    /// traced through the old view's pixels.
    pub fn forget_pairs(&mut self) {
        self.known_keys = None;
    }
}

/// How [`WgpuBackend::record_move_with`] records a submission.
#[derive(Clone, Copy)]
struct Recording<'a> {
    /// Clear the move counters first (else count on).
    clear: bool,
    /// Check every slot's finiteness after.
    check: bool,
    /// The cover kernel's parameters, where it runs (its covered mask cleared before it).
    cover: Option<&'a wgpu::Buffer>,
    /// The length of the list a kernel walks, where it is not the move's own.
    list: Option<&'a wgpu::Buffer>,
}

impl Default for Recording<'_> {
    fn default() -> Self {
        Self {
            clear: true,
            check: true,
            cover: None,
            list: None,
        }
    }
}

/// Bytes of the records of `listed` slots' pairs keyed as `keys`: three words a pair.
fn store_bytes(listed: u32, keys: &PairKeys) -> u64 {
    u64::from(listed) * u64::from(keys.direct_samples) * 12
}

/// Bytes of the list of `listed` slots' pairs keyed as `keys`: a word a pair.
fn pair_list_bytes(listed: u32, keys: &PairKeys) -> u64 {
    store_bytes(listed, keys) / 3
}

/// Bytes of the covered mask of `pixels` pixels: a bit each, and the word that says all.
fn covered_bytes(pixels: u32) -> u64 {
    (u64::from(pixels).div_ceil(32) + 1) * 4
}

impl WgpuBackend {
    /// Whether a local move takes its pose-A pairs' light from the last move's pose B where
    /// that is its pose A (the default), or evaluates it again: the same slots bit for bit,
    /// which a test holds it to.
    pub fn set_keep_pairs(&mut self, keep: bool) {
        self.keep_pairs = keep;
    }

    /// [`ppm_core::passes::LocalMoves::begin_local_move`]: `prepare_slot` at every slot in
    /// pose A, then pose A's half of the pairs of the slots listed.
    pub(crate) fn begin_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        const PASS: &str = "local move";
        let &(_, slots) = self.hit_points(PASS)?;
        let scene = self.scene(PASS)?;
        let pixels = scene.camera_value.width * scene.camera_value.height;
        let keys = PairKeys {
            pose: scene.pose(),
            seed: request.seed,
            max_depth: request.paths.max_depth,
            ray_epsilon: request.paths.ray_epsilon.to_bits(),
            direct_samples: request.direct_samples,
        };
        let objects = request.objects.len();
        if request.before.len() != objects || request.after.len() != objects {
            return Err(BackendError::Limit(format!(
                "local move: {objects} objects with {} boxes in pose A and {} in pose B; each needs one in each",
                request.before.len(),
                request.after.len()
            )));
        }
        if let Some(preparing) = self.preparing.take() {
            preparing.finish()?;
        }
        self.ctx.scoped("shader compilation", || {
            self.kernels.moves.local(&self.ctx);
        })?;
        let fits = self
            .move_buffers
            .as_ref()
            .is_some_and(|b| b.slots == slots && b.covered.size() >= covered_bytes(pixels));
        if !fits {
            self.move_buffers = Some(MoveBuffers::new(&self.ctx, slots, pixels)?);
        }
        let mut moving = MoveInProgress {
            stage: Stage::Begun,
            params: buffers::uniform(&self.ctx, "local move", &request.params()),
            list: buffers::uniform(&self.ctx, "list", &ListParams::default()),
            listed: 0,
            objects: objects as u32,
            boxes: buffers::storage_init(&self.ctx, "move boxes", &request.boxes()),
            object_ids: buffers::storage_init(&self.ctx, "moved objects", &request.objects),
            keys,
            rays_before: 0,
        };
        let counters = self.record_move(PASS, &moving, &[(MoveStage::Begin, slots)], false)?;
        moving.listed = counters[MOVE_LISTED];
        if moving.listed > 0 && request.direct_samples > 0 {
            let bytes = store_bytes(moving.listed, &keys);
            let held = self.move_buffers.as_mut().expect("allocated above");
            if held.store.size() < bytes {
                held.store = storage_zeroed(&self.ctx, "pair store", bytes)?;
            }
            let bytes = pair_list_bytes(moving.listed, &keys);
            if held.pair_list.size() < bytes {
                held.pair_list = storage_zeroed(&self.ctx, "listed pairs", bytes)?;
            }
            let list = ListParams {
                count: moving.listed,
                known: u32::from(self.keep_pairs && held.known_keys == Some(keys)),
                ..ListParams::default()
            };
            moving.list = buffers::uniform(&self.ctx, "list", &list);
            let stages = [(MoveStage::PairsCopy, moving.listed)];
            const PAIRS: &str = "local move, pose A's pairs";
            let mut counters = self.record_move(PAIRS, &moving, &stages, false)?;
            let pairs = counters[MOVE_PAIRS];
            if pairs > 0 {
                // Traced from their own list, as many as there are: lavapipe zeroes a
                // tracing kernel's stack at each invocation, which cost a drag step more
                // than its few pairs traced (bvh.wgsl).
                let stage = (MoveStage::PairsBefore, pairs);
                counters = self.record_listed(PAIRS, &moving, stage, false)?;
            }
            moving.rays_before = u64::from(counters[MOVE_RAYS]);
        } else {
            moving.listed = 0;
        }
        self.moving = Some(moving);
        Ok(())
    }

    /// [`ppm_core::passes::LocalMoves::local_resets`]: pose B's outline of the moved objects,
    /// then `reset_if_seen` at every slot, the probe where only it can tell.
    pub(crate) fn move_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        const PASS: &str = "local resets";
        let Some(moving) = self.moving.take_if(|m| m.stage == Stage::PoseB) else {
            return Err(BackendError::OutOfOrder {
                pass: PASS,
                needs: "a local move begun in pose A, then the scene updated to pose B",
            });
        };
        let &(_, slots) = self.hit_points(PASS)?;
        let scene = self.scene(PASS)?;
        let cover = CoverParams {
            triangles: scene.triangle_count,
            objects: moving.objects,
            ..CoverParams::new(&scene.camera_value)
        };
        let stages = [
            (MoveStage::Cover, cover.triangles),
            (MoveStage::Resets, slots),
        ];
        let cover = buffers::uniform(&self.ctx, "cover", &cover);
        let recording = Recording {
            cover: Some(&cover),
            ..Recording::default()
        };
        let mut counters = self.record_move_with(PASS, &moving, &stages, recording)?;
        let probed = counters[MOVE_PROBED];
        if probed > 0 {
            // The slots the view test could not decide, probed in a kernel of their own.
            counters = self.record_listed(PASS, &moving, (MoveStage::Probes, probed), true)?;
        }
        let reset = u64::from(counters[MOVE_RESET]);
        self.moving = Some(MoveInProgress {
            stage: Stage::Reset,
            ..moving
        });
        Ok(LocalMoveStats {
            reset,
            kept: u64::from(slots) - reset,
            direct_corrected: u64::from(counters[MOVE_CORRECTED]),
            probed: u64::from(counters[MOVE_PROBED]),
            rays: u64::from(counters[MOVE_RAYS]),
        })
    }

    /// [`ppm_core::passes::LocalMoves::local_direct_change`]: pose B's half of the listed
    /// slots' pairs, and the change applied where the slot was kept.
    pub(crate) fn move_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        const PASS: &str = "local direct change";
        let Some(moving) = self.moving.take_if(|m| m.stage == Stage::Reset) else {
            return Err(BackendError::OutOfOrder {
                pass: PASS,
                needs: "the local resets",
            });
        };
        // Pose B's lights replace the last move's, which pose A has read.
        let held = self
            .move_buffers
            .as_mut()
            .expect("allocated at the move's start");
        held.known_keys = None;
        if moving.listed == 0 {
            return Ok(LocalMoveStats::default());
        }
        let bytes = store_bytes(moving.listed, &moving.keys);
        if held.known_store.size() < bytes {
            held.known_store = storage_zeroed(&self.ctx, "known pair store", bytes)?;
        }
        let stages = [(MoveStage::PairsAfter, moving.listed)];
        let counters = self.record_move(PASS, &moving, &stages, true)?;
        let pose = self.scene(PASS)?.pose();
        let held = self
            .move_buffers
            .as_mut()
            .expect("allocated at the move's start");
        held.known_keys = Some(PairKeys {
            pose,
            ..moving.keys
        });
        Ok(LocalMoveStats {
            direct_corrected: u64::from(counters[MOVE_CORRECTED]),
            rays: moving.rays_before + u64::from(counters[MOVE_RAYS]),
            ..LocalMoveStats::default()
        })
    }

    /// [`WgpuBackend::record_move_with`] as most passes record.
    fn record_move(
        &self,
        pass: &'static str,
        moving: &MoveInProgress,
        stages: &[(MoveStage, u32)],
        check: bool,
    ) -> Result<[u32; MOVE_COUNTERS], BackendError> {
        let recording = Recording {
            check,
            ..Recording::default()
        };
        self.record_move_with(pass, moving, stages, recording)
    }

    /// Records `stage` over the `count` items a stage before it listed, counting on from
    /// that stage's counters, and checks every slot's finiteness after where `check`.
    fn record_listed(
        &self,
        pass: &'static str,
        moving: &MoveInProgress,
        (stage, count): (MoveStage, u32),
        check: bool,
    ) -> Result<[u32; MOVE_COUNTERS], BackendError> {
        let list = ListParams {
            count,
            ..ListParams::default()
        };
        let list = buffers::uniform(&self.ctx, "list", &list);
        let recording = Recording {
            clear: false,
            check,
            list: Some(&list),
            ..Recording::default()
        };
        self.record_move_with(pass, moving, &[(stage, count)], recording)
    }

    /// Records `stages` (each with its work items) of `moving` in one submission, as
    /// `recording` says (the index of the known pairs cleared before pose B's), and returns
    /// the move counters.
    fn record_move_with(
        &self,
        pass: &'static str,
        moving: &MoveInProgress,
        stages: &[(MoveStage, u32)],
        recording: Recording,
    ) -> Result<[u32; MOVE_COUNTERS], BackendError> {
        let kernels = self.kernels.moves.local(&self.ctx);
        let held = self
            .move_buffers
            .as_ref()
            .expect("allocated at the move's start");
        let (hit_points, count) = self.hit_points(pass)?;
        let slot_bounds = self.slot_bounds.as_ref().ok_or(BackendError::OutOfOrder {
            pass,
            needs: "an eye pass",
        })?;
        let bindings = MoveBindings {
            params: &moving.params,
            scene: self.scene(pass)?,
            boxes: &moving.boxes,
            objects: &moving.object_ids,
            hit_points,
            slot_bounds,
            covered: &held.covered,
            listed: &held.listed,
            pair_store: &held.store,
            counters: &held.counters,
            // Bound only by the cover kernel: any uniform fills the place elsewhere.
            cover: recording.cover.unwrap_or(&moving.params),
            list: recording.list.unwrap_or(&moving.list),
            probes: &held.probes,
            known: &held.known,
            known_store: &held.known_store,
            pair_list: &held.pair_list,
        };
        let slots = Slots {
            hit_points,
            counters: &self.counters,
            count: *count,
        };
        let glass = self.specialisation(false).glass;
        let counters = self.run(pass, |encoder| {
            if recording.clear {
                encoder.clear_buffer(&held.counters, 0, None);
            }
            for &(stage, items) in stages {
                match stage {
                    MoveStage::Cover => encoder.clear_buffer(&held.covered, 0, None),
                    MoveStage::PairsAfter => encoder.clear_buffer(&held.known, 0, None),
                    _ => {}
                }
                kernels.record(&self.ctx, encoder, (stage, glass), &bindings, items);
            }
            if recording.check {
                self.kernels.check.record(&self.ctx, encoder, &slots);
            }
            Ok(())
        })?;
        self.check(pass, &counters)?;
        let moved = read_back::<u32>(&self.ctx, &held.counters, MOVE_COUNTERS)?;
        Ok(std::array::from_fn(|i| moved[i]))
    }

    /// Runs local_move_vectors.wgsl on `cases`: a test compares the outcomes with
    /// ppm_core's `segments_may_meet`, `prepare_slot` and `view_test` (tests/local_move.rs).
    /// Compiles its kernel on every call.
    pub fn local_move_vectors(
        &self,
        cases: &[MoveDecisionCase],
    ) -> Result<Vec<MoveDecisionOutcome>, BackendError> {
        let shader = (
            "local_move_vectors",
            crate::shaders::LOCAL_MOVE_VECTORS,
            "move_decision_vectors_main",
        );
        self.run_vectors(shader, cases)
    }

    /// Runs screen_cover_vectors.wgsl on `cases`: a test compares the outcomes with
    /// `ppm_core::screen_cover::covered_pixels` (tests/local_move.rs). Compiles its kernel on
    /// every call.
    pub fn screen_cover_vectors(
        &self,
        cases: &[CoverCase],
    ) -> Result<Vec<CoverOutcome>, BackendError> {
        let shader = (
            "screen_cover_vectors",
            crate::shaders::SCREEN_COVER_VECTORS,
            "cover_vectors_main",
        );
        self.run_vectors(shader, cases)
    }

    /// What [`crate::Backend::not_created`] says of local moves: their pipelines until the
    /// first, then those no move has needed yet.
    pub(crate) fn local_moves_not_created(&self) -> Vec<String> {
        match self.kernels.moves.local_parsed() {
            None => vec!["local-move pipelines: not compiled (no local move)".into()],
            Some(kernels) => kernels
                .not_compiled()
                .into_iter()
                .map(|stage| {
                    let name = stage.name();
                    format!("local-move {name} pipeline: not compiled (no move needed it)")
                })
                .collect(),
        }
    }
}
