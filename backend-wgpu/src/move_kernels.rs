//! The pipelines only moves use, and their compilation ahead of the first move.
//!
//! A still render compiles none of them. A render that says it will move
//! ([`ppm_core::passes::LocalMoves::prepare_moves`]) has them compiled on a thread of their
//! own while it renders on, so that its first move costs what the later ones do: on lavapipe
//! they take about 0.6 s, which the first drag step of `ppm view` used to wait for. Each
//! pipeline sits in a `OnceLock`, so a pass that needs one the thread is compiling waits for
//! it rather than compiling it twice.

use crate::camera_move::CameraMoveKernel;
use crate::context::GpuContext;
use crate::kept_paths::PathReplayKernel;
use crate::local_move::{LocalMoveKernels, MoveStage};
use crate::passes::PhotonPassKernel;
use crate::specialise::Specialisation;
use ppm_core::passes::BackendError;
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;

/// The pipelines only moves use, each compiled once: when a move first needs it, or ahead.
#[derive(Default)]
pub struct MoveKernels {
    local: OnceLock<LocalMoveKernels>,
    camera: OnceLock<CameraMoveKernel>,
    replay: OnceLock<PathReplayKernel>,
}

impl MoveKernels {
    /// local_move.wgsl, parsed now unless it is already (its pipelines compile when first
    /// recorded).
    pub fn local(&self, ctx: &GpuContext) -> &LocalMoveKernels {
        self.local.get_or_init(|| LocalMoveKernels::new(ctx))
    }

    /// local_move.wgsl, where a move has parsed it.
    pub fn local_parsed(&self) -> Option<&LocalMoveKernels> {
        self.local.get()
    }

    /// camera_move.wgsl's pipeline, compiled now unless it is already.
    pub fn camera(&self, ctx: &GpuContext) -> &CameraMoveKernel {
        self.camera.get_or_init(|| CameraMoveKernel::new(ctx))
    }

    /// Whether camera_move.wgsl's pipeline is compiled.
    pub fn camera_compiled(&self) -> bool {
        self.camera.get().is_some()
    }

    /// path_replay.wgsl's pipeline, compiled now unless it is already.
    pub fn replay(&self, ctx: &GpuContext) -> &PathReplayKernel {
        self.replay.get_or_init(|| PathReplayKernel::new(ctx))
    }
}

/// Move pipelines being compiled ahead, on a thread of their own.
pub struct Preparing(JoinHandle<Result<(), BackendError>>);

impl Preparing {
    /// Starts compiling every pipeline a local or a camera move uses in a scene whose
    /// correction traces `spec` specialises (with the mover-box tests): local_move.wgsl's
    /// stages, the correction's traces, the replay of kept paths and the camera move's
    /// inheritance.
    pub fn start(
        ctx: &GpuContext,
        moves: &Arc<MoveKernels>,
        photon: &Arc<PhotonPassKernel>,
        spec: Specialisation,
    ) -> Result<Self, BackendError> {
        let (ctx, moves, photon) = (ctx.clone(), moves.clone(), photon.clone());
        let compile = move || {
            ctx.captured("move pipelines compiled ahead", || {
                let local = moves.local(&ctx);
                for stage in MoveStage::ALL {
                    local.compile(&ctx, stage, spec.glass);
                }
                photon.compile_correction(&ctx, spec);
                moves.replay(&ctx);
                moves.camera(&ctx);
            })
        };
        std::thread::Builder::new()
            .name("move pipelines".into())
            .spawn(compile)
            .map(Self)
            .map_err(|e| {
                BackendError::Device(format!("cannot start compiling the move pipelines: {e}"))
            })
    }

    /// Waits until every pipeline is compiled; the error the compilation met, if any.
    pub fn finish(self) -> Result<(), BackendError> {
        self.0.join().unwrap_or_else(|_| {
            Err(BackendError::Device(
                "compiling the move pipelines ahead panicked".into(),
            ))
        })
    }
}
