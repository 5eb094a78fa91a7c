//! Local mode's probe of paths past a mirror or glass (docs/algorithm.md 3c): whether eye
//! paths through random points of a pixel meet a moved object in the new pose. The screen
//! cannot judge such a pixel, so its paths are traced, on the host with the CPU backend's
//! scene, whatever backend renders: a handful of pixels' paths cost far less than as many
//! full-image eye passes on the backend (each of which visits every slot), and every backend
//! then resets the same slots.

use backend_cpu::trace::SceneData;
use ppm_core::compile::CompiledScene;
use ppm_core::eye_path::{EyePath, EyePathSettings, Watch, trace_eye_path};
use ppm_core::rng::{PassKind, StratifiedStream, StreamKey};
use rayon::prelude::*;
use std::cell::OnceCell;

/// Eye paths per pixel the probe traces, through stratified random points of it (an
/// Owen-scrambled Sobol sequence per pixel): an object that covers an eighth of what a pixel
/// sees through a mirror would be missed by independent points with probability
/// (7/8)^32 = 1.4%, a sixteenth with 13%, and stratified points spread further. A pixel kept
/// that way holds a sliver of stale light, which its later iterations dilute.
pub const PROBE_PATHS: u32 = 32;

/// Keys the probe's random numbers apart from every iteration's.
const PROBE_SEED: u32 = 0x9b0b_e5ed;

/// A pose as the host traces it: the compiled scene, and its copy for the CPU backend's ray
/// queries made on first use, so that a move's probes share one copy of each pose.
pub(super) struct HostPose<'a> {
    /// The pose.
    pub compiled: &'a CompiledScene,
    scene: OnceCell<SceneData>,
}

impl<'a> HostPose<'a> {
    /// The pose `compiled`, not yet copied.
    pub fn new(compiled: &'a CompiledScene) -> Self {
        Self {
            compiled,
            scene: OnceCell::new(),
        }
    }

    /// The pose `compiled` with `copy`, a copy made of it earlier, if there is one: its
    /// triangles, tree and materials must be `compiled`'s; its movers' boxes are renewed.
    pub fn reusing(compiled: &'a CompiledScene, copy: Option<SceneData>) -> Self {
        let scene = OnceCell::new();
        if let Some(mut copy) = copy {
            copy.movers.clone_from(&compiled.movers);
            let _ = scene.set(copy);
        }
        Self { compiled, scene }
    }

    /// Its copy, if one was made.
    pub fn into_copy(self) -> Option<SceneData> {
        self.scene.into_inner()
    }

    /// Its scene for ray queries, copied on the first call.
    pub fn scene(&self) -> &SceneData {
        self.scene.get_or_init(|| SceneData::new(self.compiled))
    }

    /// The pose as threads share it, copied if it is not yet.
    pub fn traced(&self) -> Traced<'_> {
        (self.scene(), self.compiled)
    }
}

/// A pose copied for ray queries, and as compiled.
pub(super) type Traced<'a> = (&'a SceneData, &'a CompiledScene);

/// How the probe's paths are traced: the render's seed, depth and ray offset, and whether
/// they take the light samples the eye pass takes at glossy bounces (for their direct light).
#[derive(Clone, Copy, PartialEq)]
pub(super) struct ProbeSettings {
    pub seed: u32,
    pub max_depth: u32,
    pub ray_epsilon: f32,
    pub sample_lights: bool,
}

/// Per pixel of `pixels`, whether one of [`PROBE_PATHS`] eye paths through random points of
/// it, traced in `pose`, meets one of the object `groups` (bits of
/// [`ppm_core::compile::object_group`]), at any surface up to and including the first
/// non-specular one.
pub(super) fn paths_meet(
    pose: &HostPose,
    pixels: &[u32],
    groups: u32,
    settings: &ProbeSettings,
) -> Vec<bool> {
    let (scene, pose) = (pose.scene(), pose.compiled);
    pixels
        .par_iter()
        .map(|&pixel| {
            let points = StratifiedStream::new(settings.seed ^ PROBE_SEED, PassKind::Eye, pixel);
            (0..PROBE_PATHS).any(|path| {
                let (jx, jy) = points.pair(0, path);
                meets(scene, pose, pixel, (path, jx, jy), groups, settings)
            })
        })
        .collect()
}

/// Whether path `path` through point `(jx, jy)` of pixel `pixel` meets `groups`.
fn meets(
    scene: &SceneData,
    pose: &CompiledScene,
    pixel: u32,
    (path, jx, jy): (u32, f32, f32),
    groups: u32,
    settings: &ProbeSettings,
) -> bool {
    let key = StreamKey {
        seed: settings.seed ^ PROBE_SEED,
        kind: PassKind::Eye,
        pass_index: path,
        path: pixel,
    };
    let watch = Watch { groups, boxes: &[] };
    eye_path(scene, pose, pixel, (jx, jy), &key, &watch, settings).watched
}

/// The eye path through point `jitter` of `pixel` in `pose` (`scene`), keyed by `key`,
/// watching `watch` ([`trace_eye_path`]).
pub(super) fn eye_path(
    scene: &SceneData,
    pose: &CompiledScene,
    pixel: u32,
    jitter: (f32, f32),
    key: &StreamKey,
    watch: &Watch,
    settings: &ProbeSettings,
) -> EyePath {
    let path_settings = EyePathSettings {
        max_depth: settings.max_depth,
        ray_epsilon: settings.ray_epsilon,
        sample_lights: settings.sample_lights,
    };
    trace_eye_path(
        scene,
        &pose.camera,
        (pixel, jitter),
        key,
        &path_settings,
        watch,
    )
}
