//! Buffer layouts shared by every backend.
//!
//! Each struct is `#[repr(C)]` + Pod and is byte-for-byte the element of a GPU storage buffer:
//! a `Vec<HitPoint>` on the CPU is exactly what a WGSL `array<HitPoint>` binds. Fields are
//! grouped as `vec3<f32>` + one scalar so that every struct is a multiple of 16 bytes and matches
//! WGSL's std430-like alignment rules without hidden padding.

use crate::update::pairing::PAIRED_DEPOSITS;
use bytemuck::{Pod, Zeroable};

/// Material kinds, stored in [`GpuMaterial::kind`].
pub mod material_kind {
    /// Lambertian reflector (`albedo`), optionally emitting (`emission`).
    pub const DIFFUSE: u32 = 0;
    /// Perfect specular reflector with reflectance `albedo`.
    pub const MIRROR: u32 = 1;
    /// Smooth dielectric: Fresnel reflection and refraction with index `ior`.
    pub const GLASS: u32 = 2;
    /// Metal: Fresnel reflection of complex index `eta + i k`, scaled by `albedo`, on GGX
    /// microfacets of roughness `alpha` (smooth below [`crate::bsdf::SMOOTH_ALPHA`]).
    pub const CONDUCTOR: u32 = 3;
    /// A diffuse base of reflectance `albedo` under a dielectric coat of index `ior` and GGX
    /// roughness `alpha`; the `coat` fields of [`super::GpuMaterial`] describe what the coat
    /// lets through.
    pub const COATED: u32 = 4;
}

/// Bits of [`HitPoint::flags`].
pub mod hit_flags {
    /// The slot has a visible point this iteration; without it the eye path escaped, was
    /// absorbed or ran out of depth (its statistics stay, and so does its share of the pixel).
    pub const VALID: u32 = 1;
    /// The eye ray met the surface on the side its normal points to: emitters emit only there.
    pub const FRONT: u32 = 2;
    /// The slot was reset by the last hit-point update (docs/algorithm.md 2.4).
    pub const UPDATED: u32 = 4;
    /// Set by a local move on the kept slots whose direct light the move may change, whose
    /// direct sums it corrected (docs/algorithm.md 3c); no pass reads it.
    pub const DIRECT_MAY_CHANGE: u32 = 16;
    /// The slot sits out this iteration's eye pass and direct light (an eye pass with
    /// [`eye_flags::FOCUS`](super::eye_flags::FOCUS) found it ahead of the slots a move reset):
    /// its last visible point stays and gathers the iteration's photons, which cost nothing
    /// more to trace.
    pub const RESTING: u32 = 32;
    /// Some eye path of the slot since its statistics started bounced off a mirror or glass
    /// before its visible point: what it sees in another pose of an object the screen cannot
    /// tell (a local move probes it).
    pub const EYE_CHAINED: u32 = 128;
    /// The flags a slot keeps from iteration to iteration (`sppm`).
    pub const KEPT: u32 = UPDATED | EYE_CHAINED;
    /// The index of the object hit sits in the bits from here up (24 bits).
    pub const OBJECT_SHIFT: u32 = 8;
}

/// Marks an empty hit-point slot in [`HitPoint::material`].
pub const NO_MATERIAL: u32 = u32::MAX;

