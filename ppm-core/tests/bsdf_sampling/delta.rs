//! Delta lobes, which have no density to test against: each sampled direction is the mirror
//! image or obeys Snell's law, each weight is the lobe's reflectance or transmittance, and
//! where the sampler picks a branch by a number, it picks each as often as it should
//! (a binomial bound over many draws).

use super::chi_square::Rng;
use super::{COAT_BASES, COSINES, Z, seed, surface, view};
use glam::Vec3;
use ppm_core::bsdf::{self, Transport};
use ppm_core::geometry::Frame;
use ppm_core::layout::{GpuMaterial, material_kind};

/// Draws per incidence for a branch's frequency: its binomial bound is then within 0.02.
const DRAWS: usize = 20_000;

/// The mirror image of the view `wo` about `frame`'s normal, in f64.
fn mirror_image(frame: &Frame, wo: Vec3) -> Vec3 {
    let (n, wo) = (frame.normal.as_dvec3(), wo.as_dvec3());
    (n * (2.0 * n.dot(wo)) - wo).as_vec3()
}

/// Fresnel reflectance of a smooth boundary between indices `n1` (the light's side) and
/// `n2` for unpolarised light at `cos_i`: one past the critical angle.
fn fresnel(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (s * s + p * p)
}

/// `count` of `DRAWS` is what a binomial with chance `p` gives, within [`Z`] standard
/// deviations (and exactly where the chance is nought or one).
fn assert_frequency(name: &str, count: usize, p: f64) {
    let (n, k) = (DRAWS as f64, count as f64);
    let spread = Z * (n * p * (1.0 - p)).sqrt();
    assert!(
        (k - n * p).abs() <= spread,
        "{name}: {count} of {DRAWS}, expected {}",
        n * p
    );
}

/// `a` and `b` are the same direction within `1e-5`.
fn same_direction(a: Vec3, b: Vec3) -> bool {
    (a - b).length() <= 1e-5
}

#[test]
fn a_mirror_reflects_with_its_albedo() {
    let mirror = GpuMaterial {
        albedo: [0.9, 0.7, 0.3],
        kind: material_kind::MIRROR,
        ..bytemuck::Zeroable::zeroed()
    };
    assert!(bsdf::is_delta(&mirror));
    let frame = surface();
    let mut rng = Rng::new(seed("mirror"));
    for cos in COSINES {
        let wo = view(&frame, cos);
        for _ in 0..64 {
            let u = (rng.uniform(), rng.pair());
            for transport in [Transport::Radiance, Transport::Importance] {
                let s = bsdf::sample(&mirror, -wo, &frame, true, u, transport);
                assert!(
                    same_direction(s.dir, mirror_image(&frame, wo)),
                    "{cos}: {s:?}"
                );
                assert_eq!(s.weight, Vec3::from(mirror.albedo));
                assert_eq!((s.pdf, s.transmitted), (0.0, false));
            }
        }
    }
}

#[test]
fn a_smooth_conductor_reflects_its_fresnel_term() {
    let gold = bsdf::conductor([0.18, 0.42, 1.37], [3.42, 2.35, 1.77], 0.0);
    assert!(bsdf::is_delta(&gold));
    let frame = surface();
    let mut rng = Rng::new(seed("smooth conductor"));
    for cos in COSINES {
        let wo = view(&frame, cos);
        let u = (rng.uniform(), rng.pair());
        let s = bsdf::sample(&gold, -wo, &frame, true, u, Transport::Radiance);
        assert!(
            same_direction(s.dir, mirror_image(&frame, wo)),
            "{cos}: {s:?}"
        );
        let expected = Vec3::from(gold.albedo) * bsdf::conductor_fresnel(&gold, cos);
        assert!(
            (s.weight - expected).abs().max_element() <= 1e-5,
            "{cos}: {s:?}"
        );
        assert_eq!((s.pdf, s.transmitted), (0.0, false));
    }
}

