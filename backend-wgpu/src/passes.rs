//! One small type per pass shader: it owns the pipelines of that shader's entry points and
//! records their dispatches over the buffers named as the WGSL binds them.

use crate::buffers::{SceneBuffers, uniform};
use crate::context::GpuContext;
use crate::focus::FocusList;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::shaders;
use crate::specialise::{Specialisation, VARIANTS};
use crate::timestamps::Encoder;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, GatherParams, PhotonPassParams, ResolveParams, emission_kind,
};
use std::sync::OnceLock;

use Slot::{Read, ReadWrite, Table, Uniform, Unused, WordTable};

/// The hit-point buffer and the pass counters that per-slot passes bind.
pub struct Slots<'a> {
    /// Hit points.
    pub hit_points: &'a wgpu::Buffer,
    /// Pass counters.
    pub counters: &'a wgpu::Buffer,
    /// Number of hit points.
    pub count: u32,
}

/// eye_pass.wgsl, one pipeline per [`Specialisation`] a scene has needed.
pub struct EyePassKernel {
    module: wgpu::ShaderModule,
    variants: [OnceLock<Kernel>; VARIANTS],
}

impl EyePassKernel {
    /// Parses the shader; its pipelines are compiled when first recorded.
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            module: shader_module(&ctx.device, "eye_pass", shaders::EYE_PASS),
            variants: Default::default(),
        }
    }

    /// The variants compiled so far.
    pub fn compiled(&self) -> Vec<Specialisation> {
        compiled(&self.variants)
    }

    fn kernel(&self, ctx: &GpuContext, spec: Specialisation) -> &Kernel {
        // The eye pass has no mover tests: one pipeline serves both.
        let spec = Specialisation {
            movers: false,
            ..spec
        };
        self.variants[spec.index()].get_or_init(|| {
            let slots = [
                Uniform, Uniform, Table, Uniform, ReadWrite, ReadWrite, ReadWrite, Read, ReadWrite,
                Read, Uniform,
            ];
            // The eye pass declares SPECULAR and GLASS, not MOVERS.
            let mut constants = spec.constants();
            constants.retain(|(name, _)| *name != "MOVERS");
            Kernel::specialised(
                &ctx.device,
                &self.module,
                "eye_pass_main",
                &slots,
                WORKGROUP,
                &constants,
            )
        })
    }

    /// Records the eye pass over the slots `walk` names (every slot, or a focus pass's list);
    /// `outputs.bounds` holds a box per slot, which the pass extends with
    /// [`ppm_core::layout::eye_flags::RECORD_BOUNDS`].
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &EyePassParams,
        scene: &SceneBuffers,
        slots: &Slots,
        outputs: &EyeOutputs,
        (spec, walk): (Specialisation, &FocusList),
    ) {
        let kernel = self.kernel(ctx, spec);
        let params = uniform(ctx, "eye params", params);
        let group = kernel.bind(
            &ctx.device,
            &[
                &params,
                &scene.camera,
                &scene.table,
                &scene.index,
                slots.hit_points,
                slots.counters,
                outputs.bounds,
                &scene.texels,
                outputs.chain_light,
                &walk.listed,
                &walk.list,
            ],
        );
        kernel.dispatch(encoder, &group, walk.items(slots.count));
    }
}

/// What the eye pass writes besides the slots.
pub struct EyeOutputs<'a> {
    /// A box per slot (`slot_bounds` in eye_pass.wgsl).
    pub bounds: &'a wgpu::Buffer,
    /// What each slot's glossy bounces found (`chain_light`): one per slot in a scene with
    /// glossy surfaces, one placeholder element otherwise.
    pub chain_light: &'a wgpu::Buffer,
}

/// The specialisations of `variants` compiled so far.
fn compiled(variants: &[OnceLock<Kernel>; VARIANTS]) -> Vec<Specialisation> {
    Specialisation::all()
        .filter(|s| variants[s.index()].get().is_some())
        .collect()
}

