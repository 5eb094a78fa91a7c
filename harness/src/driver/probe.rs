//! Local mode's probe of paths past a mirror or glass (docs/algorithm.md 3c): whether eye
//! paths through random points of a pixel meet a moved object in the new pose. The screen
//! cannot judge such a pixel, so its paths are traced, on the host with the CPU backend's
//! scene, whatever backend renders: a handful of pixels' paths cost far less than as many
//! full-image eye passes on the backend (each of which visits every slot), and every backend
//! then resets the same slots.

use backend_cpu::chain_light::{ChainTracker, GlossyVertex};
use backend_cpu::trace::SceneData;
use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::compile::{CompiledScene, camera_ray};
use ppm_core::geometry::segment_meets_box;
use ppm_core::layout::{ChainLight, HitPoint, hit_flags};
use ppm_core::reach::Aabb;
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
    eye_path(scene, pose, pixel, (jx, jy), &key, &watch, settings).met
}

/// What an eye path traced on the host watches for: surfaces of some object groups (bits of
/// [`ppm_core::compile::object_group`]), where it stops, and boxes its segments may cross.
pub(super) struct Watch<'a> {
    pub groups: u32,
    pub boxes: &'a [Aabb],
}

impl Watch<'_> {
    /// Whether the segment from `origin` along the unit `dir` for `t_max` meets a box.
    pub fn crossed(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.boxes
            .iter()
            .any(|b| segment_meets_box(origin, dir, t_max, b.lo, b.hi))
    }
}

/// One eye path traced on the host, as the eye pass traces it.
#[derive(Clone, Copy)]
pub(super) struct EyePath {
    /// Whether it met one of the groups asked about, up to and including its visible point.
    pub met: bool,
    /// Whether one of its segments, up to where it stopped (escaping: without end), crossed
    /// one of the boxes asked about.
    pub crossed: bool,
    /// Whether it bounced off a mirror, glass or glossy surface on its way.
    pub bounced: bool,
    /// How far its first segment, from the eye ([`camera_segment`]), went before a surface
    /// (infinite when it left the scene).
    pub first_t: f32,
    /// Its visible point (position, facing normal, material, throughput and `VALID` and
    /// `FRONT` flags, as the eye pass writes them), if it reached one before meeting a group.
    pub visible: Option<HitPoint>,
    /// What its glossy bounces found, as the eye pass finds it, when the settings sample
    /// lights ([`ChainLight::NONE`] otherwise).
    pub chain: ChainLight,
}

/// Dimensions `DIM_GLOSSY + 2 depth` and the next of a probe's key draw a glossy bounce
/// (dimension `depth` picks at glass).
const DIM_GLOSSY: u32 = 1 << 16;

/// Traces the eye path through point `(jx, jy)` of `pixel` in `pose` (`scene`) to its first
/// diffuse surface, glass choices and glossy bounces drawn from `key`; it stops at the first
/// surface of one of `watch`'s groups.
pub(super) fn eye_path(
    scene: &SceneData,
    pose: &CompiledScene,
    pixel: u32,
    (jx, jy): (f32, f32),
    key: &StreamKey,
    watch: &Watch,
    settings: &ProbeSettings,
) -> EyePath {
    let (mut origin, mut dir) = camera_segment(pose, pixel, (jx, jy));
    let mut throughput = Vec3::ONE;
    let lights = settings
        .sample_lights
        .then_some((*key, settings.ray_epsilon));
    let mut chain = ChainTracker::new(lights);
    let mut crossed = false;
    let mut first_t = f32::INFINITY;
    let nothing = |chain: &ChainTracker, crossed, depth, first_t| EyePath {
        met: false,
        crossed,
        bounced: depth > 0,
        first_t,
        visible: None,
        chain: chain.finish(scene, None),
    };
    for depth in 0..=settings.max_depth {
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            crossed |= watch.crossed(origin, dir, f32::INFINITY);
            return nothing(&chain, crossed, depth, first_t);
        };
        if depth == 0 {
            first_t = hit.t;
        }
        crossed |= watch.crossed(origin, dir, hit.t);
        let tri = &scene.triangles[hit.triangle as usize];
        if tri.group & watch.groups != 0 {
            return EyePath {
                met: true,
                crossed,
                bounced: depth > 0,
                first_t,
                visible: None,
                chain: ChainLight::NONE,
            };
        }
        let position = origin + dir * hit.t;
        let (material, texture) = scene.surface(&hit, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let front = dir.dot(normal) < 0.0;
        let facing = if front { normal } else { -normal };
        let u = (
            key.uniform(depth),
            (
                key.uniform(DIM_GLOSSY + 2 * depth),
                key.uniform(DIM_GLOSSY + 2 * depth + 1),
            ),
        );
        if let Some(weight) = bsdf::visible_point_weight(material, facing, -dir, u.0) {
            let front = if front { hit_flags::FRONT } else { 0 };
            return EyePath {
                met: false,
                crossed,
                bounced: depth > 0,
                first_t,
                visible: Some(HitPoint {
                    position: position.into(),
                    normal: facing.into(),
                    material: tri.material,
                    throughput: (throughput * texture * weight).into(),
                    flags: hit_flags::VALID | front,
                    ..HitPoint::empty(pixel)
                }),
                chain: chain.finish(scene, Some((&hit, dir))),
            };
        }
        let at = GlossyVertex {
            position,
            frame: scene.frame(&hit, material, facing),
            front,
            wo: -dir,
            depth,
        };
        let bounce = chain.bounce(scene, material, &at, throughput, u);
        if bounce.weight == Vec3::ZERO {
            return nothing(&chain, crossed, depth + 1, first_t);
        }
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = if bounce.transmitted { -facing } else { facing };
        origin = position + side * settings.ray_epsilon;
    }
    nothing(&chain, crossed, settings.max_depth + 1, first_t)
}

/// The first segment of an eye path through point `(jx, jy)` of `pixel`: the eye, and the
/// unit direction to that point.
pub(super) fn camera_segment(
    pose: &CompiledScene,
    pixel: u32,
    (jx, jy): (f32, f32),
) -> (Vec3, Vec3) {
    let camera = &pose.camera;
    let px = (pixel % camera.width) as f32 + jx;
    let py = (pixel / camera.width) as f32 + jy;
    (Vec3::from(camera.eye), camera_ray(camera, px, py))
}