/// One eye sample of one pixel (a slot): this iteration's visible point, and the progressive
/// statistics the slot keeps across iterations (docs/algorithm.md 1).
///
/// With `sppm` the visible point (position, normal, material, throughput, the `VALID`/`FRONT`
/// flags) is traced anew every iteration while the statistics (`r2`, `n`, `tau`, `emitted`,
/// the direct sum and its iteration count) belong to the slot; with `ppm` the visible point
/// is traced once per frame. Both fold the eye path's throughput and the BRDF into what they
/// accumulate, so the pixel is `direct / iterations + tau / (pi r2 emitted)` either way.
///
/// 112 bytes: six 16-byte rows, each a `vec3<f32>` plus one scalar, and a seventh of four
/// scalars, three of them padding. At 768x768 with one eye sample per pixel that is 589,824
/// slots = 66.1 MB, well inside one storage binding (128 MiB baseline limit). The diffuse
/// albedo is not stored (`material` indexes it), nor the outgoing direction (hit points are
/// Lambertian).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitPoint {
    /// World-space position of the visible point.
    pub position: [f32; 3],
    /// Pixel index `y * width + x` this slot belongs to.
    pub pixel: u32,
    /// Shading normal, flipped to face the eye ray.
    pub normal: [f32; 3],
    /// Index into the material buffer, or [`NO_MATERIAL`] when the slot has no visible point.
    pub material: u32,
    /// Product of specular reflectances along this iteration's eye path.
    pub throughput: [f32; 3],
    /// Squared gather radius `r2` (docs/algorithm.md 1.4).
    pub r2: f32,
    /// Accumulated flux `tau` (power times throughput times BRDF), per channel.
    pub tau: [f32; 3],
    /// Accumulated photon count `n` (fractional: it grows by `alpha * M`).
    pub n: f32,
    /// Sum over the slot's iterations of the radiance towards the eye from emission seen and
    /// explicit direct light, times the eye path's throughput.
    pub direct: [f32; 3],
    /// Photons emitted so far for this slot: the normaliser of docs/algorithm.md 1.5.
    pub emitted: f32,
    /// Iterations summed in `direct`.
    pub iterations: u32,
    /// [`hit_flags`] bits.
    pub flags: u32,
    /// The object groups ([`object_group`](crate::compile::object_group)) that the slot's
    /// eye paths met since its statistics started: a move of one of them changes what the
    /// slot saw (a local move resets it).
    pub eye_met: u32,
    /// Squared radius of the disc this slot gathers a local move's correction within, when
    /// wider than the pass's floor ([`search_r2`](crate::update::gather::search_r2)): the
    /// driver widens it far from the moved objects, where the change is smooth. Written at a
    /// move, read by no other gather.
    pub correction_r2: f32,
    /// How many of the `n` photons local moves' corrections discounted: the statistics are
    /// worth `n - discounted` photons against the next correction (docs/algorithm.md 3c),
    /// while `n` itself still sets how fast the radius shrinks. Starts over with `n`.
    pub discounted: f32,
    /// Pads the slot to its WGSL stride, a multiple of 16 bytes.
    pub _pad: [u32; 3],
}

impl HitPoint {
    /// An empty slot for `pixel`: no visible point, no statistics.
    pub fn empty(pixel: u32) -> Self {
        Self {
            pixel,
            material: NO_MATERIAL,
            ..Self::default()
        }
    }

    /// Whether the slot has a visible point this iteration.
    pub fn is_valid(&self) -> bool {
        self.flags & hit_flags::VALID != 0
    }

    /// Mean direct radiance over the slot's iterations (zero before the first).
    pub fn direct_mean(&self) -> [f32; 3] {
        let k = self.iterations.max(1) as f32;
        self.direct.map(|d| d / k)
    }
}

/// What one slot's eye path found at its glossy bounces, for the direct-light pass to add
/// (docs/algorithm.md 1.2). 16 bytes; held only for a scene with glossy surfaces
/// ([`SceneFeatures::glossy`](crate::compile::SceneFeatures::glossy)).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ChainLight {
    /// The light samples' radiance towards the eye, the path's throughput included.
    pub radiance: [f32; 3],
    /// The power-heuristic weight of the emission at the visible point against a light
    /// sample at the glossy bounce before it: one when none came before.
    pub emission_weight: f32,
}

impl ChainLight {
    /// A path without glossy bounces.
    pub const NONE: Self = Self {
        radiance: [0.0; 3],
        emission_weight: 1.0,
    };
}

impl Default for ChainLight {
    fn default() -> Self {
        Self::NONE
    }
}

/// A photon deposit made during a photon pass.
///
/// 32 bytes, so that ten million photons fit in 320 MB. The surface normal is packed
/// octahedrally into one `u32` (16 bits per coordinate): it only decides which side of a surface
/// the photon lies on. No incoming direction is stored: hit points are Lambertian, whose BRDF does
/// not depend on it, so a scene never needs it (a glossy BRDF would add it here).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    /// Where the photon landed.
    pub position: [f32; 3],
    /// Index of the photon path within its pass that made this deposit.
    pub path: u32,
    /// Power carried (RGB, negative for compensation photons).
    pub power: [f32; 3],
    /// Octahedral encoding of the surface normal on the side the photon arrived from.
    pub normal_oct: u32,
}

