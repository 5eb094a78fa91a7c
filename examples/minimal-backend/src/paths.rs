//! One path of each kind, keyed exactly as the contract keys it (`ppm_core::rng`): an eye path
//! to its visible point, a slot's direct light, a photon's deposits. The passes in `lib.rs` run
//! them slot by slot and photon by photon.

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray, RayHit};
use ppm_core::bsdf::{self, Transport};
use ppm_core::compile::{CompiledScene, camera_ray};
use ppm_core::emission::{EMISSION_DIMS, Emission};
use ppm_core::geometry::{Frame, intersect_triangle, oct_encode};
use ppm_core::layout::{
    ChainLight, DirectLightParams, EyePassParams, GpuCamera, GpuLight, GpuMaterial, GpuTriangle,
    HitPoint, NO_MATERIAL, Photon, PhotonPassParams, direct_accumulate, eye_flags, first_hit,
    hit_flags,
};
use ppm_core::rng::{PassKind, StratifiedStream, StreamKey, stratified_pair};
use ppm_core::sampling::{light_pdf, power_heuristic, sample_cdf, uniform_triangle};
use ppm_core::textures::SurfaceTextures;

/// A direct-light sample's stratified pairs: the point on the light, the cosine direction,
/// and (first number) which light.
const PAIR_LIGHT_POINT: u32 = 0;
const PAIR_DIRECTION: u32 = 1;
const PAIR_LIGHT_CHOICE: u32 = 2;
/// A photon's dimensions: the emission's, then three per bounce (roulette, direction).
const DIMS_PER_BOUNCE: u32 = 3;

/// The compiled scene's buffers the paths read.
pub struct Scene {
    /// The camera.
    pub camera: GpuCamera,
    /// Triangles, in the BVH's leaf order.
    pub triangles: Vec<GpuTriangle>,
    /// obvhs's BVH over them.
    pub bvh: Bvh2,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emitting triangles, with the distribution that picks one by power.
    pub lights: Vec<GpuLight>,
    /// Texture coordinates and images.
    pub textures: SurfaceTextures,
}

impl Scene {
    /// The buffers of `scene`, copied.
    pub fn new(scene: &CompiledScene) -> Self {
        Self {
            camera: scene.camera,
            triangles: Vec::clone(&scene.triangles),
            bvh: Bvh2::clone(&scene.bvh),
            materials: scene.materials.clone(),
            lights: scene.lights.clone(),
            textures: scene.textures.clone(),
        }
    }

    /// Triangle `index`'s material at `position`, its colour scaled by its texture there,
    /// and that factor.
    fn surface(&self, index: u32, position: Vec3) -> (GpuMaterial, Vec3) {
        let tri = &self.triangles[index as usize];
        let material = &self.materials[tri.material as usize];
        self.textures.shaded(material, index, tri, position)
    }

    /// The frame of `material`'s lobe on triangle `index`, seen from the side of `facing`:
    /// an anisotropic lobe follows the surface's coordinates.
    fn frame(&self, index: u32, material: &GpuMaterial, facing: Vec3) -> Frame {
        let tri = &self.triangles[index as usize];
        self.textures.frame(material, index, tri, facing)
    }
}

