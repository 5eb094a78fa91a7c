//! What each material does with light, in one place: the eye, photon, direct-light and gather
//! passes, the reference path tracer and local mode's probes all ask here, and backend-wgpu's
//! `bsdf.wgsl` is the twin, pinned to this module by [`test_cases`] (docs/algorithm.md 1, "Materials").
//!
//! Materials fall in two families. **Delta** materials (mirror, glass) scatter into one or two
//! directions: paths continue through them, and no density exists to evaluate or to weight
//! against light sampling. **Diffuse** materials scatter over the hemisphere with
//! `f = albedo / pi`: an eye path stops at the first one (its visible point), a photon is
//! stored there. Because `f` is the same for every pair of directions on such a surface,
//! slots and photons store no direction; a glossy material adds them.
//!
//! Directions follow the passes: `incoming` is the unit direction a path travels (towards
//! the surface), `facing` the unit normal on its side, and every sampled direction leaves
//! the surface.

use crate::geometry::{fresnel_refract, reflect, to_world};
use crate::layout::{GpuMaterial, material_kind};
use crate::sampling::cosine_hemisphere;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// What a path carries, which decides how refraction scales it (Veach 1997, 5.2).
///
/// Radiance is not invariant across a refractive boundary, `L / eta^2` is: a camera in air
/// looking into water of index 1.8 sees the radiance leaving a surface under water divided by
/// `1.8^2`. Flux is invariant: a photon keeps its power when it refracts. So an eye path's
/// throughput takes `(eta_i / eta_t)^2` at each refraction and a photon's power takes nothing;
/// the two factors of a path that enters and leaves a body cancel. The values are the WGSL
/// twin's `TRANSPORT_*` constants.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// An eye path: its throughput weights radiance found at its end.
    Radiance = 0,
    /// A photon path: its power is flux.
    Importance = 1,
}

/// A direction drawn from a surface's BSDF, and what it does to the path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// New unit direction, leaving the surface.
    pub dir: Vec3,
    /// Factor on the path's throughput or power: `f cos / pdf`, times `(eta_i / eta_t)^2`
    /// for radiance through a refraction; a delta lobe's reflectance or transmittance.
    pub weight: Vec3,
    /// Solid-angle density of `dir`; zero for a delta lobe, which no other strategy can draw.
    pub pdf: f32,
    /// The path passed through the surface: the next origin goes to the far side.
    pub transmitted: bool,
}

/// Whether the material scatters into single directions (mirror, glass): paths continue
/// through it, and it holds no visible points and no photons.
#[inline]
pub fn is_delta(material: &GpuMaterial) -> bool {
    matches!(material.kind, material_kind::MIRROR | material_kind::GLASS)
}

/// The BSDF `f` at a visible point (or a photon's surface), for any pair of directions on the
/// facing side: every material that holds visible points is diffuse, `albedo / pi`.
#[inline]
pub fn visible_point_f(material: &GpuMaterial) -> Vec3 {
    Vec3::from(material.albedo) * FRAC_1_PI
}

/// Solid-angle density with which [`sample`] draws `wi` at a non-delta surface with facing
/// normal `facing` (the cosine lobe); zero below the surface and for delta materials.
#[inline]
pub fn pdf(material: &GpuMaterial, facing: Vec3, wi: Vec3) -> f32 {
    if is_delta(material) {
        return 0.0;
    }
    facing.dot(wi).max(0.0) * FRAC_1_PI
}

/// Draws a direction at a non-delta surface: the cosine lobe about `facing`, from the pair
/// `u`; the weight is the albedo (`f cos / pdf`).
#[inline]
pub fn sample_visible(material: &GpuMaterial, facing: Vec3, u: (f32, f32)) -> BsdfSample {
    let local = cosine_hemisphere(u.0, u.1);
    BsdfSample {
        dir: to_world(local, facing),
        weight: Vec3::from(material.albedo),
        pdf: local.z * FRAC_1_PI,
        transmitted: false,
    }
}

