//! An eye path (docs/algorithm.md 1.1): from the eye through a point of a pixel, through
//! mirrors, glass and glossy bounces, to its visible point, the first surface that holds one
//! ([`bsdf::visible_point_weight`]). At each glossy bounce it may also take a light sample,
//! weighed by the power heuristic against its own bounce, which in turn weighs the emission it
//! meets next (docs/algorithm.md 1.2): what those find rides beside the slot
//! ([`ChainLight`]) to the direct-light pass.
//!
//! One path, one function, for every caller: a backend's eye pass ([`slot_eye_path`], the twin
//! of eye_pass.wgsl), and a local move's probes and paired direct-light samples
//! ([`trace_eye_path`] with a [`Watch`]), all keyed by [`StreamKey::eye_lobe`],
//! [`StreamKey::eye_bounce`] and [`StreamKey::eye_light`].

use crate::bsdf::{self, BsdfSample, Transport};
use crate::compile::camera_ray;
use crate::geometry::{Frame, segment_meets_box};
use crate::layout::{
    ChainLight, EyePassParams, GpuCamera, GpuMaterial, HitPoint, NO_MATERIAL, SlotBounds,
    eye_flags, hit_flags,
};
use crate::reach::Aabb;
use crate::rng::{PassKind, StreamKey, stratified_pair};
use crate::sampling::{light_pdf, power_heuristic, sample_cdf, uniform_triangle};
use crate::trace::{Hit, PoseQueries};
use glam::Vec3;

/// How an eye path is traced: its bounces, its rays' offset from the surfaces they leave, and
/// whether it takes a light sample at each glossy bounce.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePathSettings {
    /// Bounces after which the path stops without a visible point.
    pub max_depth: u32,
    /// Offset along the normal of every ray's origin.
    pub ray_epsilon: f32,
    /// Take a light sample at each glossy bounce ([`eye_flags::SAMPLE_LIGHTS`]).
    pub sample_lights: bool,
}

/// What a path traced for a local move watches for: surfaces of some object groups (bits of
/// [`crate::compile::object_group`]), at the first of which it stops, and boxes whose
/// crossing by one of its segments it notes. The eye pass watches nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Watch<'a> {
    /// The groups at whose surfaces the path stops.
    pub groups: u32,
    /// The boxes it notes crossing.
    pub boxes: &'a [Aabb],
}

impl Watch<'_> {
    /// Whether the segment from `origin` along the unit `dir` for `t_max` crosses a box.
    pub fn crossed(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.boxes
            .iter()
            .any(|b| segment_meets_box(origin, dir, t_max, b.lo, b.hi))
    }
}

/// Where an eye path stopped on a surface that holds a visible point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visible {
    /// Its position.
    pub position: Vec3,
    /// The surface's normal on the path's side.
    pub normal: Vec3,
    /// Its material's index.
    pub material: u32,
    /// The object it belongs to.
    pub object: u32,
    /// The path's throughput there, the texture's factor and a coat's transmittance towards
    /// the eye included.
    pub throughput: Vec3,
    /// The path met the surface on the side its normal points to.
    pub front: bool,
}

impl Visible {
    /// The slot of `pixel` this visible point fills: position, facing normal, material,
    /// throughput and the `VALID`, `FRONT` and object bits, no statistics.
    pub fn hit_point(&self, pixel: u32) -> HitPoint {
        HitPoint {
            position: self.position.into(),
            normal: self.normal.into(),
            material: self.material,
            throughput: self.throughput.into(),
            flags: self.flags(),
            ..HitPoint::empty(pixel)
        }
    }

    /// The flags a slot holding it carries: `VALID`, `FRONT` where it is, and its object.
    pub fn flags(&self) -> u32 {
        hit_flags::VALID
            | if self.front { hit_flags::FRONT } else { 0 }
            | (self.object << hit_flags::OBJECT_SHIFT)
    }
}

/// One eye path, traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePath {
    /// Its visible point, if it reached one (before a watched group).
    pub visible: Option<Visible>,
    /// What its glossy bounces found ([`ChainLight::NONE`] where it took no light samples).
    pub chain: ChainLight,
    /// The object groups of every surface it met, its visible point's included.
    pub met: u32,
    /// It stopped on a surface of a watched group.
    pub watched: bool,
    /// It met a surface that continues paths (a mirror, glass, a glossy surface) on its way,
    /// or ended on one.
    pub chained: bool,
    /// One of its segments, up to where it ended (without end where it escaped), crossed a
    /// watched box.
    pub crossed: bool,
    /// How far its first segment went before a surface; infinite where it left the scene.
    pub first_t: f32,
    /// The box of its vertices after the eye ([`SlotBounds::NOTHING`] where it met nothing).
    pub vertices: SlotBounds,
    /// Rays traced: its segments, and the shadow rays of its light samples.
    pub rays: u64,
}

