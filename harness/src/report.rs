//! The JSON report of a render: parameters, counters, time per pass kind (and per kernel on
//! the device, where it measures them), and what the scene did not need and was left out.

use ppm_core::compile::{CompiledScene, SceneFeatures};
use ppm_core::device_time::DeviceTime;
use ppm_core::params::{DirectMode, Estimator, RenderParams};
use ppm_core::scene::{Scene, degenerate_triangle_count};
use serde::{Deserialize, Serialize};

/// Seconds spent per pass kind, summed over the render.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PassTimes {
    /// Building the BVH (obvhs).
    pub bvh_build: f64,
    /// Handing the buffers to the backend.
    pub upload: f64,
    /// Eye pass.
    pub eye: f64,
    /// Direct-light pass.
    pub direct: f64,
    /// All photon passes.
    pub photon: f64,
    /// All gather passes.
    pub gather: f64,
    /// Resolves.
    pub resolve: f64,
    /// Moves (compensation, hit-point update, testing photons), all passes included.
    pub moves: f64,
    /// Wall clock of the whole render.
    pub total: f64,
}

/// Rays traced per pass kind.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RayCounts {
    /// Camera rays and specular continuations.
    pub eye: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Photon path segments.
    pub photon: u64,
}

/// Everything a render reports.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RenderReport {
    /// Scene name.
    pub scene: String,
    /// Frame the render started in (0 before the scene's moves, 1 after).
    pub frame: u32,
    /// Backend name.
    pub backend: String,
    /// Settings used.
    pub params: RenderParams,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Zero-area triangles (never hit).
    pub degenerate_triangles: usize,
    /// What the scene contains.
    pub features: SceneFeatures,
    /// Slots with a visible point after the last eye pass.
    pub hit_points: u64,
    /// Iterations run (one photon pass each).
    pub passes: u32,
    /// Photons emitted.
    pub photons_emitted: u64,
    /// Photon deposits stored.
    pub photons_deposited: u64,
    /// Photon contributions gathered by hit points.
    pub photons_gathered: u64,
    /// Rays traced.
    pub rays: RayCounts,
    /// Seconds per pass kind.
    pub times: PassTimes,
    /// Seconds the device spent in each kernel of each pass, as it measured them (timestamp
    /// queries); absent where the backend cannot measure them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device_times: Option<Vec<DeviceTime>>,
    /// Passes and code paths not run because the scene or settings do not need them.
    pub left_out: Vec<String>,
    /// Pixels that were not finite after a failed pass and were written as zero.
    pub non_finite_pixels_zeroed: u64,
    /// The error that stopped the render early, if any.
    pub error: Option<String>,
    /// The render was asked to stop (Ctrl-C) before its budget was spent: the image holds
    /// the iterations completed.
    pub interrupted: bool,
    /// This render is one of independent shards (`ppm render --shard I/N`, its own seed),
    /// to be averaged by `ppm merge`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<crate::shard::Shard>,
}

impl RenderReport {
    /// A report with the counters at zero.
    pub fn new(
        backend: &str,
        scene: &Scene,
        params: &RenderParams,
        compiled: &CompiledScene,
    ) -> Self {
        Self {
            scene: scene.name.clone(),
            frame: 0,
            backend: backend.to_owned(),
            params: params.clone(),
            triangles: compiled.triangles.len(),
            degenerate_triangles: degenerate_triangle_count(scene),
            features: compiled.features,
            hit_points: 0,
            passes: 0,
            photons_emitted: 0,
            photons_deposited: 0,
            photons_gathered: 0,
            rays: RayCounts::default(),
            times: PassTimes::default(),
            device_times: None,
            left_out: Vec::new(),
            non_finite_pixels_zeroed: 0,
            error: None,
            interrupted: false,
            shard: None,
        }
    }
}

/// The passes and code paths a render skips, each with the reason.
///
/// `moving`: the render moves the scene; without moves even a scene that could move runs no
/// compensation pass.
pub fn left_out(features: &SceneFeatures, params: &RenderParams, moving: bool) -> Vec<String> {
    let mut out = Vec::new();
    if !features.moving_objects {
        out.push("compensation, region and guided photon passes: no object moves".to_owned());
    } else if !moving {
        out.push(
            "compensation passes: a single frame is rendered (moves apply between frames)"
                .to_owned(),
        );
    }
    if !features.glass {
        out.push("Fresnel sampling and refraction: no glass".to_owned());
    }
    if !features.textured {
        let what = if features.anisotropic {
            "texture images and lookups"
        } else {
            "texture coordinates, images and lookups"
        };
        out.push(format!("{what}: no texture (one word tested a hit)"));
    }
    if !features.anisotropic {
        out.push(
            "tangent frames of anisotropic lobes: no anisotropic roughness (one comparison a glossy hit)"
                .to_owned(),
        );
    }
    if !features.glossy {
        out.push(
            "light samples at glossy eye bounces (16 bytes a slot): no rough metal, coat or glass"
                .to_owned(),
        );
    }
    if !features.specular() {
        out.push(
            "specular eye chains and caustic photon paths: no mirror, glass, conductor or coat"
                .to_owned(),
        );
    }
    match params.direct {
        DirectMode::Explicit => {
            out.push("deposits at a photon's first surface: direct light is explicit".to_owned())
        }
        DirectMode::Photons => out.push("shadow rays: photons carry direct light".to_owned()),
    }
    if params.estimator == Estimator::Ppm && params.spp == 1 {
        out.push("pixel jitter: one eye ray through each pixel centre (ppm)".to_owned());
    }
    out
}
