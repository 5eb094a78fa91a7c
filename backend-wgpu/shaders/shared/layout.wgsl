// Buffer element layouts: the twins of ppm_core::layout, member for member.
// tests/layout.rs reflects these with naga and compares every offset and size with Rust.

const MATERIAL_DIFFUSE: u32 = 0u;
const MATERIAL_MIRROR: u32 = 1u;
const MATERIAL_GLASS: u32 = 2u;
const MATERIAL_CONDUCTOR: u32 = 3u;
const MATERIAL_COATED: u32 = 4u;

const HIT_VALID: u32 = 1u;
const HIT_FRONT: u32 = 2u;
const HIT_UPDATED: u32 = 4u;
const HIT_DIRECT_MAY_CHANGE: u32 = 16u;
const HIT_RESTING: u32 = 32u;
const HIT_EYE_CHAINED: u32 = 128u;
const HIT_KEPT: u32 = HIT_UPDATED | HIT_EYE_CHAINED;
const HIT_OBJECT_SHIFT: u32 = 8u;
const NO_MATERIAL: u32 = 0xffffffffu;

const FIRST_HIT_SKIP: u32 = 0u;
const FIRST_HIT_DEPOSIT: u32 = 1u;

// Slots of the per-pass counter buffer (backend_wgpu::counters).
const COUNTER_RAYS: u32 = 0u;
const COUNTER_ITEMS: u32 = 1u;
const COUNTER_GATHERED: u32 = 2u;
const COUNTER_FIRST_BAD: u32 = 3u;
// Photon passes count the paths they cull in the gathers' slot.
const COUNTER_CULLED: u32 = 2u;
// A focus eye pass counts the slots it lists in the gathers' slot (focus.wgsl).
const COUNTER_LISTED: u32 = 2u;

struct HitPoint {
    position: vec3<f32>,
    pixel: u32,
    normal: vec3<f32>,
    material: u32,
    throughput: vec3<f32>,
    r2: f32,
    tau: vec3<f32>,
    n: f32,
    direct: vec3<f32>,
    emitted: f32,
    iterations: u32,
    flags: u32,
    eye_met: u32,
    correction_r2: f32,
    discounted: f32,
    _pad: array<u32, 3>,
}

struct Photon {
    position: vec3<f32>,
    path: u32,
    power: vec3<f32>,
    normal_oct: u32,
}

struct GpuTriangle {
    v0: vec3<f32>,
    material: u32,
    e1: vec3<f32>,
    object: u32,
    e2: vec3<f32>,
    light: u32,
    normal: vec3<f32>,
    group: u32,
}

struct BvhNode {
    min: vec3<f32>,
    first: u32,
    max: vec3<f32>,
    count: u32,
}

struct GpuMaterial {
    albedo: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    ior: f32,
    eta: vec3<f32>,
    alpha: f32,
    k: vec3<f32>,
    texture: u32,
    coat_internal: f32,
    coat_nonlinear: u32,
    coat_specular_weight: f32,
    alpha_v: f32,
    coat_transmittance: array<vec4<f32>, 3>,
}

struct GpuTexture {
    first: u32,
    width: u32,
    height: u32,
    nearest: u32,
    scale: vec2<f32>,
    offset: vec2<f32>,
}

struct GpuTriangleUv {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    _pad: vec2<u32>,
}

struct GpuLight {
    v0: vec3<f32>,
    area: f32,
    e1: vec3<f32>,
    cdf: f32,
    e2: vec3<f32>,
    pdf: f32,
    normal: vec3<f32>,
    material: u32,
}

struct GpuCamera {
    eye: vec3<f32>,
    width: u32,
    forward: vec3<f32>,
    height: u32,
    right: vec3<f32>,
    _pad0: u32,
    up: vec3<f32>,
    _pad1: u32,
}

const EYE_KEEP_STATISTICS: u32 = 1u;
const EYE_JITTER: u32 = 2u;
const EYE_FOCUS: u32 = 4u;
const EYE_RECORD_BOUNDS: u32 = 8u;
const EYE_RETRACE: u32 = 16u;
const EYE_SAMPLE_LIGHTS: u32 = 32u;

struct EyePassParams {
    seed: u32,
    spp: u32,
    max_depth: u32,
    iteration: u32,
    r2_initial: f32,
    ray_epsilon: f32,
    flags: u32,
    rest_at: u32,
}

