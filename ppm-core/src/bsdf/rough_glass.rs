//! A rough dielectric's value and density for a pair of directions, on either side of the
//! surface: what the reference path tracer and the eye pass ([`super::glossy_lobe`]) need to
//! take light samples at rough glass and weigh them against the bounce that
//! [`sample`](super::sample) draws there; bsdf.wgsl's `rough_glass_eval_cos_pdf` is the twin.
//!
//! [`eval_cos`](super::eval_cos) and [`pdf`](super::pdf) leave rough glass out: its Fresnel
//! term depends on which side the path arrives from, which they do not take (no visible
//! point lies on glass). Here the side comes in as `front`, and
//! the densities are those of the sampler: a microfacet normal drawn from the normals visible
//! from `wo`, then reflection with the chance `F` or refraction with `1 - F` (Walter et al.
//! 2007, sections 4-5; Heitz 2018).

use super::{GpuMaterial, Vec3, ggx_d, ggx_pdf, ggx_reflection_cos, roughness, smith_root};
use crate::geometry::{Frame, fresnel_refract};

/// `f cos_i` and the solid-angle density of `wi` for an eye path (radiance) that arrived
/// from `wo` at rough glass: `frame.normal` is the unit normal on `wo`'s side, `front`
/// whether that is the outside. `wi` above the surface is a reflection, below it a refraction; zero (and
/// zero density) where the sampler cannot draw `wi` from `wo`.
pub fn eval_cos_pdf(
    material: &GpuMaterial,
    frame: &Frame,
    front: bool,
    wo: Vec3,
    wi: Vec3,
) -> (f32, f32) {
    let (alpha, facing) = (roughness(material), frame.normal);
    let (local_o, local_i) = (frame.to_local(wo), frame.to_local(wi));
    let (cos_o, cos_i) = (local_o.z, local_i.z);
    if cos_o <= 0.0 || cos_i == 0.0 {
        return (0.0, 0.0);
    }
    // The index on `wo`'s side over the index on the far side, as the sampler takes it.
    let eta = if front {
        1.0 / material.ior
    } else {
        material.ior
    };
    if cos_i > 0.0 {
        let (lobe, h) = ggx_reflection_cos(alpha, frame, wo, wi);
        let (fresnel, _) = fresnel_refract(-wo, h, eta);
        return (fresnel * lobe, fresnel * ggx_pdf(alpha, frame, wo, wi));
    }
    // The microfacet normal that refracts `-wo` into `wi` (Walter et al. eq. 16), turned to
    // `wo`'s side.
    let sum = wo * eta + wi;
    let h = (sum / sum.abs().max_element()).normalize();
    let h = if facing.dot(h) < 0.0 { -h } else { h };
    let (o_h, i_h) = (wo.dot(h), wi.dot(h));
    // Refraction leaves the microfacet on its far side; the squared Jacobian denominator
    // vanishes only where no such normal exists.
    let denom = eta * o_h + i_h;
    let denom2 = denom * denom;
    if o_h <= 0.0 || i_h >= 0.0 || denom2 <= 0.0 || denom2.is_nan() {
        return (0.0, 0.0);
    }
    let (fresnel, refracted) = fresnel_refract(-wo, h, eta);
    if refracted.is_none() {
        return (0.0, 0.0);
    }
    let d = ggx_d(alpha, frame.to_local(h));
    let (abs_i, root_o) = (-cos_i, smith_root(alpha, local_o));
    let root_i = smith_root(alpha, local_i);
    // Visible-normal density D G1(wo) (wo.h) / cos_o, G1 = 2 cos_o / (cos_o + root_o), times
    // the refraction's Jacobian |wi.h| / (eta wo.h + wi.h)^2 (both indices divided by the far
    // one), times the chance 1 - F of refracting.
    let jacobian = -i_h / denom2;
    let pdf = (1.0 - fresnel) * d * 2.0 * o_h / (cos_o + root_o) * jacobian;
    // f cos_i = (1 - F) D G2 (wo.h) |wi.h| / (cos_o (eta wo.h + wi.h)^2), radiance scaled by
    // eta^2 through the boundary (Transport::Radiance), G2 = 2 cos_o |cos_i| / (|cos_i| root_o
    // + cos_o root_i).
    let g2 = 2.0 * cos_o * abs_i / (abs_i * root_o + cos_o * root_i);
    let f_cos = eta * eta * (1.0 - fresnel) * d * g2 * o_h * jacobian / cos_o;
    (f_cos, pdf)
}

