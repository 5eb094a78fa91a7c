//! Every sampler of `ppm_core::bsdf` proved against its density, independently of its own
//! code, as pbrt-v4's and Mitsuba 3's suites prove theirs (their `chi2` tests).
//!
//! Each lobe with a density is drawn [`SAMPLES`] times from a fixed seed over incidences from
//! normal to grazing; its directions are binned over the sphere and scored by Pearson's
//! chi-square against the density's integrals over the bins ([`chi_square`], [`sphere_grid`]),
//! at significance 0.01 over the whole file (Sidak's correction over [`chi_square_cases`]).
//! The same samples show that the density integrates to the share of samples kept, that each
//! weight is the lobe's `f cos / pdf`, and that a white furnace keeps at most what arrives
//! and at least what single scattering is known to keep. Delta lobes are checked by their
//! directions, weights and branch frequencies ([`delta`]), and `wrong_samplers_are_rejected`
//! shows the test has teeth.
//!
//! `cargo test -p ppm-core --release --test bsdf_sampling -- --nocapture` prints each case's
//! statistic, p-value and time.

mod chi_square;
mod delta;
mod sphere_grid;

use chi_square::{Outcome, Rng};
use glam::Vec3;
use ppm_core::bsdf::{self, Transport, rough_glass};
use ppm_core::geometry::Frame;
use ppm_core::layout::{GpuMaterial, material_kind};
use ppm_core::stats::sidak;
use sphere_grid::{Focus, SphereGrid};
use std::f64::consts::PI;
use std::time::Instant;

/// Samples per case: at 2^18 a case takes about a tenth of a second in `--release`, its
/// quadrature included, and a lobe's dense bins expect hundreds of samples each.
const SAMPLES: usize = 1 << 18;

/// Bins along `mu` and `phi` in a hemisphere a lobe reaches, and in one it must leave empty.
const LOBE_BINS: (usize, usize) = (16, 24);
const EMPTY_BINS: (usize, usize) = (2, 4);

/// The view's cosine to the normal, from normal incidence to grazing.
const COSINES: [f32; 6] = [1.0, 0.95, 0.8, 0.5, 0.15, 0.05];

/// The view's azimuth in the local frame: between the tangent and the bitangent and on
/// neither diagonal, so that an anisotropic lobe is seen obliquely.
const VIEW_AZIMUTH: f64 = 1.1;

/// The least share of the light arriving that a white furnace returns, from views at cosines
/// 0.15 and above (`steep`) and at the grazing 0.05. What single scattering on microfacets
/// loses (light that leaves below the surface or meets another facet) grows with roughness
/// (Heitz et al. 2016, "Multiple-scattering microfacet BSDFs with the Smith model"); the
/// bounds are this suite's measurements rounded down by 0.01 to 0.03, so that a change that
/// loses light (a wrong masking term, a dropped lobe) falls below them, as one that makes
/// light fails the upper bound of one.
#[derive(Clone, Copy, Debug)]
struct Keeps {
    steep: f64,
    grazing: f64,
}

impl Keeps {
    fn at(self, cos: f32) -> f64 {
        if cos < 0.15 { self.grazing } else { self.steep }
    }
}

/// Shorthand for the tables.
const fn keeps(steep: f64, grazing: f64) -> Keeps {
    Keeps { steep, grazing }
}

/// Rough conductors' roughness along and across the tangent, isotropic from nearly smooth to
/// the roughest and anisotropic either way round, and what a lossless white one keeps. Seen
/// from above at alpha 1, half the microfacets send light below the surface; seen at grazing
/// angles, the visible microfacets face the view and send it up.
const CONDUCTORS: [((f32, f32), Keeps); 8] = [
    ((0.02, 0.02), keeps(0.985, 0.91)),
    ((0.05, 0.05), keeps(0.93, 0.87)),
    ((0.1, 0.1), keeps(0.87, 0.89)),
    ((0.3, 0.3), keeps(0.8, 0.9)),
    ((0.6, 0.6), keeps(0.57, 0.88)),
    ((1.0, 1.0), keeps(0.3, 0.83)),
    ((0.4, 0.05), keeps(0.82, 0.89)),
    ((0.1, 0.8), keeps(0.61, 0.9)),
];