/// Continues a path at a delta surface: mirrors reflect with their reflectance; glass
/// reflects with probability equal to the Fresnel term, else refracts, the weight then
/// `(eta_i / eta_t)^2` for radiance and one for flux ([`Transport`]). `front` says whether
/// `facing` is the triangle's own normal (the path is entering); `u_lobe` picks at glass.
#[inline]
pub fn sample_delta(
    material: &GpuMaterial,
    incoming: Vec3,
    facing: Vec3,
    front: bool,
    u_lobe: f32,
    transport: Transport,
) -> BsdfSample {
    let reflected = |weight| BsdfSample {
        dir: reflect(incoming, facing),
        weight,
        pdf: 0.0,
        transmitted: false,
    };
    if material.kind == material_kind::MIRROR {
        return reflected(Vec3::from(material.albedo));
    }
    let eta = if front {
        1.0 / material.ior
    } else {
        material.ior
    };
    match fresnel_refract(incoming, facing, eta) {
        (fresnel, Some(t)) if u_lobe >= fresnel => BsdfSample {
            dir: t,
            weight: Vec3::splat(match transport {
                Transport::Radiance => eta * eta,
                Transport::Importance => 1.0,
            }),
            pdf: 0.0,
            transmitted: true,
        },
        _ => reflected(Vec3::ONE),
    }
}

/// Draws how a path continues at any surface: [`sample_delta`] with `u_lobe` at mirror and
/// glass, [`sample_visible`] with `u_dir` elsewhere.
#[inline]
pub fn sample(
    material: &GpuMaterial,
    incoming: Vec3,
    facing: Vec3,
    front: bool,
    (u_lobe, u_dir): (f32, (f32, f32)),
    transport: Transport,
) -> BsdfSample {
    if is_delta(material) {
        sample_delta(material, incoming, facing, front, u_lobe, transport)
    } else {
        sample_visible(material, facing, u_dir)
    }
}

/// One input of the BSDF: a backend's twin must give [`BsdfCase::expected`]. 80 bytes, the
/// layout of `BsdfCase` in the wgpu backend's bsdf_vectors.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BsdfCase {
    /// The surface.
    pub material: GpuMaterial,
    /// Direction the path travels.
    pub incoming: [f32; 3],
    /// 1 when `facing` is the triangle's own normal.
    pub front: u32,
    /// Normal on the incoming side.
    pub facing: [f32; 3],
    /// Number that picks at glass.
    pub u_lobe: f32,
    /// Pair that draws a diffuse direction.
    pub u_dir: [f32; 2],
    /// [`Transport`] as `u32`.
    pub transport: u32,
    /// Padding.
    pub _pad: u32,
}

/// What the BSDF gives for one [`BsdfCase`]: [`sample`], and at its direction [`pdf`] and
/// [`visible_point_f`]. 48 bytes, bsdf_vectors.wgsl's `BsdfOutcome`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BsdfOutcome {
    /// [`BsdfSample::dir`].
    pub dir: [f32; 3],
    /// [`BsdfSample::pdf`].
    pub pdf: f32,
    /// [`BsdfSample::weight`].
    pub weight: [f32; 3],
    /// [`BsdfSample::transmitted`] as 0 or 1.
    pub transmitted: u32,
    /// [`visible_point_f`].
    pub f: [f32; 3],
    /// [`pdf`] of the sampled direction.
    pub pdf_of_dir: f32,
}

impl BsdfCase {
    /// The outcome by this module.
    pub fn expected(&self) -> BsdfOutcome {
        let transport = match self.transport {
            0 => Transport::Radiance,
            _ => Transport::Importance,
        };
        let facing = Vec3::from(self.facing);
        let s = sample(
            &self.material,
            Vec3::from(self.incoming),
            facing,
            self.front != 0,
            (self.u_lobe, (self.u_dir[0], self.u_dir[1])),
            transport,
        );
        BsdfOutcome {
            dir: s.dir.into(),
            pdf: s.pdf,
            weight: s.weight.into(),
            transmitted: u32::from(s.transmitted),
            f: visible_point_f(&self.material).into(),
            pdf_of_dir: pdf(&self.material, facing, s.dir),
        }
    }
}