/// One scene triangle in the form the intersection test wants: a vertex and two edges.
///
/// 64 bytes. Triangles are stored in BVH leaf order, so leaves index them directly.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    /// First vertex.
    pub v0: [f32; 3],
    /// Index into the material buffer.
    pub material: u32,
    /// `v1 - v0`.
    pub e1: [f32; 3],
    /// Index of the named object this triangle belongs to.
    pub object: u32,
    /// `v2 - v0`.
    pub e2: [f32; 3],
    /// Index into the light buffer if the triangle emits, else `u32::MAX`.
    pub light: u32,
    /// Unit geometric normal, `normalize(e1 x e2)`; zero for a degenerate triangle.
    pub normal: [f32; 3],
    /// The bit of the triangle's object group ([`object_group`](crate::compile::object_group)):
    /// an eye path that meets the triangle sets it in its slot's [`HitPoint::eye_met`].
    pub group: u32,
}

/// A node of the binary BVH built by obvhs, flattened for traversal on any backend.
///
/// 32 bytes. Inner node: `count == 0`, children at `first` and `first + 1`. Leaf: triangles
/// `first .. first + count` of the (reordered) triangle buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Bounding-box minimum.
    pub min: [f32; 3],
    /// First child or first triangle.
    pub first: u32,
    /// Bounding-box maximum.
    pub max: [f32; 3],
    /// Number of triangles in a leaf, zero for an inner node.
    pub count: u32,
}

/// A material. 128 bytes; the last 64 describe a coat and are zero for every other kind.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Diffuse albedo or specular reflectance (a conductor's factor on its Fresnel term), per
    /// channel, in [0, 1].
    pub albedo: [f32; 3],
    /// One of [`material_kind`].
    pub kind: u32,
    /// Emitted radiance `Le` (one-sided, along the triangle's normal); zero for non-emitters.
    pub emission: [f32; 3],
    /// Index of refraction (glass only).
    pub ior: f32,
    /// Real part of a conductor's complex index of refraction, per channel.
    pub eta: [f32; 3],
    /// GGX roughness `alpha` of a conductor's, glass's or coat's microfacets along the
    /// surface's tangent (0: smooth; [`Frame`](crate::geometry::Frame)).
    pub alpha: f32,
    /// Imaginary part (absorption) of a conductor's index, per channel.
    pub k: [f32; 3],
    /// One plus the index of the texture that scales `albedo` at each point
    /// ([`GpuTexture`]); 0 when `albedo` is uniform.
    pub texture: u32,
    /// A coat's internal reflectance `F_int`: the share of light diffused by the base that
    /// the coat sends back to it (the cosine-weighted mean of its reflectance from inside).
    pub coat_internal: f32,
    /// 1 when the base's colour is met at every return under the coat (`albedo / (1 -
    /// albedo F_int)`), 0 when once (`albedo / (1 - F_int)`).
    pub coat_nonlinear: u32,
    /// The share of a rough coat's samples spent on its reflection where the two lobes are
    /// equally likely to matter (Mitsuba 3's `specular_sampling_weight`).
    pub coat_specular_weight: f32,
    /// GGX roughness across the tangent: `alpha` but where the material is anisotropic.
    pub alpha_v: f32,
    /// A rough coat's transmittance `1 - R(mu)` (`R` its directional reflectance) at
    /// `mu = (i / 11)^2`, `i = 0 ..= 11`: dense where it changes fast, at grazing angles.
    pub coat_transmittance: [f32; 12],
}

/// An image texture's header (docs/materials.md, "Textures"); its texels, two words each
/// ([`pack_texel`](crate::scene::pack_texel)), are `first .. first + width * height` of the
/// scene's texel buffer, rows from the top. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// Index of the top-left texel in the scene's texel buffer.
    pub first: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// 1: the nearest texel; 0: bilinear.
    pub nearest: u32,
    /// `(s, t) = scale * uv + offset`.
    pub scale: [f32; 2],
    /// See `scale`.
    pub offset: [f32; 2],
}

/// The texture coordinates of one triangle's vertices, in the triangle buffer's order. 32
/// bytes; only scenes with a texture have them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangleUv {
    /// At `v0`.
    pub uv0: [f32; 2],
    /// At `v1`.
    pub uv1: [f32; 2],
    /// At `v2`.
    pub uv2: [f32; 2],
    /// Padding.
    pub _pad: [u32; 2],
}

/// An axis-aligned box: a moved object's box in one of its poses (the boxes whose crossing a
/// move's photon passes watch for), or the box of the vertices a slot's eye paths reached
/// ([`SlotBounds`]). 32 bytes.
/// An empty box (`min > max`) stands for "nothing moves" and no ray crosses it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuBounds {
    /// Smallest corner.
    pub min: [f32; 3],
    /// Padding.
    pub _pad0: u32,
    /// Largest corner.
    pub max: [f32; 3],
    /// Padding.
    pub _pad1: u32,
}

