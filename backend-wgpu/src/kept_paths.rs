//! The paths an ordinary photon pass keeps for the next local move's pose-A correction
//! ([`photon_flags::KEEP_PATHS`], kept_paths.wgsl): photon_pass.wgsl writes each path's first
//! [`KEPT_SEGMENTS`] segments beside its deposits, and path_replay.wgsl answers the correction
//! from them and the pass's deposits, tracing again only the paths too long to keep. A drag
//! step's pose A then traces a few per cent of its paths, not all of them, as backend-cpu's
//! path_record.rs does with every segment kept.
//!
//! [`photon_flags::KEEP_PATHS`]: ppm_core::layout::photon_flags::KEEP_PATHS

use crate::buffers::uniform;
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::passes::PhotonTargets;
use crate::shaders;
use crate::timestamps::Encoder;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::PhotonPassParams;
use ppm_core::photon_path::KeptPass;

/// Segments kept per path (`KEPT_SEGMENTS` in kept_paths.wgsl): enough for all but a few per
/// cent of the paths of a scene of ordinary albedo, whose paths mostly end within three.
pub const KEPT_SEGMENTS: u32 = 6;

/// Bytes kept per path: eight words a segment and its count (`KEPT_STRIDE`).
const PATH_BYTES: u64 = (8 * KEPT_SEGMENTS as u64 + 1) * 4;

/// A deposit's index plus one is kept in an f32 word, exact up to 2^24: a pass whose photon
/// buffer holds more keeps nothing.
pub const MOST_DEPOSITS: u32 = (1 << 24) - 1;

/// Bytes of the kept segments of a pass of `params`.
pub fn segment_bytes(params: &PhotonPassParams) -> u64 {
    u64::from(params.photon_count.max(1)) * PATH_BYTES
}

/// An ordinary pass whose paths the segment buffer holds, with its deposits still in the
/// photon buffer.
pub struct KeptPaths {
    /// The pass and what it answers.
    pub pass: KeptPass,
    /// The pose it was traced in ([`crate::buffers::SceneBuffers::pose`]).
    pub pose: u64,
    /// Its deposits.
    pub deposits: u32,
}

impl KeptPaths {
    /// The sign that turns the kept deposits into those of a pass of `params` from `source`
    /// in `pose`, where the kept paths answer it ([`KeptPass::answers`]).
    pub fn answers(
        &self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
        pose: u64,
    ) -> Option<f32> {
        self.pass
            .answers(params, source)
            .filter(|_| pose == self.pose)
    }
}

/// path_replay.wgsl.
pub struct PathReplayKernel(Kernel);

impl PathReplayKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        use Slot::{Read, ReadWrite, Table, Uniform};
        let module = shader_module(&ctx.device, "path_replay", shaders::PATH_REPLAY);
        let slots = [
            Uniform, Table, Uniform, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
            ReadWrite, ReadWrite,
        ];
        Self(Kernel::new(
            &ctx.device,
            &module,
            "path_replay_main",
            &slots,
            WORKGROUP,
        ))
    }

    /// Records the replay of the pass `params` (its power scale the sign of the kept
    /// deposits) in `scene`, from the kept `segments` and the kept pass's deposits copied to
    /// `kept`, into `targets` (their deposits, ranks, counters, mask, partners and list).
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        (params, scene): (&PhotonPassParams, &crate::buffers::SceneBuffers),
        (segments, kept): (&wgpu::Buffer, &wgpu::Buffer),
        targets: &PhotonTargets,
    ) {
        let params_buffer = uniform(ctx, "replay params", params);
        let group = self.0.bind(
            &ctx.device,
            &[
                &params_buffer,
                &scene.table,
                &scene.index,
                segments,
                kept,
                targets.photons,
                targets.ranks,
                targets.counters,
                targets.crossed,
                targets.partners,
                targets.listed_paths,
            ],
        );
        self.0.dispatch(encoder, &group, params.photon_count);
    }
}
