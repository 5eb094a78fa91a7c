//! Checkpoints: the whole state of a render on disk, so that a stopped render (Ctrl-C, a
//! scheduler's preemption) resumes bit for bit as if it had never stopped.
//!
//! A checkpoint folder holds `slots.bin` (every slot's statistics, as the backend holds them)
//! and `state.json` (the driver's counters, which are the random generator's position since
//! every stream is keyed by them; the photon counts; the report so far; and a fingerprint of
//! the scene and the settings). Each file is written atomically, slots first; the state names
//! the slots' hash, so a folder caught between the two writes is refused, not half-read.

use super::{Counters, PhotonCounts, Renderer};
use crate::report::RenderReport;
use ppm_core::compile::CompiledScene;
use ppm_core::layout::HitPoint;
use ppm_core::params::RenderParams;
use ppm_core::passes::BackendError;
use serde::{Deserialize, Serialize};
use std::path::Path;
use thiserror::Error;

/// Version of the checkpoint format: 2 since a hit point holds the photons local moves
/// discounted (112 bytes, was 96).
const FORMAT: u32 = 2;

/// Why a checkpoint cannot be written or resumed.
#[derive(Debug, Error)]
pub enum CheckpointError {
    /// Reading or writing a file failed.
    #[error("{file}: {reason}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        reason: String,
    },
    /// The checkpoint belongs to another render.
    #[error("{dir}: {reason}")]
    Mismatch {
        /// The checkpoint folder.
        dir: String,
        /// What differs.
        reason: String,
    },
    /// A pass failed while taking or restoring the state.
    #[error(transparent)]
    Backend(#[from] BackendError),
}

/// A render's state between two iterations.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RenderState {
    /// Checkpoint format version.
    pub format: u32,
    /// Hash of the flattened scene and of every setting that changes the image
    /// ([`fingerprint`]).
    pub fingerprint: String,
    /// Seconds of rendering so far.
    pub seconds: f64,
    /// Slots in `slots.bin`.
    pub slots: u64,
    /// Hash of `slots.bin`.
    pub slots_hash: String,
    counters: Counters,
    counts: PhotonCounts,
    /// The report so far.
    pub report: RenderReport,
    #[serde(skip)]
    hit_points: Vec<HitPoint>,
}