/// direct_light.wgsl.
pub struct DirectLightKernel(Kernel);

impl DirectLightKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "direct_light", shaders::DIRECT_LIGHT);
        let slots = [
            Uniform, Table, Uniform, ReadWrite, ReadWrite, Read, Read, Uniform,
        ];
        Self(Kernel::new(
            &ctx.device,
            &module,
            "direct_light_main",
            &slots,
            WORKGROUP,
        ))
    }

    /// Records the direct-light pass over the slots `walk` names (every slot, or a focus
    /// pass's list), adding what `chain_light` holds ([`EyeOutputs::chain_light`]).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &DirectLightParams,
        scene: &SceneBuffers,
        slots: &Slots,
        chain_light: &wgpu::Buffer,
        walk: &FocusList,
    ) {
        let params = uniform(ctx, "direct params", params);
        let group = self.0.bind(
            &ctx.device,
            &[
                &params,
                &scene.table,
                &scene.index,
                slots.hit_points,
                slots.counters,
                chain_light,
                &walk.listed,
                &walk.list,
            ],
        );
        self.0.dispatch(encoder, &group, walk.items(slots.count));
    }
}

/// photon_pass.wgsl: one trace appending its deposits, one pipeline per emission kind
/// (ordinary, region, guided) and [`Specialisation`], each compiled when first needed; and
/// for a culling pass of ordinary photons, the list of the paths it traces and their trace.
pub struct PhotonPassKernel {
    module: wgpu::ShaderModule,
    trace: [[OnceLock<Kernel>; VARIANTS]; 3],
    list: OnceLock<Kernel>,
    listed: [OnceLock<Kernel>; VARIANTS],
}

/// The buffers a photon pass binds besides the scene.
pub struct PhotonTargets<'a> {
    /// Each deposit's rank in path order.
    pub ranks: &'a wgpu::Buffer,
    /// The deposits.
    pub photons: &'a wgpu::Buffer,
    /// Pass counters.
    pub counters: &'a wgpu::Buffer,
    /// Where photons start (uniform `Emitter`).
    pub emitter: &'a wgpu::Buffer,
    /// Recorded paths for guided photons.
    pub recorded: &'a wgpu::Buffer,
    /// Path weight of each deposit.
    pub weights: &'a wgpu::Buffer,
    /// The crossed-path mask (local mode's difference passes).
    pub crossed: &'a wgpu::Buffer,
    /// Pose A's first deposits per path (a local correction's pairing).
    pub partners: &'a wgpu::Buffer,
    /// The paths a culling pass traces, a word each.
    pub listed_paths: &'a wgpu::Buffer,
}

/// Which paths a photon trace launches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Launch {
    /// Paths `first_path .. first_path + photon_count`, culled by the mask where the pass
    /// says.
    Range,
    /// The first `photon_count` paths of the list (ordinary emission only).
    Listed,
}

/// The bindings of photon_pass.wgsl, in order.
const PHOTON_SLOTS: [Slot; 13] = [
    Uniform, Table, Uniform, ReadWrite, ReadWrite, ReadWrite, Uniform, Read, ReadWrite, ReadWrite,
    Read, ReadWrite, ReadWrite,
];

/// [`PHOTON_SLOTS`] with those an entry point does not read left out (baseline WebGPU binds
/// at most eight storage buffers per stage).
fn photon_slots(unused: &[usize]) -> [Slot; 13] {
    let mut slots = PHOTON_SLOTS;
    for &i in unused {
        slots[i] = Slot::Unused;
    }
    slots
}