/// Rough glass's roughness, and what it keeps of a photon's flux seen from outside (index
/// 1.5) and from inside (1 / 1.5), where microfacets past the critical angle reflect light
/// that masking then loses.
const GLASSES: [((f32, f32), Keeps, Keeps); 5] = [
    ((0.05, 0.05), keeps(0.95, 0.89), keeps(0.92, 0.86)),
    ((0.2, 0.2), keeps(0.9, 0.92), keeps(0.8, 0.83)),
    ((0.5, 0.5), keeps(0.82, 0.86), keeps(0.64, 0.69)),
    ((1.0, 1.0), keeps(0.69, 0.78), keeps(0.4, 0.51)),
    ((0.05, 0.4), keeps(0.87, 0.9), keeps(0.74, 0.75)),
];

/// Coats' roughness, and what one over a white base keeps: smooth (a delta reflection over
/// the base's density), which loses nothing, narrow and wide, which lose what single
/// scattering loses on the way in, out and back under the coat (`coat.rs`'s furnace).
const COATS: [(f32, Keeps); 3] = [
    (0.0, keeps(0.995, 0.995)),
    (0.1, keeps(0.87, 0.87)),
    (0.4, keeps(0.56, 0.56)),
];

/// Coats' bases: `(albedo, nonlinear)`. White for the furnace; coloured with either model of
/// the light that returns under the coat, which changes the weights and not the density.
const COAT_BASES: [([f32; 3], bool); 3] = [
    ([1.0; 3], false),
    ([0.7, 0.4, 0.2], false),
    ([0.7, 0.4, 0.2], true),
];

/// The cosine lobes: `sample_visible` on a diffuse and a coated surface, `sample` on a
/// diffuse one.
const COSINE_CASES: usize = 3;

/// The right samplers that `wrong_samplers_are_rejected` scores beside the wrong ones.
const RIGHT_SAMPLERS_IN_TEETH: usize = 2;

/// The number of chi-square tests in this file, over which the significance is shared.
fn chi_square_cases() -> usize {
    let glossy = CONDUCTORS.len() + 2 * GLASSES.len() + COATS.len() * COAT_BASES.len();
    COSINE_CASES + COSINES.len() * glossy + RIGHT_SAMPLERS_IN_TEETH
}

/// The p-value below which one case rejects its sampler: 0.01 over all of them.
fn level() -> f64 {
    sidak(0.01, chi_square_cases())
}

/// How far the quadrature over the bins may be off an integral: five times what
/// `the_quadrature_agrees_with_a_finer_grid` allows where it is hardest.
const QUADRATURE_TOLERANCE: f64 = 1e-4;

/// Standard deviations a binomial count or a mean may stray before a check fails: a chance of
/// 6e-7 each, below the chi-square tests' level.
const Z: f64 = 5.0;

/// The surface the lobes are drawn at: a normal off every axis and a tangent off its basis.
fn surface() -> Frame {
    Frame::with_tangent(
        Vec3::new(0.2, 0.9, -0.1).normalize(),
        Vec3::new(0.3, -0.4, 0.9),
    )
}

/// The unit direction towards the viewer at `cos` to the normal, at [`VIEW_AZIMUTH`].
fn view(frame: &Frame, cos: f32) -> Vec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let azimuth = VIEW_AZIMUTH as f32;
    frame
        .to_world(Vec3::new(sin * azimuth.cos(), sin * azimuth.sin(), cos))
        .normalize()
}

/// Bins crowded at a reflection lobe of `alpha` seen at `cos`: about the mirror direction,
/// which a microfacet tilted by `alpha` turns by twice that.
fn reflection_focus(cos: f32, alpha: f32) -> Focus {
    Focus {
        cos: f64::from(cos),
        azimuth: VIEW_AZIMUTH + PI,
        width: 2.0 * f64::from(alpha),
        bins: LOBE_BINS,
        jump: None,
    }
}

/// The bins for a rough conductor's lobe seen at `cos`, `scale` times finer than the suite's
/// along each axis.
fn conductor_grid((alpha, alpha_v): (f32, f32), cos: f32, scale: usize) -> SphereGrid {
    let upper = reflection_focus(cos, alpha.max(alpha_v));
    SphereGrid::new(
        surface(),
        Focus {
            bins: (upper.bins.0 * scale, upper.bins.1 * scale),
            ..upper
        },
        Focus::uniform(EMPTY_BINS),
    )
}

