//! A coated diffuse surface: a Lambertian base under a clear dielectric coat, smooth or
//! GGX-rough (Mitsuba 3's `plastic` and `roughplastic`; docs/materials.md, "Coated diffuse").
//!
//! The coat reflects a share `R(mu)` of the light arriving at cosine `mu` as a dielectric of
//! index `ior` would, and lets `t(mu)` through to the base (`1 - R(mu)` when smooth; when
//! rough, the refraction lobe's integral, which the microfacets' masking keeps below
//! `1 - R`), which diffuses it; of that, the coat sends `F_int` back down (its
//! cosine-weighted reflectance from inside), and so on. What leaves through the coat towards `wo` is spread as the base spreads it, so
//! the diffuse part of the BSDF separates:
//!
//! `f_d(wo, wi) = A t(cos_o) t(cos_i)`, `A = albedo / (pi ior^2 (1 - x F_int))`,
//!
//! with `x = albedo` when the base's colour is met at every return under the coat, one when
//! once. That is what lets a visible point on it keep one `f` ([`visible_point_f`] is `A`):
//! the eye pass folds `t(cos_o)` into the slot's throughput, the photon pass folds `t(cos_i)`
//! into each deposit, and the direct-light pass multiplies by it.
//!
//! Paths choose between the coat's reflection and the base with the coat's reflectance
//! weighed against the base's colour (Mitsuba 3's choice): an eye path that takes the base
//! stops there, one that takes the reflection continues, as at a mirror or a rough metal.

use super::{
    BsdfSample, FRAC_1_PI, GpuMaterial, SMOOTH_ALPHA, Vec3, ggx_g2_over_g1, ggx_pdf,
    ggx_reflection_cos, roughness, sample_ggx_reflection, sample_visible, visible_normal,
};
use crate::geometry::{Frame, fresnel_refract, reflect};
use crate::layout::material_kind;
use glam::Vec2;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Nodes of a rough coat's transmittance table, at `mu = (i / (NODES - 1))^2`.
pub const NODES: usize = 12;