impl PhotonPassKernel {
    /// Parses the shader; its pipelines are compiled when first recorded.
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            module: shader_module(&ctx.device, "photon_pass", shaders::PHOTON_PASS),
            trace: Default::default(),
            list: OnceLock::new(),
            listed: Default::default(),
        }
    }

    /// The variants compiled so far, per emission kind (`ppm_core::layout::emission_kind`).
    pub fn compiled(&self, emission: u32) -> Vec<Specialisation> {
        compiled(&self.trace[emission as usize])
    }

    fn kernel(&self, ctx: &GpuContext, emission: u32, spec: Specialisation) -> &Kernel {
        self.trace[emission as usize][spec.index()].get_or_init(|| {
            let mut constants = spec.constants();
            constants.push(("EMISSION", f64::from(emission)));
            Kernel::specialised(
                &ctx.device,
                &self.module,
                "photon_trace_main",
                &photon_slots(&[12]),
                WORKGROUP,
                &constants,
            )
        })
    }

    fn listed_kernel(&self, ctx: &GpuContext, spec: Specialisation) -> &Kernel {
        self.listed[spec.index()].get_or_init(|| {
            let mut constants = spec.constants();
            constants.push(("EMISSION", f64::from(emission_kind::ORDINARY)));
            Kernel::specialised(
                &ctx.device,
                &self.module,
                "photon_trace_listed_main",
                &photon_slots(&[7]),
                WORKGROUP,
                &constants,
            )
        })
    }

    fn list_kernel(&self, ctx: &GpuContext) -> &Kernel {
        self.list.get_or_init(|| {
            Kernel::new(
                &ctx.device,
                &self.module,
                "photon_list_crossed_main",
                &photon_slots(&[1, 2, 3, 4, 6, 7, 8, 10, 11]),
                WORKGROUP,
            )
        })
    }

    /// Compiles now, unless they are already, the pipelines a local move's correction
    /// traces with as `spec` specialises them: the trace of a range, the list of the paths
    /// pose B traces, and their trace.
    pub fn compile_correction(&self, ctx: &GpuContext, spec: Specialisation) {
        self.kernel(ctx, emission_kind::ORDINARY, spec);
        self.list_kernel(ctx);
        self.listed_kernel(ctx, spec);
    }

    /// Records the trace of photons emitted as `emission` says (`ppm_core::layout::emission_kind`),
    /// of the paths `launch` says.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &PhotonPassParams,
        scene: &SceneBuffers,
        targets: &PhotonTargets,
        (emission, launch): (u32, Launch),
        spec: Specialisation,
    ) {
        let kernel = match launch {
            Launch::Range => self.kernel(ctx, emission, spec),
            Launch::Listed => self.listed_kernel(ctx, spec),
        };
        let uniform_params = uniform(ctx, "photon params", params);
        let group = kernel.bind(
            &ctx.device,
            &[
                &uniform_params,
                &scene.table,
                &scene.index,
                targets.ranks,
                targets.photons,
                targets.counters,
                targets.emitter,
                targets.recorded,
                targets.weights,
                targets.crossed,
                &scene.texels,
                targets.partners,
                targets.listed_paths,
            ],
        );
        kernel.dispatch(encoder, &group, params.photon_count);
    }

    /// Records the listing of the paths of `params` whose bit is set in `crossed` into
    /// `listed_paths`, counted in `counters`' items.
    pub fn record_list(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &PhotonPassParams,
        (crossed, listed_paths, counters): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    ) {
        let kernel = self.list_kernel(ctx);
        let uniform_params = uniform(ctx, "photon params", params);
        let unused = &uniform_params;
        let group = kernel.bind(
            &ctx.device,
            &[
                &uniform_params,
                unused,
                unused,
                unused,
                unused,
                counters,
                unused,
                unused,
                unused,
                crossed,
                unused,
                unused,
                listed_paths,
            ],
        );
        kernel.dispatch(encoder, &group, params.photon_count);
    }
}

/// gather_pass.wgsl: accumulate (once per photon batch; plain, weighted or paired), then
/// apply (once per pass).
pub struct GatherKernel {
    accumulate: [Kernel; 3],
    apply: Kernel,
}