/// The bins for rough glass seen at `cos` with `eta` the index on the view's side over the
/// far one: above, about the mirror direction; below, about the smooth boundary's refraction
/// (the horizon past the critical angle). A refraction shallower than `|mu| = eta cos` would
/// need a microfacet normal, along `-(eta wo + wi)`, below the horizon: the density drops
/// there from a finite value to zero, and that jump is an edge.
fn glass_grid((alpha, alpha_v): (f32, f32), eta: f32, cos: f32, scale: usize) -> SphereGrid {
    let upper = reflection_focus(cos, alpha.max(alpha_v));
    let upper = Focus {
        bins: (upper.bins.0 * scale, upper.bins.1 * scale),
        ..upper
    };
    let sin_t = eta * (1.0 - cos * cos).sqrt();
    let lower = Focus {
        cos: f64::from((1.0 - sin_t * sin_t).max(0.0).sqrt()),
        width: f64::from(alpha.max(alpha_v)),
        jump: Some(f64::from(eta * cos)),
        ..upper
    };
    SphereGrid::new(surface(), upper, lower)
}

/// A stream per case, from its name.
fn seed(name: &str) -> u64 {
    // FNV-1a.
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `a` and `b` agree within `relative` of the larger.
fn close(a: f32, b: f32, relative: f32) -> bool {
    (a - b).abs() <= relative * a.abs().max(b.abs())
}

/// One sample as a case's checks see it.
struct Drawn {
    /// The direction to bin; `None` where the sampler does not count it (below the surface,
    /// or a delta lobe's).
    dir: Option<Vec3>,
    /// The weight of a counted sample, whose mean must be the integral of the value.
    weight: f64,
}

impl Drawn {
    const LOST: Self = Self {
        dir: None,
        weight: 0.0,
    };
}

/// What a lobe's samples showed, for a case's own checks.
struct Found {
    outcome: Outcome,
    /// The mean of [`Drawn::weight`] over all samples.
    mean_weight: f64,
}

/// Draws one lobe's samples and makes the checks every lobe with a density shares: the
/// chi-square test, no sample where the density is zero, the density integrating to at most
/// one and to the share of samples kept, and the mean weight equal to the integral of the
/// lobe's value (`f cos`) over the sphere. `lobe` gives the density and the value at a
/// direction.
fn check_lobe(
    name: &str,
    grid: &SphereGrid,
    mut draw: impl FnMut(&mut Rng) -> Drawn,
    lobe: impl Fn(Vec3) -> [f64; 2],
) -> Found {
    let start = Instant::now();
    let integrals = grid.integrate(lobe);
    let densities: Vec<f64> = integrals.iter().map(|[p, _]| *p).collect();
    let by_value: f64 = integrals.iter().map(|[_, f]| f).sum();
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    let mut rng = Rng::new(seed(name));
    let draw = |rng: &mut Rng| {
        let d = draw(rng);
        sum += d.weight;
        sum2 += d.weight * d.weight;
        d.dir
    };
    let outcome = chi_square::test_integrals(grid, SAMPLES, &mut rng, draw, &densities);
    let n = SAMPLES as f64;
    let mean_weight = sum / n;
    let standard_error = ((sum2 / n - mean_weight * mean_weight).max(0.0) / n).sqrt();
    let kept = outcome.valid_share();
    println!(
        "{name:<52} chi2 {:>6.1} dof {:>3} p {:.3}  density {:.4} kept {kept:.4}  \
         weight {mean_weight:.4} f_cos {by_value:.4}  {} ms",
        outcome.statistic,
        outcome.dof,
        outcome.p_value,
        outcome.integral,
        start.elapsed().as_millis()
    );
    let worst = outcome.worst.map(|(cell, o, e)| {
        let place = if cell < grid.cells() {
            grid.describe(cell)
        } else {
            "not counted".to_string()
        };
        format!("{o} samples, {e:.1} expected: {place}")
    });
    assert_eq!(
        outcome.stray, 0,
        "{name}: samples where the density is zero"
    );
    assert!(
        outcome.p_value > level(),
        "{name}: the sampler does not draw its density: {outcome:?}; the worst bins: {worst:#?}"
    );
    assert!(
        outcome.integral <= 1.0 + QUADRATURE_TOLERANCE,
        "{name}: the density integrates to {}",
        outcome.integral
    );
    let spread = Z * (kept * (1.0 - kept) / n).sqrt() + QUADRATURE_TOLERANCE;
    assert!(
        (kept - outcome.integral).abs() <= spread,
        "{name}: the density integrates to {}, the sampler keeps {kept}",
        outcome.integral
    );
    let spread = Z * standard_error + QUADRATURE_TOLERANCE * by_value.max(1.0);
    assert!(
        (mean_weight - by_value).abs() <= spread,
        "{name}: the mean weight is {mean_weight}, f cos integrates to {by_value}"
    );
    Found {
        outcome,
        mean_weight,
    }
}

/// A white furnace's check: the mean `weight` over `n` samples is at most one, give or take
/// its noise, and at least `at_least`.
fn assert_furnace(name: &str, weight: f64, weight2: f64, at_least: f64) {
    let n = SAMPLES as f64;
    let mean = weight / n;
    let standard_error = ((weight2 / n - mean * mean).max(0.0) / n).sqrt();
    println!("{name:<52} furnace {mean:.4} +- {standard_error:.4}");
    assert!(
        mean <= 1.0 + Z * standard_error && mean >= at_least,
        "{name}: a white furnace keeps {mean} (at least {at_least})"
    );
}

#[test]
fn cosine_lobes_sample_their_density() {
    let frame = surface();
    let n = frame.normal;
    let grid = SphereGrid::new(frame, Focus::uniform(LOBE_BINS), Focus::uniform(EMPTY_BINS));
    let white = GpuMaterial {
        albedo: [1.0; 3],
        kind: material_kind::DIFFUSE,
        ..bytemuck::Zeroable::zeroed()
    };
    let found = check_lobe(
        "visible point, diffuse",
        &grid,
        |rng| {
            let s = bsdf::sample_visible(&white, n, rng.pair());
            assert_eq!(s.weight, Vec3::ONE);
            assert!((s.pdf - bsdf::visible_point_pdf(n, s.dir)).abs() <= 1e-6);
            Drawn {
                dir: Some(s.dir),
                weight: 1.0,
            }
        },
        |d| {
            let f_cos = bsdf::visible_point_f(&white).x * n.dot(d).max(0.0);
            [bsdf::visible_point_pdf(n, d), f_cos].map(f64::from)
        },
    );
    assert_eq!(found.mean_weight, 1.0, "a white diffuse surface keeps all");

    let coat = bsdf::coated([0.7, 0.4, 0.2], 1.5, 0.3, true);
    check_lobe(
        "visible point, rough coat",
        &grid,
        |rng| {
            let s = bsdf::sample_visible(&coat, n, rng.pair());
            let cos_i = n.dot(s.dir);
            let f = bsdf::visible_point_f(&coat) * bsdf::coat_transmittance(&coat, cos_i);
            let expected = f * std::f32::consts::PI;
            assert!((s.weight - expected).abs().max_element() <= 1e-5, "{s:?}");
            Drawn {
                dir: Some(s.dir),
                weight: f64::from(s.weight.x),
            }
        },
        |d| {
            let cos_i = n.dot(d).max(0.0);
            let f = bsdf::visible_point_f(&coat).x * bsdf::coat_transmittance(&coat, cos_i);
            [bsdf::visible_point_pdf(n, d), f * cos_i].map(f64::from)
        },
    );

    let red = GpuMaterial {
        albedo: [0.6, 0.3, 0.1],
        ..white
    };
    let wo = view(&frame, 0.5);
    check_lobe(
        "diffuse bounce",
        &grid,
        |rng| {
            let u = (rng.uniform(), rng.pair());
            let s = bsdf::sample(&red, -wo, &frame, true, u, Transport::Radiance);
            assert_eq!(s.weight, Vec3::from(red.albedo));
            assert!((s.pdf - bsdf::pdf(&red, &frame, wo, s.dir)).abs() <= 1e-6);
            Drawn {
                dir: Some(s.dir),
                weight: f64::from(s.weight.x),
            }
        },
        |d| {
            let f_cos = bsdf::eval_cos(&red, &frame, wo, d).x;
            [bsdf::pdf(&red, &frame, wo, d), f_cos].map(f64::from)
        },
    );
}

/// A rough conductor: its visible-normal samples against [`bsdf::pdf`], with the weight of
/// each `eval_cos / pdf`, in a white furnace (a lossless metal, `F = 1`, reflectance one).
fn check_conductor(((alpha, alpha_v), keeps): ((f32, f32), Keeps), cos: f32) {
    let name = format!("conductor alpha ({alpha}, {alpha_v}) cos {cos}");
    let metal = GpuMaterial {
        albedo: [1.0; 3],
        alpha_v,
        ..bsdf::conductor([0.0; 3], [1.0; 3], alpha)
    };
    let frame = surface();
    let wo = view(&frame, cos);
    let grid = conductor_grid((alpha, alpha_v), cos, 1);
    // A narrow lobe's density is steep in the half vector, which the evaluation recomputes
    // from the two directions in f32.
    let tolerance = (1e-4 / alpha.min(alpha_v)).max(1e-3);
    let found = check_lobe(
        &name,
        &grid,
        |rng| {
            let u = (rng.uniform(), rng.pair());
            let s = bsdf::sample(&metal, -wo, &frame, true, u, Transport::Radiance);
            if s.weight == Vec3::ZERO {
                return Drawn::LOST;
            }
            let density = bsdf::pdf(&metal, &frame, wo, s.dir);
            let f_cos = bsdf::eval_cos(&metal, &frame, wo, s.dir).x;
            assert!(close(s.pdf, density, tolerance), "{name}: {s:?} {density}");
            assert!(
                close(s.weight.x, f_cos / s.pdf, 2.0 * tolerance),
                "{name}: {s:?} {f_cos}"
            );
            assert!(s.weight.x <= 1.0 + 1e-5, "{name}: {s:?}");
            Drawn {
                dir: Some(s.dir),
                weight: f64::from(s.weight.x),
            }
        },
        |d| {
            let f_cos = bsdf::eval_cos(&metal, &frame, wo, d).x;
            [bsdf::pdf(&metal, &frame, wo, d), f_cos].map(f64::from)
        },
    );
    let n = SAMPLES as f64;
    if cos == 1.0 && alpha == alpha_v {
        // Seen from straight above, the reflection stays above the surface where the
        // microfacet leans less than 45 degrees, whose share of visible normals is
        // 1 / (1 + alpha^2).
        let share = 1.0 / (1.0 + f64::from(alpha * alpha));
        let kept = found.outcome.valid_share();
        let spread = Z * (share * (1.0 - share) / n).sqrt();
        assert!(
            (kept - share).abs() <= spread,
            "{name}: kept {kept}, not {share}"
        );
    }
    // Every weight is at most one (above), so the mean is too.
    let at_least = keeps.at(cos);
    assert!(
        found.mean_weight >= at_least,
        "{name}: a white furnace keeps {} (at least {at_least})",
        found.mean_weight
    );
}

#[test]
fn rough_conductors_sample_their_density() {
    for conductor in &CONDUCTORS[..6] {
        for cos in COSINES {
            check_conductor(*conductor, cos);
        }
    }
}

#[test]
fn anisotropic_conductors_sample_their_density() {
    for conductor in &CONDUCTORS[6..] {
        for cos in COSINES {
            check_conductor(*conductor, cos);
        }
    }
}

/// Rough glass seen from outside (`front`, index 1.5) or inside: reflection with the chance
/// `F` at the microfacet, refraction with `1 - F`, both against [`rough_glass::eval_cos_pdf`];
/// each radiance weight its `f cos / pdf`, each flux weight that without the `eta^2`.
fn check_rough_glass((alpha, alpha_v): (f32, f32), keeps: Keeps, front: bool, cos: f32) {
    let side = if front { "outside" } else { "inside" };
    let name = format!("glass alpha ({alpha}, {alpha_v}) {side} cos {cos}");
    let glass = GpuMaterial {
        kind: material_kind::GLASS,
        ior: 1.5,
        alpha,
        alpha_v,
        ..bytemuck::Zeroable::zeroed()
    };
    let eta = if front { 1.0 / 1.5 } else { 1.5 };
    let frame = surface();
    let wo = view(&frame, cos);
    let grid = glass_grid((alpha, alpha_v), eta, cos, 1);
    // As at a conductor.
    let tolerance = (1e-4 / alpha.min(alpha_v)).max(1e-3);
    let (mut flux, mut flux2) = (0.0f64, 0.0f64);
    check_lobe(
        &name,
        &grid,
        |rng| {
            let u = (rng.uniform(), rng.pair());
            let s = bsdf::sample(&glass, -wo, &frame, front, u, Transport::Radiance);
            let photon = bsdf::sample(&glass, -wo, &frame, front, u, Transport::Importance);
            assert_eq!((s.dir, s.transmitted), (photon.dir, photon.transmitted));
            let scale = if s.transmitted { eta * eta } else { 1.0 };
            assert!(
                close(s.weight.x, photon.weight.x * scale, 1e-6),
                "{name}: {s:?}"
            );
            assert!(photon.weight.x <= 1.0 + 1e-5, "{name}: {photon:?}");
            flux += f64::from(photon.weight.x);
            flux2 += f64::from(photon.weight.x).powi(2);
            if s.weight == Vec3::ZERO {
                return Drawn::LOST;
            }
            let (f_cos, pdf) = rough_glass::eval_cos_pdf(&glass, &frame, front, wo, s.dir);
            assert!(pdf > 0.0, "{name}: {s:?}");
            assert!(
                close(s.weight.x, f_cos / pdf, 2.0 * tolerance),
                "{name}: {s:?} {f_cos} {pdf}"
            );
            Drawn {
                dir: Some(s.dir),
                weight: f64::from(s.weight.x),
            }
        },
        |d| {
            let (f_cos, pdf) = rough_glass::eval_cos_pdf(&glass, &frame, front, wo, d);
            [pdf, f_cos].map(f64::from)
        },
    );
    assert_furnace(&name, flux, flux2, keeps.at(cos));
}

#[test]
fn rough_glass_from_outside_samples_its_density() {
    for (roughness, outside, _) in GLASSES {
        for cos in COSINES {
            check_rough_glass(roughness, outside, true, cos);
        }
    }
}

#[test]
fn rough_glass_from_inside_samples_its_density() {
    for (roughness, _, inside) in GLASSES {
        for cos in COSINES {
            check_rough_glass(roughness, inside, false, cos);
        }
    }
}

/// A coated surface: the coat's reflection with its chance [`bsdf::specular_probability`],
/// else the base's cosine lobe, against [`bsdf::pdf`] (both lobes weighed by their chances).
/// Each weight is its lobe's `f cos / pdf` over its chance, `eval_cos` is the two lobes'
/// sum, and a white base keeps at most what arrives. A smooth coat's reflection is a delta
/// lobe: its samples are not binned (the density is the base's alone), and `delta` checks
/// them.
fn check_coat((alpha, keeps): (f32, Keeps), (albedo, nonlinear): ([f32; 3], bool), cos: f32) {
    let name = format!("coat alpha {alpha} base {albedo:?} nonlinear {nonlinear} cos {cos}");
    let coat = bsdf::coated(albedo, 1.5, alpha, nonlinear);
    let smooth = alpha < bsdf::SMOOTH_ALPHA;
    let frame = surface();
    let n = frame.normal;
    let wo = view(&frame, cos);
    let p = bsdf::specular_probability(&coat, cos);
    let upper = if smooth {
        Focus::uniform(LOBE_BINS)
    } else {
        reflection_focus(cos, alpha)
    };
    let grid = SphereGrid::new(frame, upper, Focus::uniform(EMPTY_BINS));
    // As at a conductor.
    let tolerance = (1e-4 / alpha.max(1e-4)).max(1e-3);
    let (mut all, mut all2) = (0.0f64, 0.0f64);
    check_lobe(
        &name,
        &grid,
        |rng| {
            let u_lobe = rng.uniform();
            let s = bsdf::sample(
                &coat,
                -wo,
                &frame,
                true,
                (u_lobe, rng.pair()),
                Transport::Radiance,
            );
            all += f64::from(s.weight.x);
            all2 += f64::from(s.weight.x).powi(2);
            if u_lobe < p && smooth {
                assert_eq!(s.pdf, 0.0, "{name}: {s:?}");
                return Drawn::LOST;
            }
            if s.weight == Vec3::ZERO {
                return Drawn::LOST;
            }
            let cos_i = n.dot(s.dir);
            let (t_o, t_i) = (
                bsdf::coat_transmittance(&coat, cos),
                bsdf::coat_transmittance(&coat, cos_i),
            );
            let base_f_cos = bsdf::visible_point_f(&coat) * (t_o * t_i * cos_i);
            let base_pdf = bsdf::visible_point_pdf(n, s.dir);
            let (coat_f_cos, coat_pdf) = bsdf::glossy_lobe(&coat, &frame, true, wo, s.dir);
            let expected = if u_lobe < p {
                coat_f_cos / coat_pdf
            } else {
                base_f_cos / ((1.0 - p) * base_pdf)
            };
            let off = (s.weight - expected).abs().max_element();
            assert!(
                off <= 2.0 * tolerance * expected.max_element(),
                "{name}: {s:?} {expected}"
            );
            // The sampler's density is both lobes', and `eval_cos` both lobes' sum.
            let density = (1.0 - p) * base_pdf + p * coat_pdf;
            assert!(close(s.pdf, density, tolerance), "{name}: {s:?} {density}");
            assert!(
                close(s.pdf, bsdf::pdf(&coat, &frame, wo, s.dir), tolerance),
                "{name}"
            );
            let f_cos = bsdf::eval_cos(&coat, &frame, wo, s.dir);
            let sum = base_f_cos + coat_f_cos * p;
            assert!(
                (f_cos - sum).abs().max_element() <= tolerance * sum.max_element(),
                "{name}: eval_cos {f_cos}, the lobes {sum}"
            );
            Drawn {
                dir: Some(s.dir),
                weight: f64::from(s.weight.x),
            }
        },
        |d| {
            let f_cos = bsdf::eval_cos(&coat, &frame, wo, d).x;
            [bsdf::pdf(&coat, &frame, wo, d), f_cos].map(f64::from)
        },
    );
    if albedo == [1.0; 3] {
        assert_furnace(&name, all, all2, keeps.at(cos));
    }
}

#[test]
fn smooth_coats_sample_their_base() {
    for base in COAT_BASES {
        for cos in COSINES {
            check_coat(COATS[0], base, cos);
        }
    }
}

#[test]
fn rough_coats_sample_their_density() {
    for &coat in &COATS[1..] {
        for base in COAT_BASES {
            for cos in COSINES {
                check_coat(coat, base, cos);
            }
        }
    }
}

/// Directions of the cosine-power lobe `(e + 1) / (2 pi) cos^e` about `frame`'s normal, by
/// inverting its distribution: a sampler that is right for `e = 1` and wrong elsewhere.
fn cosine_power(frame: &Frame, exponent: f32, u: (f32, f32)) -> Vec3 {
    let cos = (1.0 - u.0).powf(1.0 / (exponent + 1.0));
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.1;
    frame.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
}

/// The test has teeth: at the seeds the suite uses, a GGX conductor sampled with a roughness
/// a quarter off the one whose density is scored, a cosine lobe sampled with the exponent
/// 1.25, and an anisotropic lobe sampled with its axes swapped are rejected, while the right
/// samplers pass.
#[test]
fn wrong_samplers_are_rejected() {
    let level = level();
    let frame = surface();
    let metal = |alpha: f32, alpha_v: f32| GpuMaterial {
        albedo: [1.0; 3],
        alpha_v,
        ..bsdf::conductor([0.0; 3], [1.0; 3], alpha)
    };
    let run =
        |name: &str, grid: &SphereGrid, drawn: &GpuMaterial, scored: &GpuMaterial, wo: Vec3| {
            let start = Instant::now();
            let outcome = chi_square::test(
                grid,
                SAMPLES,
                &mut Rng::new(seed(name)),
                |rng| {
                    let u = (rng.uniform(), rng.pair());
                    let s = bsdf::sample(drawn, -wo, &frame, true, u, Transport::Radiance);
                    (s.weight != Vec3::ZERO).then_some(s.dir)
                },
                |d| f64::from(bsdf::pdf(scored, &frame, wo, d)),
            );
            println!(
                "{name:<52} chi2 {:>6.1} dof {:>3} p {:.3e}  {} ms",
                outcome.statistic,
                outcome.dof,
                outcome.p_value,
                start.elapsed().as_millis()
            );
            outcome.p_value
        };
    let (alpha, cos) = (0.3, 0.5);
    let wo = view(&frame, cos);
    let grid = conductor_grid((alpha, alpha), cos, 1);
    let right = metal(alpha, alpha);
    for (scale, is_right) in [(1.0, true), (1.25, false), (0.8, false)] {
        let name = format!("teeth: GGX {alpha} drawn with {}", alpha * scale);
        let p = run(
            &name,
            &grid,
            &metal(alpha * scale, alpha * scale),
            &right,
            wo,
        );
        assert_eq!(p > level, is_right, "{name}: p {p}, level {level}");
    }
    let (wide, narrow) = (0.4, 0.05);
    let grid = conductor_grid((wide, narrow), cos, 1);
    let name = "teeth: GGX (0.4, 0.05) drawn as (0.05, 0.4)";
    let p = run(name, &grid, &metal(narrow, wide), &metal(wide, narrow), wo);
    assert!(p < level, "{name}: p {p}, level {level}");

    let grid = SphereGrid::new(frame, Focus::uniform(LOBE_BINS), Focus::uniform(EMPTY_BINS));
    for (exponent, is_right) in [(1.0, true), (1.25, false)] {
        let name = format!("teeth: cosine lobe drawn as cos^{exponent}");
        let start = Instant::now();
        let outcome = chi_square::test(
            &grid,
            SAMPLES,
            &mut Rng::new(seed(&name)),
            |rng| Some(cosine_power(&frame, exponent, rng.pair())),
            |d| f64::from(bsdf::visible_point_pdf(frame.normal, d)),
        );
        println!(
            "{name:<52} chi2 {:>6.1} dof {:>3} p {:.3e}  {} ms",
            outcome.statistic,
            outcome.dof,
            outcome.p_value,
            start.elapsed().as_millis()
        );
        assert_eq!(outcome.p_value > level, is_right, "{name}: {outcome:?}");
    }
}

/// The bins' quadrature has converged where it is hardest (narrow and anisotropic lobes at
/// grazing views, rough glass's refraction ending with a jump and at the critical angle):
/// a grid three times finer along each axis gives the same integrals, within a tenth of the
/// binomial noise of the share of samples kept.
#[test]
fn the_quadrature_agrees_with_a_finer_grid() {
    let frame = surface();
    let glass = |(alpha, alpha_v): (f32, f32)| GpuMaterial {
        kind: material_kind::GLASS,
        ior: 1.5,
        alpha,
        alpha_v,
        ..bytemuck::Zeroable::zeroed()
    };
    for (roughness, front, cos) in [
        ((0.05, 0.4), true, 0.05),
        ((1.0, 1.0), false, 0.2),
        ((0.05, 0.05), true, 0.2),
        ((0.2, 0.2), false, 0.5),
    ] {
        let (m, wo) = (glass(roughness), view(&frame, cos));
        let eta = if front { 1.0 / 1.5 } else { 1.5 };
        let density = |d| {
            [f64::from(
                rough_glass::eval_cos_pdf(&m, &frame, front, wo, d).1,
            )]
        };
        let integral = |scale| -> f64 {
            glass_grid(roughness, eta, cos, scale)
                .integrate(density)
                .iter()
                .map(|[p]| p)
                .sum()
        };
        let (coarse, fine) = (integral(1), integral(3));
        assert!(
            (coarse - fine).abs() < 2e-5,
            "glass {roughness:?} {front} {cos}: {coarse} {fine}"
        );
    }
    for (roughness, cos) in [((0.4, 0.05), 0.05), ((0.02, 0.02), 0.2), ((1.0, 1.0), 0.05)] {
        let m = GpuMaterial {
            albedo: [1.0; 3],
            alpha_v: roughness.1,
            ..bsdf::conductor([0.0; 3], [1.0; 3], roughness.0)
        };
        let wo = view(&frame, cos);
        let density = |d| [f64::from(bsdf::pdf(&m, &frame, wo, d))];
        let integral = |scale| -> f64 {
            conductor_grid(roughness, cos, scale)
                .integrate(density)
                .iter()
                .map(|[p]| p)
                .sum()
        };
        let (coarse, fine) = (integral(1), integral(3));
        assert!(
            (coarse - fine).abs() < 2e-5,
            "conductor {roughness:?} {cos}: {coarse} {fine}"
        );
    }
}