/// FNV-1a, 64 bits: enough to tell another scene, setting or a torn write apart.
fn fnv(bytes: &[u8], mut hash: u64) -> u64 {
    for &b in bytes {
        hash = (hash ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    hash
}

const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

/// The fingerprint of `compiled` rendered with `params`: the geometry, materials, lights and
/// camera as the backend receives them, and every setting but the budget (a resumed render may
/// run longer than the one that stopped).
pub fn fingerprint(compiled: &CompiledScene, params: &RenderParams) -> String {
    let mut budgetless = params.clone();
    budgetless.passes = 0;
    budgetless.time_budget = None;
    let settings = serde_json::to_vec(&budgetless).expect("settings serialise");
    let mut h = FNV_START;
    h = fnv(bytemuck::cast_slice(&compiled.triangles), h);
    h = fnv(bytemuck::cast_slice(&compiled.materials), h);
    h = fnv(bytemuck::cast_slice(&compiled.lights), h);
    h = fnv(bytemuck::bytes_of(&compiled.camera), h);
    h = fnv(&settings, h);
    format!("{h:016x}")
}

impl RenderState {
    /// Writes the checkpoint into `dir` (created if missing): slots, then state.
    pub fn write(&self, dir: &Path) -> Result<(), CheckpointError> {
        let io = |file: &Path, e: std::io::Error| CheckpointError::Io {
            file: file.display().to_string(),
            reason: e.to_string(),
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        let slots = dir.join("slots.bin");
        scenes::file::output::write_bytes(&slots, bytemuck::cast_slice(&self.hit_points))
            .map_err(|e| io(&slots, e))?;
        let state = dir.join("state.json");
        let json = serde_json::to_string_pretty(self).expect("a state serialises");
        scenes::file::output::write_bytes(&state, json).map_err(|e| io(&state, e))
    }

    /// Reads the checkpoint in `dir`, refusing a torn or foreign one.
    pub fn read(dir: &Path) -> Result<Self, CheckpointError> {
        let state_path = dir.join("state.json");
        let io = |file: &Path, reason: String| CheckpointError::Io {
            file: file.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(&state_path).map_err(|e| {
            io(
                &state_path,
                format!("{e} (not a checkpoint folder written by --checkpoint)"),
            )
        })?;
        let mut state: RenderState =
            serde_json::from_str(&text).map_err(|e| io(&state_path, e.to_string()))?;
        let mismatch = |reason: String| CheckpointError::Mismatch {
            dir: dir.display().to_string(),
            reason,
        };
        if state.format != FORMAT {
            return Err(mismatch(format!(
                "checkpoint format {}, this ppm reads {FORMAT}",
                state.format
            )));
        }
        let slots_path = dir.join("slots.bin");
        let bytes = std::fs::read(&slots_path).map_err(|e| io(&slots_path, e.to_string()))?;
        let expected = state.slots as usize * size_of::<HitPoint>();
        let hash = format!("{:016x}", fnv(&bytes, FNV_START));
        if bytes.len() != expected || hash != state.slots_hash {
            return Err(mismatch(format!(
                "slots.bin ({} bytes, hash {hash}) is not the one state.json names ({expected} \
                 bytes, hash {}): the checkpoint was caught between two writes",
                bytes.len(),
                state.slots_hash
            )));
        }
        state.hit_points = bytemuck::pod_collect_to_vec(&bytes);
        Ok(state)
    }
}

impl Renderer<'_> {
    /// The render's state now, `seconds` of rendering in. Refused while a move's guided
    /// passes are still running (their recorded paths are not part of a checkpoint).
    pub fn snapshot(&mut self, seconds: f64) -> Result<RenderState, BackendError> {
        if self.guide.is_some() || self.focus {
            return Err(BackendError::Unsupported(
                "a checkpoint of a render that is following a move".to_owned(),
            ));
        }
        let hit_points = match self.has_image() {
            true => self.backend.read_hit_points()?,
            false => Vec::new(),
        };
        let bytes: &[u8] = bytemuck::cast_slice(&hit_points);
        Ok(RenderState {
            format: FORMAT,
            fingerprint: fingerprint(&self.compiled, &self.params),
            seconds,
            slots: hit_points.len() as u64,
            slots_hash: format!("{:016x}", fnv(bytes, FNV_START)),
            counters: self.counters.clone(),
            counts: self.counts.clone(),
            report: self.report.clone(),
            hit_points,
        })
    }

    /// Continues from `state`, taken of this scene with these settings (`dir` names the
    /// checkpoint in errors): the slots go back to the backend, the counters to the driver.
    pub fn restore(&mut self, state: &RenderState, dir: &Path) -> Result<(), CheckpointError> {
        let here = fingerprint(&self.compiled, &self.params);
        if state.fingerprint != here {
            return Err(CheckpointError::Mismatch {
                dir: dir.display().to_string(),
                reason: format!(
                    "written for another scene or other settings (fingerprint {}, this render \
                     {here}); only --passes and --time-budget may change on resume",
                    state.fingerprint
                ),
            });
        }
        // A state without slots was taken before any were traced.
        if !state.hit_points.is_empty() {
            if self.counters.fresh {
                // The slot buffers exist once an eye pass has run: this one's results are
                // replaced at once.
                self.eye_pass(0, false)?;
            }
            self.backend.write_hit_points(&state.hit_points)?;
        }
        self.counters = state.counters.clone();
        self.counts = state.counts.clone();
        // A state may continue on another backend (a preempted job landing elsewhere): the
        // slots' layout is the contract's; only the bit-for-bit promise needs the same one.
        self.report = RenderReport {
            params: self.params.clone(),
            backend: self.backend.name().to_owned(),
            ..state.report.clone()
        };
        Ok(())
    }
}