/// The box of every vertex a slot's eye paths reached after leaving the camera (mirror and
/// glass bounces and visible points) since its statistics started: a local move tests
/// against it where the slot's paths and shadow rays may have gone. Fresh, it is
/// [`GpuBounds::NOTHING`].
pub type SlotBounds = GpuBounds;

impl GpuBounds {
    /// The box of no point, which any point's box contains: `min` at `f32::MAX` and `max` at
    /// `-f32::MAX`, so that taking the minimum and maximum with a point gives that point.
    pub const NOTHING: GpuBounds = GpuBounds {
        min: [f32::MAX; 3],
        _pad0: 0,
        max: [-f32::MAX; 3],
        _pad1: 0,
    };

    /// The box no ray crosses.
    pub const EMPTY: GpuBounds = GpuBounds {
        min: [1.0; 3],
        _pad0: 0,
        max: [-1.0; 3],
        _pad1: 0,
    };

    /// The box between two corners.
    pub fn new(min: glam::Vec3, max: glam::Vec3) -> Self {
        GpuBounds {
            min: min.into(),
            max: max.into(),
            ..Self::EMPTY
        }
    }
}

/// One emitting triangle, with what photon emission needs precomputed. 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// First vertex.
    pub v0: [f32; 3],
    /// Triangle area.
    pub area: f32,
    /// `v1 - v0`.
    pub e1: [f32; 3],
    /// Cumulative selection probability up to and including this light (the last is 1).
    pub cdf: f32,
    /// `v2 - v0`.
    pub e2: [f32; 3],
    /// Probability of selecting this light for a photon.
    pub pdf: f32,
    /// Unit normal: the side that emits.
    pub normal: [f32; 3],
    /// Index of the triangle's material, which holds the radiance.
    pub material: u32,
}

/// Pinhole camera, in the form ray generation wants. 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    /// Eye position.
    pub eye: [f32; 3],
    /// Image width in pixels.
    pub width: u32,
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Image height in pixels.
    pub height: u32,
    /// Unit screen-right vector scaled by `tan(fov/2) * aspect`.
    pub right: [f32; 3],
    /// Padding.
    pub _pad0: u32,
    /// Unit screen-up vector scaled by `tan(fov/2)`.
    pub up: [f32; 3],
    /// Padding.
    pub _pad1: u32,
}

/// Bits of [`EyePassParams::flags`].
pub mod eye_flags {
    /// Keep each slot's statistics and replace only its visible point (an `sppm` iteration);
    /// without it every slot starts fresh (`r2 = r2_initial`, everything else zero).
    pub const KEEP_STATISTICS: u32 = 1;
    /// Shoot through a random point of the pixel even with one sample per pixel (`sppm`);
    /// without it one sample per pixel goes through the pixel's centre.
    pub const JITTER: u32 = 2;
    /// With `KEEP_STATISTICS`: slots whose direct sum already holds
    /// [`EyePassParams::rest_at`](super::EyePassParams::rest_at) iterations rest, skipping the eye path and direct light
    /// (local mode, after a move: that work goes to the slots the move reset until they catch
    /// up with the kept ones).
    pub const FOCUS: u32 = 4;
    /// Extend each kept slot's [`SlotBounds`](super::SlotBounds) by its eye path's vertices (started over where
    /// the slot's statistics start); without it the bounds are left alone (the probe of a
    /// local move, the hit-point update of the other modes).
    pub const RECORD_BOUNDS: u32 = 8;
    /// Without `KEEP_STATISTICS`: trace each slot's last sample again, the jitter stratum its
    /// own sequence last used (its `iterations` less one), read from the slot before it is
    /// overwritten; the hit-point update of the thesis's modes. Without this flag a fresh
    /// slot draws stratum `iteration`, which a slot whose direct sum a move restarted no
    /// longer follows: every move after the first then found nearly every visible point
    /// moved and reset it.
    pub const RETRACE: u32 = 16;
    /// Take a light sample at each glossy bounce, weighed against the bounce, for the
    /// direct-light pass ([`ChainLight`](super::ChainLight)): direct light is explicit.
    /// Without it (photons carry direct light) the bounce alone finds what a glossy surface
    /// reflects of the lights.
    pub const SAMPLE_LIGHTS: u32 = 32;
}

