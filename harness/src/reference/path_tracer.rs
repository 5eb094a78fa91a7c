//! An unbiased path tracer: the ground truth the photon mapper is measured against.
//!
//! It shares with the photon passes the compiled scene, its ray queries and the materials
//! ([`ppm_core::bsdf`]: what a surface does with light is written once, and checked by
//! white-furnace tests and against other renderers rather than against a second copy); the
//! light transport is written here on its own (light sampling, multiple importance sampling,
//! Russian roulette), so a mistake in the passes' transport does not repeat here.
//! Per sample: a point uniform in the pixel's area (a box filter), then at every surface
//! with a density (`bsdf::samples_lights`, and rough glass, whose density takes the side:
//! `bsdf::rough_glass`) next-event estimation towards a point on the area lights and a
//! bounce drawn from the BSDF, the two weighted by the power heuristic; at mirrors and
//! smooth glass the BSDF's bounce alone continues the path (radiance scaled by
//! `(eta_i / eta_t)^2` through a refraction); emission reached directly or after such a
//! bounce counts whole.

use super::sampler::Sampler;
use backend_cpu::trace::SceneData;
use glam::Vec3;
use ppm_core::bsdf::{self, Transport, rough_glass};
use ppm_core::compile::camera_ray;
use ppm_core::layout::{GpuCamera, GpuLight, NO_MATERIAL, material_kind};
use ppm_core::sampling::{sample_cdf, uniform_triangle};
use ppm_core::trace::PoseQueries;

/// Bounces after which a path stops. Russian roulette ends paths long before in any scene
/// that absorbs: even the albedo-0.99 furnace loses only `0.99^1024 = 3e-5` of its light here.
pub const MAX_BOUNCES: u32 = 1024;

/// Bounces taken before Russian roulette may end a path.
const ROULETTE_AFTER: u32 = 3;

/// Dimension pairs of the sampler: the point in the pixel, then per bounce three pairs: the
/// point on a light; the bounce direction; the light (its number also picks the lobe at
/// glass and coats) and the roulette.
const PAIRS_PER_BOUNCE: u32 = 3;

/// The random numbers of one bounce.
struct Bounce {
    light_point: (f32, f32),
    direction: (f32, f32),
    light: f32,
    roulette: f32,
}

impl Bounce {
    fn new(sampler: &Sampler, bounce: u32) -> Self {
        let pair = 1 + bounce * PAIRS_PER_BOUNCE;
        let (light, roulette) = sampler.pair(pair + 2);
        Self {
            light_point: sampler.pair(pair),
            direction: sampler.pair(pair + 1),
            light,
            roulette,
        }
    }
}

/// What one path needs to know besides its random numbers.
pub struct PathTracer<'a> {
    /// Geometry, materials and lights.
    pub scene: &'a SceneData,
    /// The camera.
    pub camera: &'a GpuCamera,
    /// Offset of new ray origins against self-intersection.
    pub ray_epsilon: f32,
}