/// What the gather binds besides the hit points.
pub struct GatherInputs<'a> {
    /// Gather parameters (alpha, emitted increment, kind).
    pub params: &'a GatherParams,
    /// The scene table, whose materials give the BRDF.
    pub table: &'a crate::table::Table,
    /// Per hit point: running power, count and weight of the pass's photons so far.
    pub accumulated: &'a wgpu::Buffer,
    /// Per hit point: deferred region photons.
    pub pending: &'a wgpu::Buffer,
    /// Uniform vec4: the initial squared radius, and the photon pass's `gather_r2_floor`
    /// (read by the accumulation only).
    pub radii: &'a wgpu::Buffer,
}

/// Which half of the gather a record runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GatherStage {
    /// Inside the photon pass: one batch's photons into the accumulators of the slots that
    /// gather the named kind; `weighted` when the deposits carry path weights (a region
    /// source's), `paired` when they carry their pose-A partners (a pairing pose B's).
    Accumulate {
        /// Whether the deposits carry path weights.
        weighted: bool,
        /// Whether they carry pose-A partners.
        paired: bool,
    },
    /// The gather pass: each slot's update from its accumulator, by the gather rule.
    Apply,
}

impl GatherKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "gather_pass", shaders::GATHER_PASS);
        // Binding 5 is free: the gather reads each deposit's words in bucket order.
        let slots = [
            Uniform, Table, Table, Read, WordTable, Unused, ReadWrite, ReadWrite, ReadWrite, Table,
            ReadWrite, Uniform,
        ];
        Self {
            accumulate: [(false, false), (true, false), (false, true)].map(|(weighted, paired)| {
                Kernel::specialised(
                    &ctx.device,
                    &module,
                    "gather_accumulate_main",
                    &slots,
                    WORKGROUP,
                    &[
                        ("WEIGHTED", f64::from(u8::from(weighted))),
                        ("PAIRED", f64::from(u8::from(paired))),
                    ],
                )
            }),
            apply: Kernel::new(&ctx.device, &module, "gather_apply_main", &slots, WORKGROUP),
        }
    }

    /// Records `stage` of the gather of photon map `map`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        inputs: &GatherInputs,
        map: &crate::photon_grid::PhotonMap,
        slots: &Slots,
        stage: GatherStage,
    ) {
        let kernel = match stage {
            GatherStage::Apply => &self.apply,
            GatherStage::Accumulate { weighted, paired } => {
                &self.accumulate[usize::from(weighted) + 2 * usize::from(paired)]
            }
        };
        let params = uniform(ctx, "gather params", inputs.params);
        let group = kernel.bind(
            &ctx.device,
            &[
                &params,
                inputs.table,
                &map.sorted_table,
                &map.grid,
                &map.bucket_table,
                &params,
                slots.hit_points,
                inputs.accumulated,
                slots.counters,
                &map.words_table,
                inputs.pending,
                inputs.radii,
            ],
        );
        kernel.dispatch(encoder, &group, slots.count);
    }
}

/// resolve.wgsl.
pub struct ResolveKernel(Kernel);

impl ResolveKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "resolve", shaders::RESOLVE);
        Self(Kernel::new(
            &ctx.device,
            &module,
            "resolve_main",
            &[Uniform, Read, ReadWrite],
            WORKGROUP,
        ))
    }

    /// Records the resolve of `params.width * params.height` pixels into `image` (RGB f32).
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &ResolveParams,
        hit_points: &wgpu::Buffer,
        image: &wgpu::Buffer,
    ) {
        let uniform_params = uniform(ctx, "resolve params", params);
        let group = self
            .0
            .bind(&ctx.device, &[&uniform_params, hit_points, image]);
        self.0
            .dispatch(encoder, &group, params.width * params.height);
    }
}

/// check.wgsl.
pub struct CheckKernel(Kernel);

impl CheckKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "check", shaders::CHECK);
        Self(Kernel::new(
            &ctx.device,
            &module,
            "check_main",
            &[Read, ReadWrite],
            WORKGROUP,
        ))
    }

    /// Records the finiteness check of every hit point.
    pub fn record(&self, ctx: &GpuContext, encoder: &mut Encoder<'_>, slots: &Slots) {
        let group = self
            .0
            .bind(&ctx.device, &[slots.hit_points, slots.counters]);
        self.0.dispatch(encoder, &group, slots.count);
    }
}