/// Parameters of one eye pass. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct EyePassParams {
    /// Run seed.
    pub seed: u32,
    /// Eye samples (slots) per pixel.
    pub spp: u32,
    /// Specular bounces after which an eye path is dropped.
    pub max_depth: u32,
    /// Keys the random generator: the iteration (`sppm`) or the frame (`ppm`).
    pub iteration: u32,
    /// Initial squared radius given to every fresh slot.
    pub r2_initial: f32,
    /// Offset along the normal for new ray origins, against self-intersection.
    pub ray_epsilon: f32,
    /// [`eye_flags`] bits.
    pub flags: u32,
    /// With [`eye_flags::FOCUS`]: the iteration count from which a slot rests.
    pub rest_at: u32,
}

/// Parameters of the direct-light pass. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DirectLightParams {
    /// Run seed.
    pub seed: u32,
    /// Samples per hit point (0 when photons carry direct light): each a shadow ray and a
    /// cosine ray.
    pub samples: u32,
    /// Keys the random generator: the iteration (`sppm`) or the frame (`ppm`).
    pub iteration: u32,
    /// Offset along the normal for shadow-ray origins.
    pub ray_epsilon: f32,
    /// One of [`direct_accumulate`].
    pub accumulate: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// What the direct-light pass does with its estimate, in [`DirectLightParams::accumulate`].
pub mod direct_accumulate {
    /// Replace each slot's direct sum with it (`ppm`, once per frame).
    pub const REPLACE: u32 = 0;
    /// Add it to the sum as one more iteration (`sppm`).
    pub const ADD: u32 = 1;
}

/// How the photon pass treats the first surface a photon meets after leaving the light.
pub mod first_hit {
    /// Skip it: explicit direct light already counts that light (the thesis's choice).
    pub const SKIP: u32 = 0;
    /// Deposit it: photons carry direct light too (classic PPM).
    pub const DEPOSIT: u32 = 1;
}

/// Parameters of one photon pass. 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonPassParams {
    /// Run seed.
    pub seed: u32,
    /// Global index of this photon pass (keys the random generator).
    pub pass_index: u32,
    /// Photons emitted in this pass.
    pub photon_count: u32,
    /// Bounces after which a photon path stops.
    pub max_depth: u32,
    /// One of [`first_hit`].
    pub first_hit: u32,
    /// Offset along the normal for new ray origins.
    pub ray_epsilon: f32,
    /// Multiplies every emitted photon's power (1 for ordinary photons).
    pub power_scale: f32,
    /// Index of the first path traced: paths `first_path .. first_path + photon_count`. Lets a
    /// backend split a pass into batches that still draw the numbers of the whole pass.
    pub first_path: u32,
    /// [`photon_flags`] bits.
    pub flags: u32,
    /// Bit of path `p` in the crossed-path mask is `mask_offset + p` (with
    /// [`photon_flags::RECORD_CROSSED`] or [`photon_flags::CULL_UNCROSSED`]): each of a move's
    /// difference passes has its own slot, read in pose B where pose A wrote it.
    pub mask_offset: u32,
    /// The [`gather_kind`], flags included, of the gather pass that will consume this map,
    /// which must name the same (pbrt-v4's SPPM has one photon pass too; here a map is
    /// gathered once, by one kind). A backend that searches while it traces, as the wgpu
    /// backend folds each batch into per-slot sums, searches only for the slots that kind
    /// gathers ([`crate::update::gather::gathers`]).
    pub gather_kind: u32,
    /// Squared radius within which every slot gathers this pass's photons at least, or its
    /// `correction_r2` where wider ([`search_r2`](crate::update::gather::search_r2)): a slot
    /// whose `r2` is smaller searches that disc and scales what it finds by `r2` over it
    /// (local mode's correction, which a small converged disc would gather too noisily).
    /// Zero: each slot gathers within its own radius.
    pub gather_r2_floor: f32,
}

