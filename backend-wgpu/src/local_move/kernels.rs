//! local_move.wgsl's pipelines: one per entry point, over one binding list, each compiled the
//! first time a move records it.

use crate::buffers::SceneBuffers;
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::shaders;
use crate::timestamps::Encoder;
use std::sync::OnceLock;

use Slot::{Read, ReadWrite, Table, Uniform, Unused};

/// A pass of a local move: an entry point of local_move.wgsl.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveStage {
    /// Pose A, per slot: `prepare_slot`, and the slots whose pairs the move corrects listed.
    Begin,
    /// Pose A, per listed slot: its pairs' light copied where the last move evaluated it in
    /// this pose, the other pairs listed.
    PairsCopy,
    /// Pose A, per listed pair: pose A's half.
    PairsBefore,
    /// Pose B, per triangle: pose B's outline of the moved objects.
    Cover,
    /// Pose B, per slot: `reset_if_seen` where the view test decides; the others listed for
    /// the probe.
    Resets,
    /// Pose B, per slot the resets listed: the probe decides.
    Probes,
    /// Pose B, per listed slot: pose B's half of its pairs, the change and its application.
    PairsAfter,
}

impl MoveStage {
    pub(crate) const ALL: [MoveStage; STAGES] = [
        MoveStage::Begin,
        MoveStage::PairsCopy,
        MoveStage::PairsBefore,
        MoveStage::Cover,
        MoveStage::Resets,
        MoveStage::Probes,
        MoveStage::PairsAfter,
    ];

    /// What a reader calls it.
    pub fn name(self) -> &'static str {
        match self {
            MoveStage::Begin => "preparation",
            MoveStage::PairsCopy => "pose-A pairs kept",
            MoveStage::PairsBefore => "pose-A pairs",
            MoveStage::Cover => "outline",
            MoveStage::Resets => "resets",
            MoveStage::Probes => "probe",
            MoveStage::PairsAfter => "pose-B pairs",
        }
    }

    /// The entry point.
    fn entry(self) -> &'static str {
        match self {
            MoveStage::Begin => "local_begin_main",
            MoveStage::PairsCopy => "local_pairs_copy_main",
            MoveStage::PairsBefore => "local_pairs_before_main",
            MoveStage::Cover => "local_cover_main",
            MoveStage::Resets => "local_resets_main",
            MoveStage::Probes => "local_probes_main",
            MoveStage::PairsAfter => "local_pairs_after_main",
        }
    }

    /// The bindings (named as [`MoveBindings`] names them) the entry point reads, the others
    /// [`Slot::Unused`]: each stays within baseline WebGPU's per-stage limits.
    fn slots(self) -> [Slot; 19] {
        // params, camera, scene table, scene index, texels, boxes, objects, hit points,
        // slot bounds, covered, listed, pair store, move counters, cover, list, probes,
        // known, known store, pair list.
        match self {
            MoveStage::Begin => [
                Uniform, Unused, Unused, Unused, Unused, Read, Unused, ReadWrite, Read, Unused,
                ReadWrite, Unused, ReadWrite, Unused, Unused, Unused, Unused, Unused, Unused,
            ],
            MoveStage::PairsCopy => [
                Uniform, Unused, Unused, Unused, Unused, Unused, Unused, Unused, Unused, Unused,
                ReadWrite, ReadWrite, ReadWrite, Unused, Uniform, Unused, ReadWrite, ReadWrite,
                ReadWrite,
            ],
            MoveStage::PairsBefore => [
                Uniform, Uniform, Table, Uniform, Read, Read, Unused, ReadWrite, Unused, Unused,
                ReadWrite, ReadWrite, ReadWrite, Unused, Uniform, Unused, Unused, Unused,
                ReadWrite,
            ],
            MoveStage::PairsAfter => [
                Uniform, Uniform, Table, Uniform, Read, Unused, Unused, ReadWrite, Unused, Unused,
                ReadWrite, ReadWrite, ReadWrite, Unused, Uniform, Unused, ReadWrite, ReadWrite,
                Unused,
            ],
            MoveStage::Cover => [
                Unused, Unused, Table, Uniform, Unused, Unused, Read, Unused, Unused, ReadWrite,
                Unused, Unused, Unused, Uniform, Unused, Unused, Unused, Unused, Unused,
            ],
            MoveStage::Resets => [
                Uniform, Uniform, Unused, Unused, Unused, Read, Unused, ReadWrite, Read, ReadWrite,
                Unused, Unused, ReadWrite, Unused, Unused, ReadWrite, Unused, Unused, Unused,
            ],
            MoveStage::Probes => [
                Uniform, Uniform, Table, Uniform, Read, Unused, Unused, ReadWrite, Unused, Unused,
                Unused, Unused, ReadWrite, Unused, Uniform, ReadWrite, Unused, Unused, Unused,
            ],
        }
    }
}