/// The nearest triangle a ray meets before `tmax`, and where.
fn closest_hit(scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(f32, u32)> {
    let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
    let mut hit = RayHit::none();
    let found = scene.bvh.ray_traverse(ray, &mut hit, |r, id| {
        intersect_triangle(origin, dir, &scene.triangles[id], r.tmin, r.tmax)
    });
    found.then_some((hit.t, hit.primitive_id))
}

/// Whether anything lies on the segment from `origin` along `dir` to `tmax`.
fn occluded(scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
    closest_hit(scene, origin, dir, tmax).is_some()
}

/// Traces slot `slot`'s eye path (docs/algorithm.md 1.1) and writes its visible point into
/// `hp`: fresh statistics, or with [`eye_flags::KEEP_STATISTICS`] the slot's own, which then
/// continues its own sample sequence. Returns the rays traced and what the path's glossy
/// bounces found, for the direct-light pass.
pub fn eye_path(
    params: &EyePassParams,
    scene: &Scene,
    slot: u32,
    hp: &mut HitPoint,
) -> (u64, ChainLight) {
    let camera = &scene.camera;
    let pixel = slot / params.spp;
    let keep = params.flags & eye_flags::KEEP_STATISTICS != 0;
    let start = if keep {
        hp.iterations
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
    // The point in the pixel: its centre for one fixed sample, else the slot's stratified
    // sequence over all its samples so far.
    let (jx, jy) = if params.spp == 1 && params.flags & eye_flags::JITTER == 0 {
        (0.5, 0.5)
    } else {
        let sample = start * params.spp + slot % params.spp;
        stratified_pair(params.seed, PassKind::Eye, pixel, 0, sample)
    };
    let x = (pixel % camera.width) as f32 + jx;
    let y = (pixel / camera.width) as f32 + jy;
    let mut dir = camera_ray(camera, x, y);
    let mut origin = Vec3::from(camera.eye);
    let mut throughput = Vec3::ONE;
    // At a glossy bounce, with explicit direct light: a light sample, and the bounce's
    // density, which weighs the emission the path meets next against it.
    let sample_lights = params.flags & eye_flags::SAMPLE_LIGHTS != 0;
    let mut chain = ChainLight::NONE;
    let mut shadow_rays = 0;
    let mut bounce_pdf = None;
    for depth in 0..=params.max_depth {
        let Some((t, index)) = closest_hit(scene, origin, dir, f32::INFINITY) else {
            return (u64::from(depth) + 1 + shadow_rays, chain);
        };
        let tri = &scene.triangles[index as usize];
        hp.eye_met |= tri.group;
        let position = origin + dir * t;
        // A textured colour: scaled here, and carried by the slot's throughput where the
        // path stops (ppm_core::textures).
        let (material, texture) = scene.surface(index, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let front = dir.dot(normal) < 0.0;
        let facing = if front { normal } else { -normal };
        // A diffuse surface holds the visible point; a coated one when the path takes its
        // base, whose transmittance then rides in the throughput too (ppm_core::bsdf).
        let u_lobe = key.eye_lobe(depth);
        if let Some(weight) = bsdf::visible_point_weight(material, facing, -dir, u_lobe) {
            hp.position = position.into();
            hp.normal = facing.into();
            hp.material = tri.material;
            hp.throughput = (throughput * texture * weight).into();
            hp.flags |= hit_flags::VALID
                | if front { hit_flags::FRONT } else { 0 }
                | (tri.object << hit_flags::OBJECT_SHIFT);
            let cos_l = -normal.dot(dir);
            if let Some(pb) = bounce_pdf.filter(|_| tri.light != NO_MATERIAL && cos_l > 0.0) {
                let light = &scene.lights[tri.light as usize];
                let pl = light_pdf(light.pdf, light.area, t * t, cos_l);
                chain.emission_weight = power_heuristic(pb, pl);
            }
            return (u64::from(depth) + 1 + shadow_rays, chain);
        }
        // Mirror, glass, conductor or a coat's reflection: follow the bounce.
        hp.flags |= hit_flags::EYE_CHAINED;
        let glossy = sample_lights && bsdf::chain_samples_lights(material);
        let frame = scene.frame(index, material, facing);
        if glossy && !scene.lights.is_empty() {
            let (light, traced) = glossy_light(
                params,
                scene,
                material,
                (position, &frame, front),
                -dir,
                (&key, depth),
            );
            chain.radiance = (Vec3::from(chain.radiance) + throughput * light).into();
            shadow_rays += u64::from(traced);
        }
        let u = key.eye_bounce(depth);
        let bounce = bsdf::sample(material, dir, &frame, front, u, Transport::Radiance);
        if bounce.weight == Vec3::ZERO {
            return (u64::from(depth) + 1 + shadow_rays, chain);
        }
        bounce_pdf = glossy.then(|| bsdf::glossy_lobe(material, &frame, front, -dir, bounce.dir).1);
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = if bounce.transmitted { -facing } else { facing };
        origin = position + side * params.ray_epsilon;
    }
    (u64::from(params.max_depth) + 1 + shadow_rays, chain)
}

/// The light sample at a glossy bounce at `depth` (`position`, the lobe's frame on the
/// path's side and whether that is the outside; `wo` the direction back along the path): a light
/// by power and a point on it by area from the eye stream's light dimensions
/// ([`StreamKey::eye_light`]), its `f cos Le / p_light` from the lobe the path continues by,
/// weighed against that lobe's density. Returns it and whether a shadow ray was traced.
fn glossy_light(
    params: &EyePassParams,
    scene: &Scene,
    material: &GpuMaterial,
    (position, frame, front): (Vec3, &Frame, bool),
    wo: Vec3,
    (key, depth): (&StreamKey, u32),
) -> (Vec3, bool) {
    let facing = frame.normal;
    let (choice, (u1, u2)) = key.eye_light(depth);
    let light = &scene.lights[sample_cdf(|i| scene.lights[i].cdf, scene.lights.len(), choice)];
    let (b1, b2) = uniform_triangle(u1, u2);
    let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
    // The shadow ray leaves from the light's side (the far one through rough glass).
    let side = match facing.dot(y - position) >= 0.0 {
        true => facing,
        false => -facing,
    };
    let origin = position + side * params.ray_epsilon;
    let to_light = y - origin;
    let dist2 = to_light.length_squared();
    if dist2 <= 0.0 {
        return (Vec3::ZERO, false);
    }
    let dist = dist2.sqrt();
    let wi = to_light / dist;
    let cos_l = -Vec3::from(light.normal).dot(wi);
    let (f_cos, pb) = bsdf::glossy_lobe(material, frame, front, wo, wi);
    if cos_l <= 0.0 || f_cos == Vec3::ZERO {
        return (Vec3::ZERO, false);
    }
    if occluded(scene, origin, wi, dist - 2.0 * params.ray_epsilon) {
        return (Vec3::ZERO, true);
    }
    let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
    let le = Vec3::from(scene.materials[light.material as usize].emission);
    (f_cos * le * (power_heuristic(pl, pb) / pl), true)
}

/// An eye path's direct radiance towards the eye, throughput included (docs/algorithm.md
/// 1.2): what its glossy bounces found (`chain`), and at its visible point, if it has one, the
/// emission it shows (weighed by `chain`'s weight) plus per sample a shadow ray to a point on a
/// light and a ray drawn from the BSDF that may meet one, weighted by the power heuristic.
/// Returns it and the rays traced.
pub fn direct_light(
    params: &DirectLightParams,
    scene: &Scene,
    hp: &HitPoint,
    chain: &ChainLight,
    slot: u32,
) -> ([f32; 3], u64) {
    let found = Vec3::from(chain.radiance);
    if !hp.is_valid() {
        return (found.into(), 0);
    }
    let material = &scene.materials[hp.material as usize];
    let mut radiance = match hp.flags & hit_flags::FRONT != 0 {
        true => Vec3::from(material.emission) * chain.emission_weight,
        false => Vec3::ZERO,
    };
    let mut rays = 0;
    if params.samples > 0
        && bsdf::visible_point_f(material).max_element() > 0.0
        && !scene.lights.is_empty()
    {
        radiance += reflected(params, scene, material, hp, slot);
        rays = u64::from(params.samples) * 2;
    }
    ((Vec3::from(hp.throughput) * radiance + found).into(), rays)
}

/// Light from the lights reflected at a visible point, `params.samples` samples of both
/// strategies. A slot that adds to its sum continues its own sequence from its iteration
/// count, so its samples over all iterations are stratified together.
fn reflected(
    params: &DirectLightParams,
    scene: &Scene,
    material: &GpuMaterial,
    hp: &HitPoint,
    slot: u32,
) -> Vec3 {
    let x = Vec3::from(hp.position);
    let n = Vec3::from(hp.normal);
    let f = bsdf::visible_point_f(material);
    let origin = x + n * params.ray_epsilon;
    let first = match params.accumulate == direct_accumulate::ADD {
        true => hp.iterations,
        false => params.iteration,
    };
    let stream = StratifiedStream::new(params.seed, PassKind::DirectLight, slot);
    let emission = |light: u32| Vec3::from(scene.materials[light as usize].emission);
    let mut sum = Vec3::ZERO;
    for s in 0..params.samples {
        let index = first * params.samples + s;
        // Light sampling: a light by power, a point on it by area.
        let (choice, _) = stream.pair(PAIR_LIGHT_CHOICE, index);
        let light = &scene.lights[sample_cdf(|i| scene.lights[i].cdf, scene.lights.len(), choice)];
        let (u1, u2) = stream.pair(PAIR_LIGHT_POINT, index);
        let (b1, b2) = uniform_triangle(u1, u2);
        let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
        let to_light = y - origin;
        let dist2 = to_light.length_squared();
        if dist2 > 0.0 {
            let dist = dist2.sqrt();
            let w = to_light / dist;
            let (cos_x, cos_l) = (n.dot(w), -Vec3::from(light.normal).dot(w));
            if cos_x > 0.0
                && cos_l > 0.0
                && !occluded(scene, origin, w, dist - 2.0 * params.ray_epsilon)
            {
                let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
                let pb = bsdf::visible_point_pdf(n, w);
                // A coat lets through a share of the light (one on a bare surface).
                let cos_through = cos_x * bsdf::arrival(material, cos_x);
                sum += f * emission(light.material) * (cos_through / pl * power_heuristic(pl, pb));
            }
        }
        // BSDF sampling: light only where the ray meets an emitter's front first.
        let scattered = bsdf::sample_visible(material, n, stream.pair(PAIR_DIRECTION, index));
        let w = scattered.dir;
        if let Some((t, index)) = closest_hit(scene, origin, w, f32::INFINITY) {
            let tri = &scene.triangles[index as usize];
            let cos_l = -Vec3::from(tri.normal).dot(w);
            if tri.light != NO_MATERIAL && cos_l > 0.0 {
                let light = &scene.lights[tri.light as usize];
                let pl = light_pdf(light.pdf, light.area, t * t, cos_l);
                sum += scattered.weight
                    * emission(light.material)
                    * power_heuristic(scattered.pdf, pl);
            }
        }
    }
    sum / params.samples as f32
}

/// Traces one photon from `emission` (docs/algorithm.md 1.3), appending a deposit at each
/// diffuse surface it meets (but the first when shadow rays count direct light), with
/// Russian roulette at each; returns the ray segments traced.
pub fn photon_path(
    params: &PhotonPassParams,
    scene: &Scene,
    key: &StreamKey,
    emission: &Emission,
    out: &mut Vec<Photon>,
) -> u64 {
    let mut dir = emission.direction;
    let mut origin = emission.origin + emission.normal * params.ray_epsilon;
    let mut power = emission.power * params.power_scale;
    let mut rays = 0;
    for bounce in 0..params.max_depth {
        rays += 1;
        let Some((t, index)) = closest_hit(scene, origin, dir, f32::INFINITY) else {
            break;
        };
        let tri = &scene.triangles[index as usize];
        let position = origin + dir * t;
        let (material, _) = scene.surface(index, position);
        let material = &material;
        let normal = Vec3::from(tri.normal);
        let facing = if dir.dot(normal) < 0.0 {
            normal
        } else {
            -normal
        };
        let d = EMISSION_DIMS + bounce * DIMS_PER_BOUNCE;
        if bsdf::holds_visible_points(material)
            && (bounce > 0 || params.first_hit == first_hit::DEPOSIT)
        {
            // What reaches the base of a coated surface.
            let arrived = bsdf::arrival(material, -dir.dot(facing));
            out.push(Photon {
                position: position.into(),
                path: key.path,
                power: (power * arrived).into(),
                normal_oct: oct_encode(facing),
            });
        }
        let u = (key.uniform(d), (key.uniform(d + 1), key.uniform(d + 2)));
        let frame = scene.frame(index, material, facing);
        let Some(b) = bsdf::photon_bounce(material, dir, &frame, facing == normal, u) else {
            break;
        };
        power *= b.weight;
        dir = b.dir;
        let side = if b.transmitted { -facing } else { facing };
        origin = position + side * params.ray_epsilon;
    }
    rays
}