/// Bits of [`PhotonPassParams::flags`]. The driver sets only [`KEEP_PATHS`](photon_flags::KEEP_PATHS), a hint; the others
/// are how the CPU and wgpu backends' photon passes trace a local move's correction
/// ([`CorrectionPhotons::flagged_pass`](crate::local_move::CorrectionPhotons::flagged_pass)),
/// which a backend of its own need not honour.
pub mod photon_flags {
    /// Store only the deposits whose path crossed a moved object's box before reaching them
    /// (local mode's difference passes): a path that has not met a box is the same in both
    /// poses, so its deposits would cancel between the two poses; dropping them in both is
    /// exact, and the gathers then cost in proportion to the light the move touches.
    pub const CHANGED_ONLY: u32 = 1;
    /// Write into the crossed-path mask, per path traced, whether it crossed a moved object's box
    /// anywhere, its last segment included (local mode's pose-A difference passes).
    pub const RECORD_CROSSED: u32 = 2;
    /// Skip the paths whose bit in the crossed-path mask is clear (pose B, with the mask pose
    /// A recorded): such a path meets the same surfaces in both poses, so with
    /// [`CHANGED_ONLY`] it would store nothing. A bit no pass recorded counts as set.
    pub const CULL_UNCROSSED: u32 = 4;
    /// A hint, on an ordinary pass: a local move may soon ask, in this same pose, for a
    /// [`CHANGED_ONLY`] pass with these random numbers (its pose-A correction). A backend may
    /// keep the paths' segments to answer it by testing them against the movers' boxes instead
    /// of tracing them again; the answer must be what tracing gives. One that keeps nothing
    /// ignores it.
    pub const KEEP_PATHS: u32 = 8;
    /// Add this pass's photons to those of the photon pass before it, which no eye pass or
    /// gather has consumed since and which named the same gather kind and floor: the gather
    /// that follows folds both as one map (local mode's correction, whose gather only adds,
    /// searches pose A's negative and pose B's positive photons at once instead of twice). A
    /// scene update between the two keeps the first one's photons for this.
    pub const ADD_TO_MAP: u32 = 16;
    /// Keep each path's first [`PAIRED_DEPOSITS`](crate::update::pairing::PAIRED_DEPOSITS)
    /// stored deposits ([`PathDeposits`](super::PathDeposits), at the path's bit of the mask)
    /// for a [`PAIR_DEPOSITS`] pass to pair with (a local move's pose-A correction). A backend
    /// that still holds this pass's deposits when the pairing pass runs may read them there.
    pub const RECORD_DEPOSITS: u32 = 32;
    /// Pair each deposit with the one its path stored in the same order in the
    /// [`RECORD_DEPOSITS`] pass just before (pose A's), as
    /// [`partner`](crate::update::pairing::partner) says, and carry that partner's position
    /// and luminance: a gather that sums squares adds the cross term
    /// ([`variance_term`](crate::update::pairing::variance_term)) where both lie in the
    /// disc, so the correction's variance counts each path's net deposit
    /// ([`crate::update::pairing`]; a local move's pose-B correction).
    pub const PAIR_DEPOSITS: u32 = 64;
}

/// Which photons a gather folds in, who gathers them, and with which update
/// (docs/algorithm.md 3, "Who gathers what"), stored in [`GatherParams::kind`].
pub mod gather_kind {
    /// Ordinary photons: every hit point, eqs 1-3, `emitted` grows.
    pub const ORDINARY: u32 = 0;
    /// Compensation photons (negative, pose A): hit points not updated, eqs 5-7 with clamps.
    pub const REGION_NEGATIVE: u32 = 1;
    /// Region photons (positive, pose B): hit points not updated, eqs 1-3.
    pub const REGION_POSITIVE: u32 = 2;
    /// Testing and guided photons: updated hit points only, eqs 1-3, `emitted` grows.
    pub const GUIDED: u32 = 3;
    /// No photons: folds the region photons deferred so far into the statistics, as one
    /// update with their net count and flux, and clears them.
    pub const REGION_APPLY: u32 = 4;
    /// Low bits hold the kind.
    pub const KIND_MASK: u32 = 0xff;
    /// Flag on region kinds: add the photons to a per-hit-point pending sum instead of
    /// updating now (area mode). With the same random numbers for the compensation and the
    /// region passes, the photons whose paths the move did not touch cancel exactly in the
    /// sum, so only the light that changed reaches the statistics.
    pub const DEFERRED: u32 = 0x200;
    /// Flag: region photons count raw in `M` (thesis mode) instead of as the ordinary photons
    /// their weights stand for (area mode).
    pub const RAW_COUNT: u32 = 0x100;
    /// Local mode's flux-only correction (it brings no new photons to shrink the radius
    /// with). On deferred region kinds: the pending count keeps the correction's variance
    /// instead (the squared luminance of each photon's contribution, summed). On
    /// `REGION_APPLY`: add the pending flux to `tau` (clamped at zero), leave `n` and `r2`,
    /// and scale `tau` and `emitted` by the share of the slot's history worth keeping against
    /// that variance ([`crate::update::history_kept`]).
    pub const ADD_FLUX: u32 = 0x400;
}