struct DirectLightParams {
    seed: u32,
    samples: u32,
    iteration: u32,
    ray_epsilon: f32,
    accumulate: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// DirectLightParams::accumulate (ppm_core::layout::direct_accumulate).
const DIRECT_REPLACE: u32 = 0u;
const DIRECT_ADD: u32 = 1u;

struct PhotonPassParams {
    seed: u32,
    pass_index: u32,
    photon_count: u32,
    max_depth: u32,
    first_hit: u32,
    ray_epsilon: f32,
    power_scale: f32,
    first_path: u32,
    flags: u32,
    mask_offset: u32,
    gather_kind: u32,
    gather_r2_floor: f32,
}

// PhotonPassParams::flags (ppm_core::layout::photon_flags).
const PHOTON_CHANGED_ONLY: u32 = 1u;
const PHOTON_RECORD_CROSSED: u32 = 2u;
const PHOTON_CULL_UNCROSSED: u32 = 4u;
const PHOTON_KEEP_PATHS: u32 = 8u;
const PHOTON_RECORD_DEPOSITS: u32 = 32u;
const PHOTON_PAIR_DEPOSITS: u32 = 64u;
// The wgpu backend's own bit (backend_wgpu::layout::PHOTON_MARK_CANCELLED): a pairing pose B
// whose pose-A deposits are held unfiled marks both deposits of each pair that cancels, for
// the map that joins them to leave out.
const PHOTON_MARK_CANCELLED: u32 = 0x80000000u;
// The four words beside a deposit so marked, in place of a partner: a real partner's
// luminance is pose A's, which is never positive.
const CANCELLED_PARTNER: vec4<f32> = vec4<f32>(0.0, 0.0, 0.0, 1.0);

struct GatherParams {
    alpha: f32,
    emitted_increment: f32,
    kind: u32,
    region_photons: f32,
}

struct GridParams {
    cell_size: f32,
    bucket_count: u32,
    photon_count: u32,
    _pad0: u32,
}

struct GridPhoton {
    position: vec3<f32>,
    cell: u32,
    power: vec3<f32>,
    normal_oct: u32,
}

// ppm_core::update::pairing's constants.
const PAIRED_DEPOSITS: u32 = 4u;
const PAIR_FLOOR: f32 = 0.25;

struct PathDeposits {
    deposits: array<vec4<f32>, 4>,
    normal_oct: vec4<u32>,
    slots: vec4<u32>,
}

struct EmissionRegion {
    light_point: vec3<f32>,
    mode: u32,
    origin: vec3<f32>,
    _pad1: u32,
    edge_u: vec3<f32>,
    area: f32,
    edge_v: vec3<f32>,
    _pad0: u32,
}

const REGION_AREA: u32 = 0u;
const REGION_POINT: u32 = 1u;

struct RecordedPath {
    origin: vec3<f32>,
    light: u32,
    direction: vec3<f32>,
    _pad0: u32,
}

struct GuidedEmission {
    cos_cone: f32,
    beta: f32,
    paths: u32,
    weighted: u32,
}

// Where a photon pass's photons start (ppm_core::layout::Emitter), by kind.
const EMISSION_ORDINARY: u32 = 0u;
const EMISSION_REGION: u32 = 1u;
const EMISSION_GUIDED: u32 = 2u;

struct Emitter {
    kind: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    region: EmissionRegion,
    guide: GuidedEmission,
}

const GATHER_ORDINARY: u32 = 0u;
const GATHER_REGION_NEGATIVE: u32 = 1u;
const GATHER_REGION_POSITIVE: u32 = 2u;
const GATHER_GUIDED: u32 = 3u;
const GATHER_REGION_APPLY: u32 = 4u;
const GATHER_KIND_MASK: u32 = 0xffu;
const GATHER_RAW_COUNT: u32 = 0x100u;
const GATHER_DEFERRED: u32 = 0x200u;
const GATHER_ADD_FLUX: u32 = 0x400u;

// A local move's parameters (ppm_core::layout::LocalMoveParams), beside its boxes.
struct LocalMoveParams {
    seed: u32,
    groups: u32,
    max_depth: u32,
    ray_epsilon: f32,
    r2_initial: f32,
    r2_floor: f32,
    widest: f32,
    direct_samples: u32,
    objects: u32,
    lights: u32,
    _pad0: u32,
    _pad1: u32,
}

// A camera move's parameters (ppm_core::layout::CameraMoveParams): the cameras before and
// after, and the slots per pixel.
struct CameraMoveParams {
    before: GpuCamera,
    after: GpuCamera,
    spp: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct ResolveParams {
    width: u32,
    height: u32,
    spp: u32,
    _pad0: u32,
}

// How many slots a kernel over a list walks (backend_wgpu::layout::ListParams): those a
// local move listed in pose A (its pair kernels) or for its probe, or a focus eye pass's
// slots behind.
struct ListParams {
    count: u32,
    // A local move's pair kernels: whether `known` and `known_store` hold the last move's
    // pairs in this pose, keyed and traced as this move's (1), or not (0).
    known: u32,
    // The eye and direct-light passes: whether they walk a focus pass's list (1) or every
    // slot (0).
    focus: u32,
    _pad0: u32,
}

// Launch geometry: work items beyond 65,535 workgroups spill into the y dimension.
const WORKGROUP_SIZE: u32 = 64u;

fn item_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.y * groups.x * WORKGROUP_SIZE + gid.x;
}

// A NaN or infinity has every exponent bit set; bit tests survive fast-math compilers.
fn is_finite_f32(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn is_finite_vec3(v: vec3<f32>) -> bool {
    return is_finite_f32(v.x) && is_finite_f32(v.y) && is_finite_f32(v.z);
}

// The largest finite f32: the corners of the box of no point (ppm_core's GpuBounds::NOTHING).
const F32_MAX: f32 = 3.4028235e38;
// The smallest positive normal f32 (Rust's f32::MIN_POSITIVE).
const F32_MIN_POSITIVE: f32 = 1.17549435e-38;

// What a slot's eye path found at its glossy bounces (ppm_core::layout::ChainLight).
struct ChainLight {
    radiance: vec3<f32>,
    emission_weight: f32,
}

struct GpuBounds {
    min: vec3<f32>,
    _pad0: u32,
    max: vec3<f32>,
    _pad1: u32,
}