/// Fresnel reflectance of a smooth boundary for unpolarised light arriving at `cos_i` from
/// the side of index `eta_i`, with `eta = eta_i / eta_t`; one past the critical angle.
pub fn dielectric_fresnel(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// Whether the coat reflects as a smooth boundary (a delta lobe).
#[inline]
pub fn is_smooth(material: &GpuMaterial) -> bool {
    material.alpha < SMOOTH_ALPHA
}

/// The share of light arriving at cosine `mu` that the coat lets through, `t(mu)`: `1 - F`
/// for a smooth coat, the table (linear in `mu` between nodes) for a rough one.
pub fn transmittance(material: &GpuMaterial, mu: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    if is_smooth(material) {
        return 1.0 - dielectric_fresnel(mu, 1.0 / material.ior);
    }
    let last = (NODES - 1) as f32;
    let i = ((mu.sqrt() * last) as usize).min(NODES - 2);
    let (a, b) = ((i as f32 / last).powi(2), ((i + 1) as f32 / last).powi(2));
    let w = ((mu - a) / (b - a)).clamp(0.0, 1.0);
    let table = &material.coat_transmittance;
    table[i] + (table[i + 1] - table[i]) * w
}

/// The factor on light arriving at cosine `mu` that reaches a visible point's `f`: the
/// coat's transmittance on a coated surface, one on a bare diffuse one.
#[inline]
pub fn arrival(material: &GpuMaterial, mu: f32) -> f32 {
    if material.kind == material_kind::COATED {
        transmittance(material, mu)
    } else {
        1.0
    }
}

/// The base's `A` (the module's formula).
pub fn base_f(material: &GpuMaterial) -> Vec3 {
    let albedo = Vec3::from(material.albedo);
    let returns = if material.coat_nonlinear != 0 {
        albedo
    } else {
        Vec3::ONE
    };
    let denominator = (Vec3::ONE - returns * material.coat_internal) * material.ior.powi(2);
    albedo * FRAC_1_PI / denominator
}

/// The chance that a path arriving at cosine `cos_o` takes the coat's reflection: its
/// reflectance weighed by [`GpuMaterial::coat_specular_weight`] against its transmittance
/// weighed by the rest.
pub fn specular_probability(material: &GpuMaterial, cos_o: f32) -> f32 {
    let t = transmittance(material, cos_o);
    let w = material.coat_specular_weight;
    let (specular, diffuse) = ((1.0 - t) * w, t * (1.0 - w));
    if specular + diffuse > 0.0 {
        specular / (specular + diffuse)
    } else {
        0.0
    }
}

/// Where an eye path arriving from `wo` (cosine `cos_o`) stops on a coated surface: the
/// factor on its throughput, `t(cos_o)` over the chance of taking the base, when `u_lobe`
/// takes it; `None` when it takes the coat's reflection.
pub fn visible_point_weight(material: &GpuMaterial, cos_o: f32, u_lobe: f32) -> Option<f32> {
    let p = specular_probability(material, cos_o);
    (u_lobe >= p).then(|| transmittance(material, cos_o) / (1.0 - p))
}

/// `f(wo, wi) cos_i` of both lobes ([`super::eval_cos`]'s conventions; a smooth coat's
/// reflection is a delta lobe and has none).
pub fn eval_cos(material: &GpuMaterial, frame: &Frame, wo: Vec3, wi: Vec3) -> Vec3 {
    let (cos_o, cos_i) = (frame.normal.dot(wo), frame.normal.dot(wi));
    let diffuse = base_f(material)
        * (transmittance(material, cos_o) * transmittance(material, cos_i) * cos_i);
    if is_smooth(material) {
        return diffuse;
    }
    let (lobe, h) = ggx_reflection_cos(roughness(material), frame, wo, wi);
    diffuse + Vec3::splat(dielectric_fresnel(wo.dot(h), 1.0 / material.ior) * lobe)
}

/// The rough coat's reflection lobe alone, the one an eye path continues by: `f cos` over
/// the chance of taking it, and the density with which [`sample`] draws `wi` once it has
/// ([`super::glossy_lobe`]).
pub fn reflection_lobe(material: &GpuMaterial, frame: &Frame, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
    let p = specular_probability(material, frame.normal.dot(wo));
    if p <= 0.0 {
        return (Vec3::ZERO, 0.0);
    }
    let alpha = roughness(material);
    let (lobe, h) = ggx_reflection_cos(alpha, frame, wo, wi);
    let f_cos = dielectric_fresnel(wo.dot(h), 1.0 / material.ior) * lobe / p;
    (Vec3::splat(f_cos), ggx_pdf(alpha, frame, wo, wi))
}

/// The density of `wi` over both lobes, each weighed by its chance.
pub fn pdf(material: &GpuMaterial, frame: &Frame, wo: Vec3, wi: Vec3) -> f32 {
    let p = specular_probability(material, frame.normal.dot(wo));
    let diffuse = (1.0 - p) * frame.normal.dot(wi) * FRAC_1_PI;
    if is_smooth(material) {
        return diffuse;
    }
    diffuse + p * ggx_pdf(roughness(material), frame, wo, wi)
}

/// Draws one lobe with `u_lobe` (below the reflection's chance: the reflection) and a
/// direction from it with `u_dir`. The weight is that lobe's `f cos / pdf` over its chance,
/// so that a path which stops at the base for the other lobe counts each once; the density
/// is over both lobes, for weighing against light samples.
pub fn sample(
    material: &GpuMaterial,
    incoming: Vec3,
    frame: &Frame,
    u_lobe: f32,
    u_dir: (f32, f32),
) -> BsdfSample {
    let (wo, facing) = (-incoming, frame.normal);
    let cos_o = facing.dot(wo);
    let p = specular_probability(material, cos_o);
    let eta = 1.0 / material.ior;
    if u_lobe < p {
        if is_smooth(material) {
            return BsdfSample {
                dir: reflect(incoming, facing),
                weight: Vec3::splat(dielectric_fresnel(cos_o, eta) / p),
                pdf: 0.0,
                transmitted: false,
            };
        }
        let r = sample_ggx_reflection(roughness(material), frame, wo, u_dir);
        let weight = dielectric_fresnel(wo.dot(r.h), eta) * r.g2_over_g1 / p;
        return BsdfSample {
            dir: r.dir,
            weight: Vec3::splat(weight),
            pdf: if weight > 0.0 {
                pdf(material, frame, wo, r.dir)
            } else {
                0.0
            },
            transmitted: false,
        };
    }
    let drawn = sample_visible(material, facing, u_dir);
    let cos_i = facing.dot(drawn.dir);
    let through = transmittance(material, cos_o) * transmittance(material, cos_i);
    BsdfSample {
        weight: base_f(material) * (std::f32::consts::PI * through / (1.0 - p)),
        pdf: pdf(material, frame, wo, drawn.dir),
        ..drawn
    }
}

/// The number a photon that took the base plays roulette with: `u_lobe` rescaled from the
/// base's share of `[0, 1)` to all of it, so that it does not depend on the lobe drawn.
pub fn roulette_number(material: &GpuMaterial, cos_o: f32, u_lobe: f32) -> Option<f32> {
    let p = specular_probability(material, cos_o);
    (u_lobe >= p).then(|| ((u_lobe - p) / (1.0 - p)).min(1.0 - f32::EPSILON / 2.0))
}

/// A coat's internal reflectance `F_int` and, for a rough one, its transmittance table: the
/// [`GpuMaterial`] fields the host computes per material (`SMOOTH_ALPHA` and below: the
/// table stays zero, [`transmittance`] is exact). Remembered by index and roughness, since
/// every pose of a moving scene compiles its materials again.
pub fn coat_tables(ior: f32, alpha: f32) -> (f32, [f32; NODES]) {
    type Tables = HashMap<(u32, u32), (f32, [f32; NODES])>;
    static KNOWN: OnceLock<Mutex<Tables>> = OnceLock::new();
    let known = KNOWN.get_or_init(Default::default);
    let key = (ior.to_bits(), alpha.to_bits());
    if let Some(tables) = known.lock().map_or(None, |k| k.get(&key).copied()) {
        return tables;
    }
    let tables = integrate_tables(ior, alpha);
    if let Ok(mut k) = known.lock() {
        k.insert(key, tables);
    }
    tables
}

/// [`coat_tables`] by numerical integration.
fn integrate_tables(ior: f32, alpha: f32) -> (f32, [f32; NODES]) {
    let smooth = alpha < SMOOTH_ALPHA;
    let mut table = [0.0; NODES];
    if !smooth {
        for (i, t) in table.iter_mut().enumerate() {
            let mu = (i as f64 / (NODES - 1) as f64).powi(2).max(1e-6);
            *t = rough_transmittance(1.0 / ior, alpha, mu) as f32;
        }
    }
    // F_int = 2 integral of R_inside(mu) mu dmu, by midpoints.
    let k = if smooth { 4096 } else { 128 };
    let internal = (0..k)
        .map(|i| {
            let mu = (i as f64 + 0.5) / k as f64;
            2.0 * reflectance(ior, alpha, mu) * mu / k as f64
        })
        .sum::<f64>();
    (internal as f32, table)
}

/// A rough coat's transmittance for light arriving at cosine `mu` from outside (`eta = 1 /
/// ior`): the integral of its refraction lobe's `f cos`, `(1 - F) G2 / G1` averaged over the
/// visible normals (as Mitsuba 3's `roughplastic` and pbrt-v4's layered `coateddiffuse`
/// take it). Not `1 - R`: single scattering on the microfacets loses light on the way in as
/// on the way back, and `1 - R` would hand the reflection's loss to the base.
fn rough_transmittance(eta: f32, alpha: f32, mu: f64) -> f64 {
    let (alpha, frame) = (Vec2::splat(alpha), Frame::around(Vec3::Z));
    mean_over_visible_normals(mu, |wo, u| {
        let (_, h) = visible_normal(alpha, &frame, wo, u);
        match fresnel_refract(-wo, h, eta) {
            (fresnel, Some(t)) if t.z < 0.0 => (1.0 - fresnel) * ggx_g2_over_g1(alpha, wo, t),
            _ => 0.0,
        }
    })
}

/// The coat's directional reflectance for light arriving at cosine `mu` from the side where
/// `eta = eta_i / eta_t`: the Fresnel term when smooth; when rough, `F G2 / G1` averaged over
/// the visible normals, the integral of the reflection lobe's `f cos`.
fn reflectance(eta: f32, alpha: f32, mu: f64) -> f64 {
    if alpha < SMOOTH_ALPHA {
        return f64::from(dielectric_fresnel(mu as f32, eta));
    }
    let (alpha, frame) = (Vec2::splat(alpha), Frame::around(Vec3::Z));
    mean_over_visible_normals(mu, |wo, u| {
        let r = sample_ggx_reflection(alpha, &frame, wo, u);
        dielectric_fresnel(wo.dot(r.h), eta) * r.g2_over_g1
    })
}

/// The mean of `f(wo, u)` over a 32x32 grid of midpoints `u` of the visible-normal sampler's
/// numbers, `wo` at cosine `mu` to +z: a lobe's integral, sampled by its own sampler.
fn mean_over_visible_normals(mu: f64, f: impl Fn(Vec3, (f32, f32)) -> f32) -> f64 {
    let wo = Vec3::new((1.0 - mu * mu).sqrt() as f32, 0.0, mu as f32);
    let k = 32;
    let mut sum = 0.0;
    for i in 0..k {
        for j in 0..k {
            let u = ((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
            sum += f64::from(f(wo, u));
        }
    }
    sum / f64::from(k * k)
}

#[cfg(test)]
mod tests {
    use super::super::{Transport, coated, photon_bounce, to_world};
    use super::*;
    use approx::assert_relative_eq;
    use std::f32::consts::PI;

    /// A direction at cosine `mu` about `n`, in the plane of `n`'s tangent.
    fn at(n: Vec3, mu: f32) -> Vec3 {
        let (t, _) = crate::geometry::orthonormal_basis(n);
        (t * (1.0 - mu * mu).sqrt() + n * mu).normalize()
    }

    /// The mean of `f` over a `k`^3 grid of midpoints of a bounce's numbers.
    fn grid_mean(k: usize, f: impl Fn((f32, (f32, f32))) -> f32) -> f64 {
        let mid = |x: usize| (x as f32 + 0.5) / k as f32;
        let mut sum = 0.0;
        for l in 0..k {
            for i in 0..k {
                for j in 0..k {
                    sum += f64::from(f((mid(l), (mid(i), mid(j)))));
                }
            }
        }
        sum / (k * k * k) as f64
    }

    /// Mean weight of `sample` over a grid of its numbers: the directional albedo.
    fn albedo(material: &GpuMaterial, n: Vec3, wo: Vec3) -> f64 {
        grid_mean(48, |(l, d)| {
            sample(material, -wo, &Frame::around(n), l, d).weight.x
        })
    }

    /// The smooth coat's internal reflectance is the known one for an index of 1.5 (0.596),
    /// and what light the coat lets in from outside balances what the base's diffuse light
    /// gets out: `1 - F_ext = ior^2 (1 - F_int)`.
    #[test]
    fn a_smooth_coat_s_internal_reflectance_balances_its_external_one() {
        let (internal, table) = coat_tables(1.5, 0.0);
        assert_relative_eq!(internal, 0.596, epsilon = 2e-3);
        assert_eq!(table, [0.0; NODES]);
        let k = 4096;
        let external: f64 = (0..k)
            .map(|i| {
                let mu = (i as f64 + 0.5) / k as f64;
                2.0 * f64::from(dielectric_fresnel(mu as f32, 1.0 / 1.5)) * mu / k as f64
            })
            .sum();
        assert_relative_eq!(
            1.0 - external,
            2.25 * (1.0 - f64::from(internal)),
            epsilon = 1e-3
        );
    }

    /// A white base under a smooth coat, whose light returns to it until it leaves, loses
    /// nothing: from every incidence the coat's reflection and the base's light add to one
    /// (a white furnace). Under a rough coat single scattering on the microfacets loses,
    /// on the way in, on the way out and where light returns under the coat (Mitsuba 3's
    /// `roughplastic` keeps 0.69 of it at alpha 0.3 seen from above; this model 0.70, with
    /// Smith's height-correlated masking and finer sums), and never gains. A black base
    /// leaves the coat's reflection alone.
    #[test]
    fn a_white_coated_surface_conserves_energy() {
        let n = Vec3::new(0.2, 0.9, -0.1).normalize();
        let smooth = coated([1.0; 3], 1.5, 0.0, true);
        let rough = coated([1.0; 3], 1.5, 0.3, true);
        let black = coated([0.0; 3], 1.5, 0.0, false);
        for mu in [1.0f32, 0.7, 0.3, 0.1] {
            let wo = at(n, mu);
            assert_relative_eq!(albedo(&smooth, n, wo), 1.0, epsilon = 3e-3);
            let a = albedo(&rough, n, wo);
            assert!((0.65..=1.0).contains(&a), "rough coat at {mu}: {a}");
            let f = f64::from(dielectric_fresnel(mu, 1.0 / 1.5));
            assert_relative_eq!(albedo(&black, n, wo), f, epsilon = 1e-4);
        }
    }

    /// A rough coat lets in less light at grazing angles than at normal incidence, by the
    /// microfacets' masking of the refracted light as well as by Fresnel: its transmittance
    /// at alpha 0.2, index 1.5, relative to normal incidence, follows Mitsuba 3.9.1's
    /// `roughplastic` (0.857 at `mu = 0.3`, 0.740 at 0.1, evaluated there) within 3%. One
    /// minus the reflection lobe's integral, which hands the reflection's single-scattering
    /// loss to the base, gives 0.913 and 0.829, and fails.
    #[test]
    fn a_rough_coat_s_transmittance_falls_at_grazing_angles_as_mitsuba_s() {
        let m = coated([1.0; 3], 1.5, 0.2, true);
        let normal = transmittance(&m, 1.0);
        for (mu, mitsuba) in [(0.3, 0.857), (0.1, 0.740)] {
            let ratio = transmittance(&m, mu) / normal;
            assert_relative_eq!(ratio, mitsuba, max_relative = 0.03);
        }
    }

    /// Both lobes of a rough coat agree with `eval_cos` and `pdf`: the mean weight is the
    /// integral of `f cos` over the hemisphere, the density integrates to the share of
    /// samples that stay above the surface, and `f` is reciprocal.
    #[test]
    fn a_rough_coat_s_samples_match_its_value_and_density() {
        let n = Vec3::Z;
        for nonlinear in [false, true] {
            let m = coated([0.7, 0.4, 0.2], 1.5, 0.4, nonlinear);
            for mu in [0.9f32, 0.4] {
                let wo = at(n, mu);
                let k = 512;
                let (mut by_eval, mut density) = (0.0f64, 0.0f64);
                for i in 0..k {
                    for j in 0..k {
                        let cos_t = (i as f32 + 0.5) / k as f32;
                        let phi = 2.0 * PI * (j as f32 + 0.5) / k as f32;
                        let sin_t = (1.0 - cos_t * cos_t).sqrt();
                        let wi =
                            to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t), n);
                        let w = 2.0 * std::f64::consts::PI / f64::from(k * k);
                        let frame = Frame::around(n);
                        by_eval += f64::from(eval_cos(&m, &frame, wo, wi).x) * w;
                        density += f64::from(pdf(&m, &frame, wo, wi)) * w;
                        let back = eval_cos(&m, &frame, wi, wo).x / mu;
                        assert_relative_eq!(
                            eval_cos(&m, &frame, wo, wi).x / cos_t,
                            back,
                            max_relative = 1e-3
                        );
                    }
                }
                assert_relative_eq!(by_eval, albedo(&m, n, wo), max_relative = 0.01);
                assert!(density <= 1.0 + 1e-3 && density > 0.9, "{density}");
            }
        }
    }

    /// A photon's roulette under a coat is unbiased: over its numbers, the expected factor
    /// on its power is the surface's directional albedo.
    #[test]
    fn a_photon_keeps_the_expected_power_under_a_coat() {
        let n = Vec3::Z;
        let m = coated([0.9, 0.5, 0.2], 1.5, 0.0, true);
        let wo = at(n, 0.6);
        let power = grid_mean(64, |u| {
            photon_bounce(&m, -wo, &Frame::around(n), true, u).map_or(0.0, |s| s.weight.x)
        });
        assert_relative_eq!(power, albedo(&m, n, wo), max_relative = 3e-3);
        let up = Frame::around(n);
        let s = super::super::sample(&m, -wo, &up, true, (0.0, (0.5, 0.5)), Transport::Radiance);
        assert_eq!(
            (s.pdf, s.transmitted),
            (0.0, false),
            "the smooth reflection is a delta lobe"
        );
    }
}