/// Every material over incidences from normal to grazing, from both sides, with both
/// transports and with numbers that reflect and refract at glass: the vectors a backend's
/// twin must reproduce. Glass cases whose number lies within 1e-3 of the Fresnel term are
/// left out, where a last-place difference could pick the other lobe.
pub fn test_cases() -> Vec<BsdfCase> {
    let materials = [
        GpuMaterial {
            albedo: [0.8, 0.5, 0.1],
            kind: material_kind::DIFFUSE,
            ..Zeroable::zeroed()
        },
        GpuMaterial {
            albedo: [0.9, 0.7, 0.3],
            kind: material_kind::MIRROR,
            ..Zeroable::zeroed()
        },
        GpuMaterial {
            kind: material_kind::GLASS,
            ior: 1.5,
            ..Zeroable::zeroed()
        },
        GpuMaterial {
            kind: material_kind::GLASS,
            ior: 1.8,
            ..Zeroable::zeroed()
        },
    ];
    let normals = [Vec3::Y, Vec3::new(0.3, -0.5, 0.8).normalize()];
    let mut cases = Vec::new();
    for material in materials {
        for n in normals {
            for front in [true, false] {
                let facing = if front { n } else { -n };
                let (t, _) = crate::geometry::orthonormal_basis(facing);
                for cos_i in [1.0f32, 0.8, 0.5, 0.2, 0.05] {
                    let sin_i = (1.0 - cos_i * cos_i).sqrt();
                    let incoming = (t * sin_i - facing * cos_i).normalize();
                    for (u_lobe, u_dir) in
                        [(0.01, [0.1, 0.3]), (0.5, [0.6, 0.9]), (0.97, [0.95, 0.02])]
                    {
                        for transport in [Transport::Radiance, Transport::Importance] {
                            let case = BsdfCase {
                                material,
                                incoming: incoming.into(),
                                front: u32::from(front),
                                facing: facing.into(),
                                u_lobe,
                                u_dir,
                                transport: transport as u32,
                                _pad: 0,
                            };
                            let eta = if front {
                                1.0 / material.ior
                            } else {
                                material.ior
                            };
                            let near_threshold = material.kind == material_kind::GLASS
                                && (fresnel_refract(incoming, facing, eta).0 - u_lobe).abs() < 1e-3;
                            if !near_threshold {
                                cases.push(case);
                            }
                        }
                    }
                }
            }
        }
    }
    cases
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn glass(ior: f32) -> GpuMaterial {
        GpuMaterial {
            kind: material_kind::GLASS,
            ior,
            ..Zeroable::zeroed()
        }
    }

    /// Into water of index 1.8 and out again: radiance divides by 1.8^2 going in and
    /// multiplies by it coming out (the product is one), flux keeps its power both ways, and
    /// reflection changes neither.
    #[test]
    fn refraction_scales_radiance_by_eta_squared_and_keeps_flux() {
        let water = glass(1.8);
        let up = Vec3::Y;
        let down = Vec3::new(0.3, -1.0, 0.0).normalize();
        let bounce = |dir: Vec3, front, u, transport| {
            let facing = if front { up } else { -up };
            sample_delta(&water, dir, facing, front, u, transport)
        };
        let enter = bounce(down, true, 0.99, Transport::Radiance);
        assert!(enter.transmitted);
        assert_relative_eq!(enter.weight.x, 1.0 / (1.8 * 1.8), epsilon = 1e-6);
        let leave = bounce(-enter.dir, false, 0.99, Transport::Radiance);
        assert!(leave.transmitted);
        assert_relative_eq!(enter.weight.x * leave.weight.x, 1.0, epsilon = 1e-5);
        assert_relative_eq!(leave.dir.dot(-down), 1.0, epsilon = 1e-5);
        let photon = bounce(down, true, 0.99, Transport::Importance);
        assert_eq!((photon.dir, photon.weight), (enter.dir, Vec3::ONE));
        let mirrored = bounce(down, true, 0.0, Transport::Radiance);
        assert!(!mirrored.transmitted);
        assert_eq!(mirrored.weight, Vec3::ONE);
    }

    /// A white diffuse surface lit evenly from every direction reflects all of it: the
    /// estimator `weight` of cosine samples is the albedo, and the density they report is
    /// the one [`pdf`] gives and integrates to one over the hemisphere (a midpoint sum).
    #[test]
    fn the_diffuse_lobe_conserves_energy_and_its_density_integrates_to_one() {
        let white = GpuMaterial {
            albedo: [1.0; 3],
            ..Zeroable::zeroed()
        };
        let n = Vec3::new(0.2, 0.9, -0.1).normalize();
        let k = 64;
        let mut integral = 0.0f64;
        for i in 0..k {
            for j in 0..k {
                let u = ((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let s = sample_visible(&white, n, u);
                assert_eq!(s.weight, Vec3::ONE);
                assert!(s.dir.dot(n) >= 0.0);
                assert_relative_eq!(s.pdf, pdf(&white, n, s.dir), epsilon = 1e-5);
                // Uniform directions: (cos theta, phi) on a grid of the hemisphere.
                let cos_t = (i as f32 + 0.5) / k as f32;
                let phi = 2.0 * std::f32::consts::PI * (j as f32 + 0.5) / k as f32;
                let sin_t = (1.0 - cos_t * cos_t).sqrt();
                let wi = to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t), n);
                integral +=
                    f64::from(pdf(&white, n, wi)) * 2.0 * std::f64::consts::PI / f64::from(k * k);
            }
        }
        assert_relative_eq!(integral, 1.0, epsilon = 1e-3);
        assert_eq!(pdf(&white, n, -n), 0.0);
        assert_relative_eq!(visible_point_f(&white).x * std::f32::consts::PI, 1.0);
    }

    /// Glass loses nothing: over the number that picks, the chance of reflecting is the
    /// Fresnel term and every flux weight is one, so the expected flux leaving is the flux
    /// arriving; delta lobes report no density.
    #[test]
    fn glass_splits_flux_by_fresnel_and_loses_none() {
        let g = glass(1.5);
        let n = Vec3::Y;
        for cos_i in [1.0f32, 0.6, 0.1] {
            let incoming = Vec3::new((1.0 - cos_i * cos_i).sqrt(), -cos_i, 0.0);
            let (fresnel, _) = fresnel_refract(incoming, n, 1.0 / 1.5);
            let k = 10_000;
            let mut reflected = 0;
            for i in 0..k {
                let u = (i as f32 + 0.5) / k as f32;
                let s = sample(
                    &g,
                    incoming,
                    n,
                    true,
                    (u, (0.5, 0.5)),
                    Transport::Importance,
                );
                assert_eq!(s.weight, Vec3::ONE);
                assert_eq!(s.pdf, 0.0);
                reflected += usize::from(!s.transmitted);
            }
            assert_relative_eq!(reflected as f32 / k as f32, fresnel, epsilon = 1e-3);
        }
        assert!(is_delta(&g));
        assert_eq!(pdf(&g, n, n), 0.0);
    }

    #[test]
    fn the_vectors_cover_every_material_both_lobes_of_glass_and_both_transports() {
        let outcomes: Vec<(BsdfCase, BsdfOutcome)> = test_cases()
            .into_iter()
            .map(|c| (c, c.expected()))
            .collect();
        for kind in [
            material_kind::DIFFUSE,
            material_kind::MIRROR,
            material_kind::GLASS,
        ] {
            assert!(outcomes.iter().any(|(c, _)| c.material.kind == kind));
        }
        let glass: Vec<_> = outcomes
            .iter()
            .filter(|(c, _)| c.material.kind == material_kind::GLASS)
            .collect();
        assert!(glass.iter().any(|(_, o)| o.transmitted == 1));
        assert!(glass.iter().any(|(_, o)| o.transmitted == 0));
        // Inside the denser medium, past the critical angle, glass reflects whatever the number.
        assert!(
            glass
                .iter()
                .any(|(c, o)| c.front == 0 && c.u_lobe > 0.9 && o.transmitted == 0)
        );
        assert!(
            outcomes
                .iter()
                .any(|(c, o)| c.transport == Transport::Radiance as u32
                    && o.weight[0] < 1.0
                    && o.transmitted == 1)
        );
    }
}