impl PathTracer<'_> {
    /// Radiance of one path through pixel `(x, y)`, sample `sample` of run `seed`.
    pub fn sample(&self, seed: u32, x: u32, y: u32, sample: u32) -> Vec3 {
        let sampler = Sampler::new(seed, y * self.camera.width + x, sample);
        let (jx, jy) = sampler.pair(0);
        let ray = camera_ray(self.camera, x as f32 + jx, y as f32 + jy);
        self.radiance(Vec3::from(self.camera.eye), ray, &sampler)
    }

    fn radiance(&self, mut origin: Vec3, mut dir: Vec3, sampler: &Sampler) -> Vec3 {
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        // Solid-angle density of the last bounce's direction; `None` after the camera or a
        // specular bounce, which light sampling cannot produce, so emission counts whole.
        let mut bsdf_pdf: Option<f32> = None;
        for bounce in 0..MAX_BOUNCES {
            let Some(hit) = self.scene.closest_hit(origin, dir, f32::INFINITY) else {
                break;
            };
            let tri = &self.scene.triangles[hit.triangle as usize];
            let position = origin + dir * hit.t;
            let (material, _) = self.scene.surface(&hit, position);
            let material = &material;
            let normal = Vec3::from(tri.normal);
            let cos_front = -dir.dot(normal);
            let front = cos_front > 0.0;
            let facing = if front { normal } else { -normal };
            let emission = Vec3::from(material.emission);
            if front && emission.max_element() > 0.0 {
                let weight = match (bsdf_pdf, tri.light) {
                    (Some(pb), light) if light != NO_MATERIAL => {
                        let pl =
                            self.light_pdf(&self.scene.lights[light as usize], hit.t, cos_front);
                        power_heuristic(pb, pl)
                    }
                    _ => 1.0,
                };
                radiance += throughput * emission * weight;
            }
            let u = Bounce::new(sampler, bounce);
            // A black diffuse surface ends the path (a coated one still reflects).
            if material.kind == material_kind::DIFFUSE
                && bsdf::visible_point_f(material).max_element() <= 0.0
            {
                break;
            }
            let wo = -dir;
            let frame = self.scene.frame(&hit, material, facing);
            if bsdf::samples_lights(material) {
                let eval = |w| {
                    (
                        bsdf::eval_cos(material, &frame, wo, w),
                        bsdf::pdf(material, &frame, wo, w),
                    )
                };
                radiance += throughput * self.light_sample(position, facing, eval, &u);
            } else if bsdf::is_rough_glass(material) {
                let eval = |w| {
                    let (f_cos, pdf) = rough_glass::eval_cos_pdf(material, &frame, front, wo, w);
                    (Vec3::splat(f_cos), pdf)
                };
                radiance += throughput * self.light_sample(position, facing, eval, &u);
            }
            // The lobe is picked by the light choice's number: a coated surface draws its
            // base's direction from both numbers of `direction`, which must not also pick
            // the lobe; light sampling and the bounce stay unbiased, only correlated.
            let scattered = bsdf::sample(
                material,
                dir,
                &frame,
                front,
                (u.light, u.direction),
                Transport::Radiance,
            );
            let side = if scattered.transmitted {
                -facing
            } else {
                facing
            };
            origin = position + side * self.ray_epsilon;
            dir = scattered.dir;
            if scattered.weight == Vec3::ZERO {
                break;
            }
            throughput *= scattered.weight;
            // A delta lobe (a coat's smooth reflection too) reports no density: light
            // sampling cannot weigh against it. A rough dielectric's bounce reports none
            // either, since its density takes the side: asked here.
            let pdf = if bsdf::is_rough_glass(material) {
                rough_glass::eval_cos_pdf(material, &frame, front, wo, scattered.dir).1
            } else {
                scattered.pdf
            };
            bsdf_pdf = (pdf > 0.0).then_some(pdf);
            if bounce >= ROULETTE_AFTER {
                let survive = throughput.max_element().min(0.95);
                if u.roulette >= survive {
                    break;
                }
                throughput /= survive;
            }
        }
        radiance
    }

    /// Light scattered towards the eye from one point on the lights, `f cos_x Le cos_l /
    /// (d^2 p_area)`, weighted against the BSDF's bounce by the power heuristic. `eval`
    /// gives the surface's `f cos_x` and density for a direction to the light; the shadow ray
    /// leaves from the side of the surface that direction is on (`facing`'s, unless the
    /// surface lets light through).
    fn light_sample(
        &self,
        position: Vec3,
        facing: Vec3,
        eval: impl Fn(Vec3) -> (Vec3, f32),
        u: &Bounce,
    ) -> Vec3 {
        let lights = &self.scene.lights;
        if lights.is_empty() {
            return Vec3::ZERO;
        }
        let light = &lights[sample_cdf(|i| lights[i].cdf, lights.len(), u.light)];
        let (b1, b2) = uniform_triangle(u.light_point.0, u.light_point.1);
        let y = Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2;
        let towards = |x: Vec3| {
            let to_light = y - x;
            let dist = to_light.length();
            (x, to_light / dist, dist)
        };
        let (mut x, mut w, mut dist) = towards(position + facing * self.ray_epsilon);
        if facing.dot(w) < 0.0 {
            (x, w, dist) = towards(position - facing * self.ray_epsilon);
        }
        if dist <= 0.0 || dist.is_nan() {
            return Vec3::ZERO;
        }
        let cos_l = -Vec3::from(light.normal).dot(w);
        if cos_l <= 0.0 {
            return Vec3::ZERO;
        }
        let (f_cos, pb) = eval(w);
        if f_cos.max_element() <= 0.0 || self.scene.occluded(x, w, dist - 2.0 * self.ray_epsilon) {
            return Vec3::ZERO;
        }
        let pl = self.light_pdf(light, dist, cos_l);
        let le = Vec3::from(self.scene.materials[light.material as usize].emission);
        f_cos * le / pl * power_heuristic(pl, pb)
    }

    /// Solid-angle density with which light sampling picks a point of `light` seen at
    /// distance `dist` under cosine `cos_l`: by power, then uniform on the area.
    fn light_pdf(&self, light: &GpuLight, dist: f32, cos_l: f32) -> f32 {
        light.pdf / light.area * dist * dist / cos_l
    }
}

/// The power heuristic (beta = 2) weight of a strategy with density `a` against one with `b`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 3.0), (0.2, 0.0), (5.0, 5.0)] {
            assert_relative_eq!(power_heuristic(a, b) + power_heuristic(b, a), 1.0);
        }
    }
}