/// Smooth glass of index 1.5 from outside and inside: it reflects as often as the Fresnel
/// term says (always past the critical angle inside), into the mirror image; it refracts by
/// Snell's law, on in the plane of incidence, and scales radiance by `(eta_i / eta_t)^2` and
/// flux by one.
#[test]
fn smooth_glass_reflects_by_fresnel_and_refracts_by_snell() {
    let glass = GpuMaterial {
        kind: material_kind::GLASS,
        ior: 1.5,
        ..bytemuck::Zeroable::zeroed()
    };
    assert!(bsdf::is_delta(&glass));
    let frame = surface();
    let n = frame.normal;
    let mut total_reflections = 0;
    for front in [true, false] {
        let (n1, n2) = if front { (1.0, 1.5) } else { (1.5, 1.0) };
        let mut rng = Rng::new(seed(&format!("smooth glass {front}")));
        for cos in COSINES {
            let name = format!("smooth glass front {front} cos {cos}");
            let wo = view(&frame, cos);
            let cos_i = f64::from(n.dot(wo));
            let sin_i = (1.0 - cos_i * cos_i).sqrt();
            // The view's part along the surface, which a refraction turns away from.
            let along = (n * n.dot(wo) - wo).normalize_or_zero();
            let mut reflected = 0;
            for _ in 0..DRAWS {
                let u = (rng.uniform(), rng.pair());
                let s = bsdf::sample(&glass, -wo, &frame, front, u, Transport::Radiance);
                let photon = bsdf::sample(&glass, -wo, &frame, front, u, Transport::Importance);
                assert_eq!((s.dir, s.transmitted), (photon.dir, photon.transmitted));
                assert_eq!((s.pdf, photon.pdf), (0.0, 0.0));
                if !s.transmitted {
                    assert!(
                        same_direction(s.dir, mirror_image(&frame, wo)),
                        "{name}: {s:?}"
                    );
                    assert_eq!((s.weight, photon.weight), (Vec3::ONE, Vec3::ONE));
                    reflected += 1;
                    continue;
                }
                let cos_t = -f64::from(n.dot(s.dir));
                assert!(
                    cos_t > 0.0,
                    "{name}: a refraction stays on the near side: {s:?}"
                );
                let tangential = s.dir + n * cos_t as f32;
                let sin_t = f64::from(tangential.length());
                assert!((n2 * sin_t - n1 * sin_i).abs() <= 1e-5, "{name}: {s:?}");
                if sin_i > 1e-3 {
                    let turn = tangential.normalize().dot(along);
                    assert!(
                        turn > 1.0 - 1e-5,
                        "{name}: out of the plane of incidence: {s:?}"
                    );
                }
                let eta2 = ((n1 / n2) * (n1 / n2)) as f32;
                assert!(
                    (s.weight - Vec3::splat(eta2)).abs().max_element() <= 1e-6,
                    "{name}"
                );
                assert_eq!(photon.weight, Vec3::ONE, "{name}");
            }
            let chance = fresnel(cos_i, n1, n2);
            if chance == 1.0 {
                assert_eq!(reflected, DRAWS, "{name}: past the critical angle");
                total_reflections += 1;
            }
            assert_frequency(&name, reflected, chance);
        }
    }
    // From inside, 0.5, 0.15 and 0.05 lie past the critical cosine sqrt(1 - 1 / 1.5^2) = 0.745.
    assert_eq!(total_reflections, 3);
}

/// A smooth coat takes its mirror reflection with the chance [`bsdf::specular_probability`],
/// Mitsuba 3's rule (the Fresnel term weighed by `coat_specular_weight` against the
/// transmittance weighed by the rest), with the weight `F / p`, so that it reflects `F` on
/// average; every other sample is the base's and has a density (`check_coat` bins those).
#[test]
fn a_smooth_coat_reflects_as_often_as_its_specular_probability() {
    let frame = surface();
    for (albedo, nonlinear) in COAT_BASES {
        let coat = bsdf::coated(albedo, 1.5, 0.0, nonlinear);
        let mut rng = Rng::new(seed(&format!("smooth coat {albedo:?} {nonlinear}")));
        for cos in COSINES {
            let name = format!("smooth coat {albedo:?} nonlinear {nonlinear} cos {cos}");
            let wo = view(&frame, cos);
            let f = fresnel(f64::from(cos), 1.0, 1.5);
            let w = f64::from(coat.coat_specular_weight);
            let p = f64::from(bsdf::specular_probability(&coat, cos));
            let rule = f * w / (f * w + (1.0 - f) * (1.0 - w));
            assert!((p - rule).abs() <= 1e-5, "{name}: {p} against {rule}");
            let mut reflected = 0;
            for _ in 0..DRAWS {
                let u_lobe = rng.uniform();
                let u = (u_lobe, rng.pair());
                let s = bsdf::sample(&coat, -wo, &frame, true, u, Transport::Radiance);
                let delta = s.pdf == 0.0;
                assert_eq!(delta, f64::from(u_lobe) < p, "{name}: {s:?}");
                if delta {
                    assert!(
                        same_direction(s.dir, mirror_image(&frame, wo)),
                        "{name}: {s:?}"
                    );
                    let weight = (f / p) as f32;
                    assert!((s.weight - Vec3::splat(weight)).abs().max_element() <= 1e-4 * weight);
                    reflected += 1;
                }
            }
            assert_frequency(&name, reflected, p);
        }
    }
}