#[cfg(test)]
mod tests {
    use super::super::{Transport, sample};
    use super::*;
    use crate::layout::material_kind;
    use crate::sampling::uniform_cone;
    use bytemuck::Zeroable;

    fn rough_glass(ior: f32, (alpha, alpha_v): (f32, f32)) -> GpuMaterial {
        GpuMaterial {
            kind: material_kind::GLASS,
            ior,
            alpha,
            alpha_v,
            ..Zeroable::zeroed()
        }
    }

    /// The +y side's frame, its tangent off every view's plane so that an anisotropic lobe
    /// is seen obliquely.
    fn frame() -> Frame {
        Frame::with_tangent(Vec3::Y, Vec3::new(0.8, 0.0, 0.6))
    }

    /// Directions `wo` on the facing side (the normal is +y), from normal to grazing.
    fn views() -> Vec<Vec3> {
        [1.0f32, 0.7, 0.3, 0.08]
            .iter()
            .map(|&c| Vec3::new((1.0 - c * c).sqrt(), c, 0.0))
            .collect()
    }

    #[test]
    fn each_sampled_direction_s_weight_is_its_value_over_its_density() {
        for (ior, alpha) in [
            (1.5, (0.3, 0.3)),
            (1.5, (0.05, 0.05)),
            (1.33, (0.8, 0.8)),
            (2.4, (0.15, 0.15)),
            (1.5, (0.05, 0.4)),
        ] {
            let material = rough_glass(ior, alpha);
            for front in [true, false] {
                for wo in views() {
                    let mut checked = [0; 2];
                    for i in 0..4096u32 {
                        let u = (
                            (i as f32 + 0.5) / 4096.0,
                            (
                                ((i * 2654435761) >> 8) as f32 / 16777216.0,
                                (i % 61) as f32 / 61.0,
                            ),
                        );
                        let s = sample(&material, -wo, &frame(), front, u, Transport::Radiance);
                        if s.weight.x == 0.0 {
                            continue;
                        }
                        let (f_cos, pdf) = eval_cos_pdf(&material, &frame(), front, wo, s.dir);
                        assert!(pdf > 0.0, "{ior} {alpha:?} {front} {wo} {}", s.dir);
                        let w = f_cos / pdf;
                        assert!(
                            (w - s.weight.x).abs() <= 1e-3 * s.weight.x.max(1.0),
                            "ior {ior} alpha {alpha:?} front {front} wo {wo} wi {}: {w} against {}",
                            s.dir,
                            s.weight.x
                        );
                        checked[usize::from(s.transmitted)] += 1;
                    }
                    // Both lobes were checked, but past the critical angle inside.
                    assert!(checked[0] > 0, "{checked:?}");
                    assert!(front || wo.y < 0.7 || checked[1] > 0, "{checked:?}");
                }
            }
        }
    }

    #[test]
    fn the_density_integrates_to_the_share_of_samples_the_sampler_keeps() {
        const N: u32 = 1 << 18;
        for (material, front) in [(0.3, 0.3), (0.1, 0.5)]
            .into_iter()
            .flat_map(|a| [true, false].map(|f| (rough_glass(1.5, a), f)))
        {
            for wo in views() {
                let integral: f64 = (0..N)
                    .map(|i| {
                        let u = (
                            (i as f32 + 0.5) / N as f32,
                            ((i * 40503) % N) as f32 / N as f32,
                        );
                        let wi = uniform_cone(u.0, u.1, -1.0);
                        let (_, pdf) = eval_cos_pdf(&material, &frame(), front, wo, wi);
                        f64::from(pdf) * 4.0 * std::f64::consts::PI
                    })
                    .sum::<f64>()
                    / f64::from(N);
                let kept = (0..N)
                    .filter(|&i| {
                        let u = (
                            ((i * 7919) % N) as f32 / N as f32,
                            (
                                (i as f32 + 0.5) / N as f32,
                                ((i * 40503) % N) as f32 / N as f32,
                            ),
                        );
                        let s = sample(&material, -wo, &frame(), front, u, Transport::Radiance);
                        s.weight.x > 0.0
                    })
                    .count() as f64
                    / f64::from(N);
                assert!(
                    (integral - kept).abs() < 0.02,
                    "front {front} wo {wo}: density integrates to {integral}, sampler keeps {kept}"
                );
            }
        }
    }
}