/// Entry points of local_move.wgsl.
const STAGES: usize = 7;

/// What a local move's kernels bind, named as local_move.wgsl binds it.
pub struct MoveBindings<'a> {
    /// `params`: the move's [`ppm_core::layout::LocalMoveParams`].
    pub params: &'a wgpu::Buffer,
    /// The pose held: `camera`, `scene_table`, `scene` and `scene_texels`.
    pub scene: &'a SceneBuffers,
    /// `move_boxes`.
    pub boxes: &'a wgpu::Buffer,
    /// `moved_objects`.
    pub objects: &'a wgpu::Buffer,
    /// `hit_points`.
    pub hit_points: &'a wgpu::Buffer,
    /// `slot_bounds`.
    pub slot_bounds: &'a wgpu::Buffer,
    /// `covered`.
    pub covered: &'a wgpu::Buffer,
    /// `listed`.
    pub listed: &'a wgpu::Buffer,
    /// `pair_store`.
    pub pair_store: &'a wgpu::Buffer,
    /// `move_counters`.
    pub counters: &'a wgpu::Buffer,
    /// `cover`.
    pub cover: &'a wgpu::Buffer,
    /// `list`.
    pub list: &'a wgpu::Buffer,
    /// `probes`.
    pub probes: &'a wgpu::Buffer,
    /// `known`.
    pub known: &'a wgpu::Buffer,
    /// `known_store`.
    pub known_store: &'a wgpu::Buffer,
    /// `pair_list`.
    pub pair_list: &'a wgpu::Buffer,
}

/// local_move.wgsl: its module parsed at a backend's first local move, each entry point's
/// pipeline compiled when first recorded (or ahead: [`crate::move_kernels`]), with or
/// without the refraction code (`GLASS` in bsdf.wgsl, as the eye pipelines are specialised:
/// [`crate::Specialisation`]).
pub struct LocalMoveKernels {
    module: wgpu::ShaderModule,
    stages: [[OnceLock<Kernel>; STAGES]; 2],
}

impl LocalMoveKernels {
    /// Parses the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            module: shader_module(&ctx.device, "local_move", shaders::LOCAL_MOVE),
            stages: Default::default(),
        }
    }

    /// The stages whose pipelines are not compiled yet.
    pub fn not_compiled(&self) -> Vec<MoveStage> {
        MoveStage::ALL
            .into_iter()
            .filter(|s| self.stages.iter().all(|v| v[*s as usize].get().is_none()))
            .collect()
    }

    /// The pipeline of `stage`, with the refraction code where `glass`, compiled now unless
    /// it is already.
    pub fn compile(&self, ctx: &GpuContext, stage: MoveStage, glass: bool) -> &Kernel {
        self.stages[usize::from(glass)][stage as usize].get_or_init(|| {
            Kernel::specialised(
                &ctx.device,
                &self.module,
                stage.entry(),
                &stage.slots(),
                WORKGROUP,
                &[("GLASS", f64::from(u8::from(glass)))],
            )
        })
    }

    /// Records `stage` over `items` work items (slots, listed slots, listed pairs or
    /// triangles), its pipeline with the refraction code where `glass`; none records nothing,
    /// and compiles nothing.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        (stage, glass): (MoveStage, bool),
        b: &MoveBindings,
        items: u32,
    ) {
        if items == 0 {
            return;
        }
        let kernel = self.compile(ctx, stage, glass);
        let group = kernel.bind(
            &ctx.device,
            &[
                b.params,
                &b.scene.camera,
                &b.scene.table,
                &b.scene.index,
                &b.scene.texels,
                b.boxes,
                b.objects,
                b.hit_points,
                b.slot_bounds,
                b.covered,
                b.listed,
                b.pair_store,
                b.counters,
                b.cover,
                b.list,
                b.probes,
                b.known,
                b.known_store,
                b.pair_list,
            ],
        );
        kernel.dispatch(encoder, &group, items);
    }
}