/// The first segment of an eye path through point `(jx, jy)` of `pixel`: the eye, and the unit
/// direction to that point.
pub fn camera_segment(camera: &GpuCamera, pixel: u32, (jx, jy): (f32, f32)) -> (Vec3, Vec3) {
    let px = (pixel % camera.width) as f32 + jx;
    let py = (pixel / camera.width) as f32 + jy;
    (Vec3::from(camera.eye), camera_ray(camera, px, py))
}

/// Traces the eye path through point `jitter` of `pixel` in `pose`, its lobes and glossy
/// bounces drawn from `key`, to its visible point; it stops instead at the first surface of
/// one of `watch`'s groups.
pub fn trace_eye_path<P: PoseQueries>(
    pose: &P,
    camera: &GpuCamera,
    (pixel, jitter): (u32, (f32, f32)),
    key: &StreamKey,
    settings: &EyePathSettings,
    watch: &Watch,
) -> EyePath {
    let (mut origin, mut dir) = camera_segment(camera, pixel, jitter);
    let mut throughput = Vec3::ONE;
    let lights = settings
        .sample_lights
        .then_some((*key, settings.ray_epsilon));
    let mut chain = ChainTracker::new(lights);
    let mut path = EyePath {
        visible: None,
        chain: ChainLight::NONE,
        met: 0,
        watched: false,
        chained: false,
        crossed: false,
        first_t: f32::INFINITY,
        vertices: SlotBounds::NOTHING,
        rays: 0,
    };
    // `segments` traced; `chained`: it met a surface that continues paths.
    let end = |mut path: EyePath,
               chain: &ChainTracker,
               (segments, chained): (u32, bool),
               stop: Option<(&Hit, Vec3)>| {
        path.chained = chained;
        path.rays = u64::from(segments) + chain.rays();
        path.chain = chain.finish(pose, stop);
        path
    };
    for depth in 0..=settings.max_depth {
        let Some(hit) = pose.closest_hit(origin, dir, f32::INFINITY) else {
            path.crossed |= watch.crossed(origin, dir, f32::INFINITY);
            return end(path, &chain, (depth + 1, depth > 0), None);
        };
        if depth == 0 {
            path.first_t = hit.t;
        }
        path.crossed |= watch.crossed(origin, dir, hit.t);
        let tri = &pose.triangles()[hit.triangle as usize];
        path.met |= tri.group;
        if tri.group & watch.groups != 0 {
            path.watched = true;
            return end(path, &chain, (depth + 1, depth > 0), None);
        }
        let position = origin + dir * hit.t;
        path.vertices = SlotBounds::new(
            Vec3::from(path.vertices.min).min(position),
            Vec3::from(path.vertices.max).max(position),
        );
        let (material, texture) = pose.surface(&hit, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let front = dir.dot(normal) < 0.0;
        let facing = if front { normal } else { -normal };
        if let Some(weight) =
            bsdf::visible_point_weight(material, facing, -dir, key.eye_lobe(depth))
        {
            path.visible = Some(Visible {
                position,
                normal: facing,
                material: tri.material,
                object: tri.object,
                throughput: throughput * texture * weight,
                front,
            });
            return end(path, &chain, (depth + 1, depth > 0), Some((&hit, dir)));
        }
        let at = GlossyVertex {
            position,
            frame: pose.frame(&hit, material, facing),
            front,
            wo: -dir,
            depth,
        };
        let bounce = chain.bounce(pose, material, &at, throughput, key.eye_bounce(depth));
        if bounce.weight == Vec3::ZERO {
            // A glossy direction below the surface: the path ends without a visible point.
            return end(path, &chain, (depth + 1, true), None);
        }
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = if bounce.transmitted { -facing } else { facing };
        origin = position + side * settings.ray_epsilon;
    }
    end(path, &chain, (settings.max_depth + 1, true), None)
}

/// What a slot's eye pass did: rays traced, what its glossy bounces found (`None` where it
/// rested), and the box of its path's vertices.
#[derive(Clone, Copy, Debug)]
pub struct SlotEyePath {
    /// Rays traced.
    pub rays: u64,
    /// What the path's glossy bounces found; `None` for a slot that rests.
    pub chain: Option<ChainLight>,
    /// The box of the path's vertices after the eye.
    pub vertices: SlotBounds,
}

/// The eye pass of one slot (`width * height * spp` slots, slot = pixel * spp + sample): traces
/// its eye path and writes its visible point into `hp`, starting the slot fresh or keeping its
/// statistics as `params.flags` says; with [`eye_flags::FOCUS`], a slot at `rest_at`
/// iterations or more rests instead ([`hit_flags::RESTING`]). The twin of eye_pass.wgsl.
pub fn slot_eye_path<P: PoseQueries>(
    params: &EyePassParams,
    camera: &GpuCamera,
    pose: &P,
    slot: u32,
    hp: &mut HitPoint,
) -> SlotEyePath {
    let pixel = slot / params.spp;
    let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
    if keep && params.flags & eye_flags::FOCUS != 0 && hp.iterations >= params.rest_at {
        hp.flags |= hit_flags::RESTING;
        return SlotEyePath {
            rays: 0,
            chain: None,
            vertices: SlotBounds::NOTHING,
        };
    }
    // Kept slots continue their own sequence (direct_light::sequence_start); a re-trace
    // repeats the stratum it last used.
    let start = if keep {
        hp.iterations
    } else if params.flags & eye_flags::RETRACE != 0 {
        hp.iterations.saturating_sub(1)
    } else {
        params.iteration
    };
    *hp = if keep {
        HitPoint {
            position: [0.0; 3],
            normal: [0.0; 3],
            material: NO_MATERIAL,
            throughput: [0.0; 3],
            flags: hp.flags & hit_flags::KEPT,
            ..*hp
        }
    } else {
        HitPoint {
            r2: params.r2_initial,
            ..HitPoint::empty(pixel)
        }
    };
    let key = StreamKey {
        seed: params.seed,
        kind: PassKind::Eye,
        pass_index: params.iteration,
        path: slot,
    };
    let jitter = if params.spp == 1 && params.flags & eye_flags::JITTER == 0 {
        (0.5, 0.5)
    } else {
        let sample = start * params.spp + slot % params.spp;
        stratified_pair(params.seed, PassKind::Eye, pixel, 0, sample)
    };
    let settings = EyePathSettings {
        max_depth: params.max_depth,
        ray_epsilon: params.ray_epsilon,
        sample_lights: params.flags & eye_flags::SAMPLE_LIGHTS != 0,
    };
    let path = trace_eye_path(
        pose,
        camera,
        (pixel, jitter),
        &key,
        &settings,
        &Watch::default(),
    );
    hp.eye_met |= path.met;
    if path.chained {
        hp.flags |= hit_flags::EYE_CHAINED;
    }
    if let Some(v) = path.visible {
        hp.position = v.position.into();
        hp.normal = v.normal.into();
        hp.material = v.material;
        hp.throughput = v.throughput.into();
        hp.flags |= v.flags();
    }
    SlotEyePath {
        rays: path.rays,
        chain: Some(path.chain),
        vertices: path.vertices,
    }
}

/// A slot's bounds after an eye pass that records them ([`eye_flags::RECORD_BOUNDS`]): started
/// over where its statistics start (no direct sample yet: a fresh or reset slot), left alone
/// where it rested, else grown by `path`, the box of its path's vertices
/// ([`SlotEyePath::vertices`]). A local move looks there for what the slot may have seen.
pub fn extended_bounds(bounds: SlotBounds, hp: &HitPoint, path: SlotBounds) -> SlotBounds {
    if hp.flags & hit_flags::RESTING != 0 {
        return bounds;
    }
    let start = if hp.iterations == 0 {
        SlotBounds::NOTHING
    } else {
        bounds
    };
    SlotBounds::new(
        Vec3::from(start.min).min(path.min.into()),
        Vec3::from(start.max).max(path.max.into()),
    )
}

/// A glossy bounce of an eye path: where, the surface's frame on the path's side and whether
/// that is the outside, towards where the path came from, and its depth (which keys the light
/// sample's numbers).
#[derive(Clone, Copy)]
pub struct GlossyVertex {
    /// The bounce's position.
    pub position: Vec3,
    /// The lobe's frame, its normal on the side the path arrived from.
    pub frame: Frame,
    /// The path arrived from the surface's front (outside, for glass).
    pub front: bool,
    /// The unit direction back along the path.
    pub wo: Vec3,
    /// The bounce's depth on the path.
    pub depth: u32,
}

/// The light sample at the glossy bounce `at`: `f cos Le / p_light` weighed against the
/// bounce's density, before the path's throughput; `None` when no shadow ray was traced.
fn glossy_vertex_light<P: PoseQueries>(
    pose: &P,
    material: &GpuMaterial,
    at: &GlossyVertex,
    key: &StreamKey,
    ray_epsilon: f32,
) -> Option<Vec3> {
    let GlossyVertex {
        position,
        frame,
        front,
        wo,
        depth,
    } = *at;
    let facing = frame.normal;
    let lights = pose.lights();
    if lights.is_empty() {
        return None;
    }
    let (choice, (u1, u2)) = key.eye_light(depth);
    let light = &lights[sample_cdf(|i| lights[i].cdf, lights.len(), choice)];
    let (b1, b2) = uniform_triangle(u1, u2);
    let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
    // The shadow ray leaves from the light's side (the far one through rough glass).
    let side = if facing.dot(y - position) >= 0.0 {
        facing
    } else {
        -facing
    };
    let origin = position + side * ray_epsilon;
    let to_light = y - origin;
    let dist2 = to_light.length_squared();
    if dist2 <= 0.0 {
        return None;
    }
    let dist = dist2.sqrt();
    let wi = to_light / dist;
    let cos_l = -Vec3::from(light.normal).dot(wi);
    let (f_cos, pb) = bsdf::glossy_lobe(material, &frame, front, wo, wi);
    if cos_l <= 0.0 || f_cos == Vec3::ZERO {
        return None;
    }
    if pose.occluded(origin, wi, dist - 2.0 * ray_epsilon) {
        return Some(Vec3::ZERO);
    }
    let le = Vec3::from(pose.materials()[light.material as usize].emission);
    let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
    Some(f_cos * le * (power_heuristic(pl, pb) / pl))
}

/// The weight of the emission an eye path meets at `hit` (travelling `dir`) after a glossy
/// bounce that drew `dir` with density `bounce_pdf`, against the light sample taken there:
/// one where `hit` is not on a light's front or no light sample was taken (`bounce_pdf`
/// `None`).
fn emission_weight<P: PoseQueries>(pose: &P, hit: &Hit, dir: Vec3, bounce_pdf: Option<f32>) -> f32 {
    let tri = &pose.triangles()[hit.triangle as usize];
    let cos_l = -Vec3::from(tri.normal).dot(dir);
    match bounce_pdf {
        Some(pb) if tri.light != NO_MATERIAL && cos_l > 0.0 => {
            let light = &pose.lights()[tri.light as usize];
            power_heuristic(pb, light_pdf(light.pdf, light.area, hit.t * hit.t, cos_l))
        }
        _ => 1.0,
    }
}

/// Follows one eye path's glossy bounces: the light samples taken at them, and the density
/// of the last bounce, which weighs the emission met next.
#[derive(Clone, Copy, Debug)]
pub struct ChainTracker {
    /// The path's key and ray offset, when it samples the lights at its glossy bounces.
    lights: Option<(StreamKey, f32)>,
    radiance: Vec3,
    bounce_pdf: Option<f32>,
    rays: u64,
}

impl ChainTracker {
    /// A path's tracker; `lights`: its key and ray offset when it samples the lights.
    pub fn new(lights: Option<(StreamKey, f32)>) -> Self {
        Self {
            lights,
            radiance: Vec3::ZERO,
            bounce_pdf: None,
            rays: 0,
        }
    }

    /// The path's bounce through `material` at `at` with `throughput` so far, drawn from
    /// `u` ([`bsdf::sample`]). Where the material has a glossy lobe and the path samples the
    /// lights, it takes the light sample first, then notes the drawn direction's density
    /// within the lobe.
    pub fn bounce<P: PoseQueries>(
        &mut self,
        pose: &P,
        material: &GpuMaterial,
        at: &GlossyVertex,
        throughput: Vec3,
        u: (f32, (f32, f32)),
    ) -> BsdfSample {
        self.bounce_pdf = None;
        let sampled = self.lights.filter(|_| bsdf::chain_samples_lights(material));
        if let Some((key, ray_epsilon)) = sampled
            && let Some(light) = glossy_vertex_light(pose, material, at, &key, ray_epsilon)
        {
            self.radiance += throughput * light;
            self.rays += 1;
        }
        let bounce = bsdf::sample(
            material,
            -at.wo,
            &at.frame,
            at.front,
            u,
            Transport::Radiance,
        );
        if sampled.is_some() && bounce.weight != Vec3::ZERO {
            self.bounce_pdf =
                Some(bsdf::glossy_lobe(material, &at.frame, at.front, at.wo, bounce.dir).1);
        }
        bounce
    }

    /// The path's light samples, and the weight of the emission at `hit`, where it stops
    /// after travelling `dir` (`None`: it left the scene or ended without a visible point).
    pub fn finish<P: PoseQueries>(&self, pose: &P, stop: Option<(&Hit, Vec3)>) -> ChainLight {
        ChainLight {
            radiance: self.radiance.into(),
            emission_weight: stop.map_or(1.0, |(hit, dir)| {
                emission_weight(pose, hit, dir, self.bounce_pdf)
            }),
        }
    }

    /// Shadow rays traced for the light samples.
    pub fn rays(&self) -> u64 {
        self.rays
    }
}