/// A test-vector shader (gather_vectors.wgsl, bsdf_vectors.wgsl): one output per input case,
/// from an entry point over a read-only case array and a result array. Compiled only when a
/// test asks for it.
pub struct VectorsKernel(Kernel);

impl VectorsKernel {
    /// Compiles entry point `entry` of the shader `name`, assembled as `source`.
    pub fn new(ctx: &GpuContext, name: &str, source: &str, entry: &'static str) -> Self {
        let module = shader_module(&ctx.device, name, source);
        Self(Kernel::new(
            &ctx.device,
            &module,
            entry,
            &[Read, ReadWrite],
            WORKGROUP,
        ))
    }

    /// Records the shader on `count` cases into `results`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        (cases, results): (&wgpu::Buffer, &wgpu::Buffer),
        count: u32,
    ) {
        let group = self.0.bind(&ctx.device, &[cases, results]);
        self.0.dispatch(encoder, &group, count);
    }
}

/// rng_vectors.wgsl: the counter-based generator and the stratified sequences on given keys.
pub struct RngVectorsKernel {
    random: Kernel,
    stratified: Kernel,
}

impl RngVectorsKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "rng_vectors", shaders::RNG_VECTORS);
        let kernel =
            |entry| Kernel::new(&ctx.device, &module, entry, &[Read, ReadWrite], WORKGROUP);
        Self {
            random: kernel("rng_vectors_main"),
            stratified: kernel("qmc_vectors_main"),
        }
    }

    /// Records the evaluation of `count` keys into `bits`: five words each giving one word
    /// of [`ppm_core::rng::random_bits`], or (`stratified`) two words each giving the two
    /// words of [`ppm_core::qmc::sobol_pair_bits`].
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        (keys, bits): (&wgpu::Buffer, &wgpu::Buffer),
        count: u32,
        stratified: bool,
    ) {
        let kernel = if stratified {
            &self.stratified
        } else {
            &self.random
        };
        let group = kernel.bind(&ctx.device, &[keys, bits]);
        kernel.dispatch(encoder, &group, count);
    }
}

/// hit_point_update.wgsl.
pub struct HitPointUpdateKernel(Kernel);

impl HitPointUpdateKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "hit_point_update", shaders::HIT_POINT_UPDATE);
        let slots = [Uniform, Read, ReadWrite, ReadWrite, ReadWrite];
        Self(Kernel::new(
            &ctx.device,
            &module,
            "hit_point_update_main",
            &slots,
            WORKGROUP,
        ))
    }

    /// Records the comparison of `fresh` (the new pose's eye pass) with the hit points.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &crate::layout::UpdateParams,
        fresh: &wgpu::Buffer,
        pending: &wgpu::Buffer,
        slots: &Slots,
    ) {
        let params = uniform(ctx, "update params", params);
        let group = self.0.bind(
            &ctx.device,
            &[&params, fresh, slots.hit_points, pending, slots.counters],
        );
        self.0.dispatch(encoder, &group, slots.count);
    }
}

/// landing_paths.wgsl.
pub struct LandingPathsKernel(Kernel);

impl LandingPathsKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "landing_paths", shaders::LANDING_PATHS);
        let slots = [Read, Read, Read, Read, Read, ReadWrite, Read];
        Self(Kernel::new(
            &ctx.device,
            &module,
            "landing_paths_main",
            &slots,
            WORKGROUP,
        ))
    }

    /// Records the flagging of paths that reached updated hit points into `landed`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        map: &crate::photon_grid::PhotonMap,
        slots: &Slots,
        landed: &wgpu::Buffer,
    ) {
        let group = self.0.bind(
            &ctx.device,
            &[
                &map.photons,
                &map.grid,
                &map.bucket_start,
                &map.order,
                slots.hit_points,
                landed,
                &map.sorted,
            ],
        );
        self.0.dispatch(encoder, &group, slots.count);
    }
}
