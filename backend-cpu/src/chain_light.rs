//! Direct light at an eye path's glossy bounces (docs/algorithm.md 1.2): where the path
//! continues off a rough metal, a rough coat's reflection or rough glass, it also takes a
//! light sample, weighed by the power heuristic against its own bounce, which in turn weighs
//! the emission it meets next. A small light in a glossy surface is then found by both
//! strategies, not by the bounce alone. What the samples add rides apart from the slot
//! ([`ChainLight`]) to the direct-light pass, which adds it to the slot's direct sum.

use crate::trace::{Hit, SceneData};
use glam::Vec3;
use ppm_core::bsdf::{self, BsdfSample, Transport};
use ppm_core::geometry::Frame;
use ppm_core::layout::{ChainLight, GpuMaterial, NO_MATERIAL};
use ppm_core::rng::StreamKey;
use ppm_core::sampling::{light_pdf, power_heuristic, sample_cdf, uniform_triangle};

/// A glossy bounce of an eye path: where, the surface's frame on the path's side and whether
/// that is the outside, towards where the path came from, and its depth (which keys the
/// light sample's numbers).
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
fn glossy_vertex_light(
    scene: &SceneData,
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
    if scene.lights.is_empty() {
        return None;
    }
    let (choice, (u1, u2)) = key.eye_light(depth);
    let light = &scene.lights[sample_cdf(|i| scene.lights[i].cdf, scene.lights.len(), choice)];
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
    if scene.occluded(origin, wi, dist - 2.0 * ray_epsilon) {
        return Some(Vec3::ZERO);
    }
    let le = Vec3::from(scene.materials[light.material as usize].emission);
    let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
    Some(f_cos * le * (power_heuristic(pl, pb) / pl))
}

/// The weight of the emission an eye path meets at `hit` (travelling `dir`) after a glossy
/// bounce that drew `dir` with density `bounce_pdf`, against the light sample taken there:
/// one where `hit` is not on a light's front or no light sample was taken (`bounce_pdf`
/// `None`).
fn emission_weight(scene: &SceneData, hit: &Hit, dir: Vec3, bounce_pdf: Option<f32>) -> f32 {
    let tri = &scene.triangles[hit.triangle as usize];
    let cos_l = -Vec3::from(tri.normal).dot(dir);
    match bounce_pdf {
        Some(pb) if tri.light != NO_MATERIAL && cos_l > 0.0 => {
            let light = &scene.lights[tri.light as usize];
            power_heuristic(pb, light_pdf(light.pdf, light.area, hit.t * hit.t, cos_l))
        }
        _ => 1.0,
    }
}

/// Follows one eye path's glossy bounces: the light samples taken at them, and the density
/// of the last bounce, which weighs the emission met next. The CPU eye pass and the host's
/// eye paths of local mode (`harness::driver::probe`) bounce through it alike.
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
    pub fn bounce(
        &mut self,
        scene: &SceneData,
        material: &GpuMaterial,
        at: &GlossyVertex,
        throughput: Vec3,
        u: (f32, (f32, f32)),
    ) -> BsdfSample {
        self.bounce_pdf = None;
        let sampled = self.lights.filter(|_| bsdf::chain_samples_lights(material));
        if let Some((key, ray_epsilon)) = sampled
            && let Some(light) = glossy_vertex_light(scene, material, at, &key, ray_epsilon)
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
    pub fn finish(&self, scene: &SceneData, stop: Option<(&Hit, Vec3)>) -> ChainLight {
        ChainLight {
            radiance: self.radiance.into(),
            emission_weight: stop.map_or(1.0, |(hit, dir)| {
                emission_weight(scene, hit, dir, self.bounce_pdf)
            }),
        }
    }

    /// Shadow rays traced for the light samples.
    pub fn rays(&self) -> u64 {
        self.rays
    }
}
