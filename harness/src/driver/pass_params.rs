//! Every pass's parameters from the render's settings, built in one place: the driver
//! ([`super::Renderer`]) adds only what its state decides (keys, move flags), and the
//! conformance suite and tests call the same functions, so a backend is proved with the
//! parameters it will be driven with, ray offset included.

#[cfg(doc)]
use ppm_core::layout::gather_kind;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, PhotonPassParams, direct_accumulate, eye_flags, first_hit,
};
use ppm_core::params::{DirectMode, Estimator, RenderParams};

/// Offset of secondary ray origins, relative to the scene's extent: ~150 f32 ulps at the
/// largest coordinate, far below any feature of the canonical scenes.
pub const RAY_EPSILON_RELATIVE: f32 = 1e-5;

/// The largest extent, in initial gather radii, that ray offsets follow: cornell-box spans
/// 48 radii, so its offsets are the extent's; beyond a thousand, geometry lies far outside
/// anything the gather resolves.
pub const OFFSET_RADII: f32 = 1000.0;

/// The offset of every pass's secondary rays: relative to the scene's `extent`, but never to
/// more of it than [`OFFSET_RADII`] initial gather radii (a vertex at 1e8 beside a 0.5 m box
/// must not push every offset past the features the gather resolves).
pub fn ray_epsilon(params: &RenderParams, extent: f32) -> f32 {
    RAY_EPSILON_RELATIVE * extent.min(OFFSET_RADII * params.initial_radius)
}

/// The eye pass keyed by `key`: fresh slots, or (`keep`) their statistics kept; `sppm`
/// jitters the point in the pixel and records what the slots' paths reached (what a local
/// move tests against); explicit direct light takes light samples at glossy bounces.
pub fn eye_pass(params: &RenderParams, extent: f32, key: u32, keep: bool) -> EyePassParams {
    let mut flags = if keep { eye_flags::KEEP_STATISTICS } else { 0 };
    if params.estimator == Estimator::Sppm {
        flags |= eye_flags::JITTER | eye_flags::RECORD_BOUNDS;
    }
    if params.direct == DirectMode::Explicit {
        flags |= eye_flags::SAMPLE_LIGHTS;
    }
    EyePassParams {
        seed: params.seed,
        spp: params.spp,
        max_depth: params.max_eye_depth,
        iteration: key,
        r2_initial: params.initial_radius * params.initial_radius,
        ray_epsilon: ray_epsilon(params, extent),
        flags,
        rest_at: 0,
    }
}

/// The direct-light pass keyed by `key`, added to each slot's sum as one more iteration or
/// (`accumulate` false) replacing it; no shadow rays when photons carry direct light.
pub fn direct_light(
    params: &RenderParams,
    extent: f32,
    key: u32,
    accumulate: bool,
) -> DirectLightParams {
    DirectLightParams {
        seed: params.seed,
        samples: match params.direct {
            DirectMode::Explicit => params.direct_samples,
            DirectMode::Photons => 0,
        },
        iteration: key,
        ray_epsilon: ray_epsilon(params, extent),
        accumulate: if accumulate {
            direct_accumulate::ADD
        } else {
            direct_accumulate::REPLACE
        },
        ..Default::default()
    }
}

/// A photon pass of `photon_count` photons keyed by `pass_index`, their power times
/// `power_scale` (-1 for compensation photons), for a gather of `gather_kind` (a
/// [`gather_kind`] with its flags); the first diffuse hit is skipped when shadow rays count
/// direct light.
pub fn photon_pass(
    params: &RenderParams,
    extent: f32,
    pass_index: u32,
    photon_count: u32,
    power_scale: f32,
    gather_kind: u32,
) -> PhotonPassParams {
    PhotonPassParams {
        seed: params.seed,
        pass_index,
        photon_count,
        max_depth: params.max_photon_depth,
        first_hit: match params.direct {
            DirectMode::Explicit => first_hit::SKIP,
            DirectMode::Photons => first_hit::DEPOSIT,
        },
        ray_epsilon: ray_epsilon(params, extent),
        power_scale,
        gather_kind,
        ..Default::default()
    }
}