/// Parameters of one gather pass. 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherParams {
    /// Fraction of new photons kept, in (0, 1) (docs/algorithm.md 1.4).
    pub alpha: f32,
    /// Photons this pass adds to each gathering hit point's `emitted`.
    pub emitted_increment: f32,
    /// One of [`gather_kind`], with its flags.
    pub kind: u32,
    /// Photons of all the region passes that together make one compensation (`N_c`), each
    /// standing for `emitted / N_c` ordinary photons times its weight; unused otherwise.
    pub region_photons: f32,
}

/// Where one photon pass's photons start, as a GPU backend uploads it: the plain form of
/// [`crate::emission::PhotonSource`], which builds it. 96 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Emitter {
    /// One of [`emission_kind`].
    pub kind: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
    /// The emitting region (region passes).
    pub region: EmissionRegion,
    /// The guide (guided passes), its `paths` the recorded paths passed beside it.
    pub guide: GuidedEmission,
}

/// Values of [`Emitter::kind`].
pub mod emission_kind {
    /// Ordinary photons, from the lights (docs/algorithm.md 1.3).
    pub const ORDINARY: u32 = 0;
    /// Through the emitting region (docs/algorithm.md 2.2, 2.5).
    pub const REGION: u32 = 1;
    /// Around recorded paths (docs/algorithm.md 2.6).
    pub const GUIDED: u32 = 2;
}

/// The emitting region of compensation and region photons (docs/algorithm.md 2.1, 3). 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct EmissionRegion {
    /// Thesis mode: the point light (the lights' area-weighted centre).
    pub light_point: [f32; 3],
    /// One of [`region_mode`].
    pub mode: u32,
    /// A corner of the rectangle.
    pub origin: [f32; 3],
    /// Padding.
    pub _pad1: u32,
    /// First edge of the rectangle from `origin`.
    pub edge_u: [f32; 3],
    /// Area of the rectangle.
    pub area: f32,
    /// Second edge, orthogonal to the first.
    pub edge_v: [f32; 3],
    /// Padding.
    pub _pad0: u32,
}

/// Where region photons start (docs/algorithm.md 3, "Which light point").
pub mod region_mode {
    /// Uniform on the area lights (ours, the default).
    pub const AREA: u32 = 0;
    /// The point light at the lights' centre (the thesis's T3.3 choice).
    pub const POINT: u32 = 1;
}

/// A recorded emission that reached an updated hit point: guided photons start around it.
/// 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RecordedPath {
    /// Where the testing photon left the light.
    pub origin: [f32; 3],
    /// Index of the light it left.
    pub light: u32,
    /// Its emission direction.
    pub direction: [f32; 3],
    /// Padding.
    pub _pad0: u32,
}

/// How guided photons are emitted (docs/algorithm.md 2.6, 3). 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GuidedEmission {
    /// Cosine of the jitter cone's half-angle.
    pub cos_cone: f32,
    /// Probability of drawing from the ordinary distribution (defensive mixture).
    pub beta: f32,
    /// Recorded paths to draw around.
    pub paths: u32,
    /// 1: weight by `p_ordinary / p_mixture` (unbiased, ours); 0: the thesis's unweighted rule.
    pub weighted: u32,
}

/// The hash grid that indexes one pass's photons ([`crate::grid`]). 16 bytes.
///
/// A photon lies in cell [`crate::grid::cell_of`]`(p, cell_size)`, whose key
/// ([`crate::grid::cell_key`]) masked to `bucket_count - 1` is its bucket.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridParams {
    /// Edge of a cell, from the gather radii in use.
    pub cell_size: f32,
    /// Number of hash buckets, a power of two.
    pub bucket_count: u32,
    /// Photons in the map.
    pub photon_count: u32,
    /// Padding.
    pub _pad0: u32,
}

/// A photon as the gather reads it: stored in bucket order, with its cell's key so that a
/// gather skips the photons of another cell sharing the bucket. 32 bytes, like [`Photon`],
/// whose path index it trades for the key (the grid keeps each one's index in the pass).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridPhoton {
    /// Where the photon landed.
    pub position: [f32; 3],
    /// Key of its cell.
    pub cell: u32,
    /// Power carried.
    pub power: [f32; 3],
    /// Octahedral encoding of the surface normal on the side the photon arrived from.
    pub normal_oct: u32,
}

/// Pose A's first stored deposits of one path of a local move's correction, which pose B's
/// pass pairs its own with ([`crate::update::pairing`]): per deposit its position and power
/// luminance, then their packed normals and where they lie in pose A's deposit buffer. 96
/// bytes; a deposit of luminance zero stands for none, so a fresh (zeroed) record pairs
/// nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathDeposits {
    /// Per stored deposit, in order: position and luminance.
    pub deposits: [[f32; 4]; PAIRED_DEPOSITS],
    /// Their octahedral normals ([`Photon::normal_oct`]).
    pub normal_oct: [u32; PAIRED_DEPOSITS],
    /// Their indices among pose A's deposits as the backend holds them, so that pose B can
    /// mark the deposit of a pair that cancels, which its map then leaves out
    /// ([`Partner::cancels`](crate::update::pairing::Partner::cancels)).
    pub slots: [u32; PAIRED_DEPOSITS],
}

/// A local move's parameters as a GPU backend uploads them
/// ([`LocalMove::params`](crate::local_move::LocalMove::params)), beside a buffer of its
/// boxes ([`LocalMove::boxes`](crate::local_move::LocalMove::boxes): the moved objects' in
/// pose A, then in pose B, then the lights') and one of the moved objects' indices. 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LocalMoveParams {
    /// The render's seed, which keys the probes' and the pairs' random numbers.
    pub seed: u32,
    /// The bits of the moved objects' groups.
    pub groups: u32,
    /// Bounces of the probes' and the pairs' eye paths.
    pub max_depth: u32,
    /// Offset along the normal of their rays' origins.
    pub ray_epsilon: f32,
    /// The squared radius a slot that starts over gets.
    pub r2_initial: f32,
    /// The correction's squared floor radius.
    pub r2_floor: f32,
    /// The widest a kept slot's correction disc grows, in floor radii.
    pub widest: f32,
    /// Paired direct-light samples per slot whose direct light may change.
    pub direct_samples: u32,
    /// Moved objects: boxes `0..objects` are theirs in pose A, `objects..2 objects` in pose B.
    pub objects: u32,
    /// Light boxes, from box `2 objects` on.
    pub lights: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
}

/// Parameters of a camera move's inheritance (docs/algorithm.md 3d): the cameras before and
/// after, and how the slots are laid out. 144 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CameraMoveParams {
    /// The camera the earlier slots were traced from.
    pub before: GpuCamera,
    /// The camera the slots are traced from now.
    pub after: GpuCamera,
    /// Eye samples per pixel: slot `pixel * spp + s`.
    pub spp: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// Parameters of the resolve pass. 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ResolveParams {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Eye samples (hit-point slots) per pixel.
    pub spp: u32,
    /// Padding.
    pub _pad0: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, size_of};

    /// Every shared struct is a whole number of 16-byte rows with 4-byte alignment, so that its
    /// Rust size equals its WGSL stride.
    #[test]
    fn layouts_are_whole_rows() {
        let sizes = [
            ("HitPoint", size_of::<HitPoint>(), 112),
            ("EmissionRegion", size_of::<EmissionRegion>(), 64),
            ("RecordedPath", size_of::<RecordedPath>(), 32),
            ("GuidedEmission", size_of::<GuidedEmission>(), 16),
            ("Emitter", size_of::<Emitter>(), 96),
            ("Photon", size_of::<Photon>(), 32),
            ("GpuTriangle", size_of::<GpuTriangle>(), 64),
            ("BvhNode", size_of::<BvhNode>(), 32),
            ("GpuMaterial", size_of::<GpuMaterial>(), 128),
            ("GpuLight", size_of::<GpuLight>(), 64),
            ("GpuCamera", size_of::<GpuCamera>(), 64),
            ("EyePassParams", size_of::<EyePassParams>(), 32),
            ("DirectLightParams", size_of::<DirectLightParams>(), 32),
            ("PhotonPassParams", size_of::<PhotonPassParams>(), 48),
            ("GatherParams", size_of::<GatherParams>(), 16),
            ("GridParams", size_of::<GridParams>(), 16),
            ("GridPhoton", size_of::<GridPhoton>(), 32),
            ("ResolveParams", size_of::<ResolveParams>(), 16),
            ("LocalMoveParams", size_of::<LocalMoveParams>(), 48),
            ("CameraMoveParams", size_of::<CameraMoveParams>(), 144),
        ];
        for (name, size, expected) in sizes {
            assert_eq!(size, expected, "{name}");
            assert_eq!(size % 16, 0, "{name}");
        }
        assert_eq!(align_of::<HitPoint>(), 4);
        assert_eq!(std::mem::offset_of!(HitPoint, r2), 44);
        assert_eq!(std::mem::offset_of!(HitPoint, tau), 48);
        assert_eq!(std::mem::offset_of!(HitPoint, iterations), 80);
    }
}
