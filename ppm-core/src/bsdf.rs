//! What each material does with light, in one place: the eye, photon, direct-light and gather
//! passes, the reference path tracer and local mode's probes all ask here, and backend-wgpu's
//! `bsdf.wgsl` is the twin, pinned to this module by [`test_cases`] (docs/algorithm.md 1, "Materials").
//!
//! Materials fall in three families. **Delta** materials (mirror, glass, a smooth conductor)
//! scatter into one or two directions: paths continue through them, and no density exists
//! to evaluate or to weight against light sampling. **Diffuse** materials scatter over the
//! hemisphere with `f = albedo / pi`: an eye path stops at the first one (its visible point),
//! a photon is stored there. Because `f` is the same for every pair of directions on such a
//! surface, slots and photons store no direction. **Glossy** materials (a rough conductor:
//! GGX microfacets, Walter et al. 2007, sampled by their visible normals, Heitz 2018) have a
//! density but a lobe too narrow for a photon disc: eye and photon paths continue through
//! them by sampling it, as through a delta surface, and sample the lights there too
//! ([`glossy_lobe`]; the reference path tracer with [`eval_cos`]); docs/algorithm.md 1,
//! "Materials", says why.
//!
//! Directions follow the passes: `incoming` is the unit direction a path travels (towards
//! the surface), `facing` the unit normal on its side (a glossy lobe's [`Frame`], whose
//! tangent orients an anisotropic roughness, holds it as `normal`), and every sampled
//! direction leaves the surface.

mod coat;
pub mod rough_glass;

pub use coat::{
    NODES as COAT_NODES, arrival, coat_tables, dielectric_fresnel, specular_probability,
    transmittance as coat_transmittance,
};

use crate::geometry::{Frame, fresnel_refract, reflect, to_world};
use crate::layout::{GpuMaterial, material_kind};
use crate::sampling::cosine_hemisphere;
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// GGX roughness below which a conductor is smooth: a narrower lobe renders as a delta one,
/// and its density (up to `1 / (pi alpha^2)`) would only add rounding (pbrt-v4's
/// `EffectivelySmooth` uses the same bound).
pub const SMOOTH_ALPHA: f32 = 1e-3;

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

/// Whether the material scatters into single directions (mirror, glass, a smooth conductor):
/// no density exists to weight against light sampling.
#[inline]
pub fn is_delta(material: &GpuMaterial) -> bool {
    match material.kind {
        material_kind::MIRROR => true,
        material_kind::GLASS | material_kind::CONDUCTOR => {
            material.alpha.max(material.alpha_v) < SMOOTH_ALPHA
        }
        _ => false,
    }
}

/// The GGX roughness of a compiled material along and across its tangent.
#[inline]
fn roughness(material: &GpuMaterial) -> Vec2 {
    Vec2::new(material.alpha, material.alpha_v)
}

/// Whether the material's lobe depends on the tangent: a rough conductor or glass whose two
/// roughnesses differ. Only then does a pass need the surface's tangent ([`Frame`]).
#[inline]
pub fn is_anisotropic(material: &GpuMaterial) -> bool {
    material.alpha != material.alpha_v && !is_delta(material)
}

/// A material's roughness along and across its tangent as the compiled record holds it:
/// both as given where the surface is smooth (both below [`SMOOTH_ALPHA`]) or isotropic,
/// else each at least 1e-4, so that a lobe smooth in one direction only keeps a finite
/// density (pbrt-v4's `TrowbridgeReitzDistribution` does the same).
pub fn roughness_pair(alpha: f32, alpha_v: f32) -> (f32, f32) {
    if alpha.max(alpha_v) < SMOOTH_ALPHA || alpha == alpha_v {
        return (alpha, alpha_v);
    }
    (alpha.max(1e-4), alpha_v.max(1e-4))
}

/// The frame `material`'s lobe is evaluated in on a surface facing `facing`:
/// [`Frame::around`] it, but where the material is anisotropic, whose tangent follows the
/// surface's `u_direction` (asked only then: [`SurfaceTextures::frame`](crate::textures::SurfaceTextures::frame)).
#[inline]
pub fn frame(material: &GpuMaterial, facing: Vec3, u_direction: impl FnOnce() -> Vec3) -> Frame {
    if is_anisotropic(material) {
        Frame::with_tangent(facing, u_direction())
    } else {
        Frame::around(facing)
    }
}

/// Whether [`eval_cos`] and [`pdf`] describe the surface's bounces, so that light samples
/// can be weighed against them: every non-delta surface but a rough dielectric, whose
/// Fresnel term depends on the side a path is on, which neither takes. Its bounces report
/// no density; [`rough_glass::eval_cos_pdf`] gives it, side included.
#[inline]
pub fn samples_lights(material: &GpuMaterial) -> bool {
    !is_delta(material) && material.kind != material_kind::GLASS
}

/// Whether an eye path that continues through the material does so by a glossy lobe with a
/// density ([`glossy_lobe`]), so that the eye pass samples the lights there: a rough
/// conductor, a rough coat's reflection, rough glass.
#[inline]
pub fn chain_samples_lights(material: &GpuMaterial) -> bool {
    match material.kind {
        material_kind::CONDUCTOR | material_kind::GLASS => !is_delta(material),
        material_kind::COATED => !coat::is_smooth(material),
        _ => false,
    }
}

/// The lobe an eye path continues by at a surface where [`chain_samples_lights`], arriving
/// from `wo` on the side of `frame.normal` (`front`: the outside): `f cos` at `wi` over the chance
/// of taking that lobe (a coat's reflection; one elsewhere), and the density with which
/// [`sample`] draws `wi` within it, for weighing a light sample against the path's own
/// bounce. `wi` may lie below the surface only at rough glass (a refraction, whose value
/// carries the radiance's `eta^2`, [`rough_glass::eval_cos_pdf`]). Zero where the lobe
/// cannot reach `wi` and on every other material.
pub fn glossy_lobe(
    material: &GpuMaterial,
    frame: &Frame,
    front: bool,
    wo: Vec3,
    wi: Vec3,
) -> (Vec3, f32) {
    if !chain_samples_lights(material) {
        return (Vec3::ZERO, 0.0);
    }
    if material.kind == material_kind::GLASS {
        let (f_cos, pdf) = rough_glass::eval_cos_pdf(material, frame, front, wo, wi);
        return (Vec3::splat(f_cos), pdf);
    }
    if frame.normal.dot(wo) <= 0.0 || frame.normal.dot(wi) <= 0.0 {
        return (Vec3::ZERO, 0.0);
    }
    match material.kind {
        material_kind::COATED => coat::reflection_lobe(material, frame, wo, wi),
        _ => (
            eval_cos(material, frame, wo, wi),
            pdf(material, frame, wo, wi),
        ),
    }
}

/// Whether the material is a rough dielectric ([`rough_glass`]).
#[inline]
pub fn is_rough_glass(material: &GpuMaterial) -> bool {
    material.kind == material_kind::GLASS && !is_delta(material)
}

/// Whether photons are stored on the material and eye paths may stop there (its visible
/// points): diffuse and coated materials. Paths continue through every other one by
/// [`sample`], and through a coat when they take its reflection.
#[inline]
pub fn holds_visible_points(material: &GpuMaterial) -> bool {
    matches!(
        material.kind,
        material_kind::DIFFUSE | material_kind::COATED
    )
}

/// Whether an eye path arriving from `wo` stops on the material, and the factor on its
/// throughput there: always, with one, on a diffuse surface; on a coated one when `u_lobe`
/// takes the base, with the coat's transmittance over that chance; never elsewhere.
#[inline]
pub fn visible_point_weight(
    material: &GpuMaterial,
    facing: Vec3,
    wo: Vec3,
    u_lobe: f32,
) -> Option<f32> {
    match material.kind {
        material_kind::DIFFUSE => Some(1.0),
        material_kind::COATED => coat::visible_point_weight(material, facing.dot(wo), u_lobe),
        _ => None,
    }
}

/// The part of the BSDF `f` at a visible point (or a photon's surface) that is the same for
/// every pair of directions on the facing side: `albedo / pi` on a diffuse surface; on a
/// coated one, the base's share, which [`arrival`] at each direction completes (the eye pass
/// holds it for `wo`, the photon and direct-light passes apply it for `wi`).
#[inline]
pub fn visible_point_f(material: &GpuMaterial) -> Vec3 {
    if material.kind == material_kind::COATED {
        coat::base_f(material)
    } else {
        Vec3::from(material.albedo) * FRAC_1_PI
    }
}

/// Solid-angle density with which [`sample_visible`] draws `wi` at a visible point with
/// facing normal `facing` (the cosine lobe); zero below the surface.
#[inline]
pub fn visible_point_pdf(facing: Vec3, wi: Vec3) -> f32 {
    facing.dot(wi).max(0.0) * FRAC_1_PI
}

/// The BSDF times the cosine at `wi`, `f(wo, wi) cos_i`, of a non-delta surface: `wo` towards
/// where the path came from and `wi` towards where light comes from, both unit and on the
/// side of `frame.normal` (zero otherwise); zero for delta materials. With the cosine, since
/// `f` alone of a rough lobe exceeds f32 between two grazing directions where the product
/// does not.
pub fn eval_cos(material: &GpuMaterial, frame: &Frame, wo: Vec3, wi: Vec3) -> Vec3 {
    let (cos_o, cos_i) = (frame.normal.dot(wo), frame.normal.dot(wi));
    if cos_o <= 0.0 || cos_i <= 0.0 || !samples_lights(material) {
        return Vec3::ZERO;
    }
    match material.kind {
        material_kind::CONDUCTOR => {
            let (lobe, h) = ggx_reflection_cos(roughness(material), frame, wo, wi);
            Vec3::from(material.albedo) * conductor_fresnel(material, wo.dot(h)) * lobe
        }
        material_kind::COATED => coat::eval_cos(material, frame, wo, wi),
        _ => visible_point_f(material) * cos_i,
    }
}

/// The GGX reflection lobe without its Fresnel term, `D G2 / (4 cos_o cos_i)` times
/// `cos_i`, and the half vector, for `wo` and `wi` above the surface.
fn ggx_reflection_cos(alpha: Vec2, frame: &Frame, wo: Vec3, wi: Vec3) -> (f32, Vec3) {
    let (local_o, local_i) = (frame.to_local(wo), frame.to_local(wi));
    let (cos_o, cos_i) = (local_o.z, local_i.z);
    let h = half_vector(wo, wi);
    let d = ggx_d(alpha, frame.to_local(h));
    // G2 / (4 cos_o cos_i) times cos_i, with cos_i cancelled.
    let (root_o, root_i) = (smith_root(alpha, local_o), smith_root(alpha, local_i));
    let visibility_cos = 0.5 * cos_i / (cos_i * root_o + cos_o * root_i);
    (d * visibility_cos, h)
}

/// Solid-angle density with which [`sample`] draws `wi` given `wo` at a non-delta surface
/// ([`eval_cos`]'s conventions); zero for delta materials.
pub fn pdf(material: &GpuMaterial, frame: &Frame, wo: Vec3, wi: Vec3) -> f32 {
    let (cos_o, cos_i) = (frame.normal.dot(wo), frame.normal.dot(wi));
    if cos_o <= 0.0 || cos_i <= 0.0 || !samples_lights(material) {
        return 0.0;
    }
    match material.kind {
        material_kind::CONDUCTOR => ggx_pdf(roughness(material), frame, wo, wi),
        material_kind::COATED => coat::pdf(material, frame, wo, wi),
        _ => visible_point_pdf(frame.normal, wi),
    }
}

/// The density of `wi` drawn by [`visible_normal`] from `wo`, both above the surface.
fn ggx_pdf(alpha: Vec2, frame: &Frame, wo: Vec3, wi: Vec3) -> f32 {
    ggx_reflection_pdf(
        alpha,
        frame.to_local(wo),
        ggx_d(alpha, frame.to_local(half_vector(wo, wi))),
    )
}

/// The GGX distribution of normals `D(m)` of the microfacet normal `m` in the surface's local
/// frame, `1 / (pi a_u a_v ((x / a_u)^2 + (y / a_v)^2 + z^2)^2)`: from the tangential
/// components rather than `1 - cos^2`, which loses a narrow lobe's width to rounding in f32.
#[inline]
fn ggx_d(alpha: Vec2, m: Vec3) -> f32 {
    let (sx, sy) = (m.x / alpha.x, m.y / alpha.y);
    let d = sx * sx + sy * sy + m.z * m.z;
    1.0 / (PI * alpha.x * alpha.y * d * d)
}

/// The unit half vector of `wo` and `wi`, both above the surface: their sum scaled to its
/// largest component before normalising, since at grazing angles its squared length
/// underflows in f32.
#[inline]
fn half_vector(wo: Vec3, wi: Vec3) -> Vec3 {
    let sum = wo + wi;
    (sum / sum.abs().max_element()).normalize()
}

/// `cos sqrt(1 + alpha^2 tan^2)` of the unit direction `w` in the local frame, the root of
/// Smith's masking for GGX, with `alpha^2 sin^2 = (a_u w_x)^2 + (a_v w_y)^2` the roughness
/// along `w`'s azimuth: written without dividing by `cos`, so finite at grazing angles,
/// where `tan` overflows. Smith's height-correlated masking and shadowing is `G2 = 2 cos_o
/// cos_i / (cos_i root_o + cos_o root_i)`, its one-direction masking `G1 = 2 cos / (cos +
/// root)`.
#[inline]
fn smith_root(alpha: Vec2, w: Vec3) -> f32 {
    let (x, y) = (alpha.x * w.x, alpha.y * w.y);
    (w.z * w.z + x * x + y * y).sqrt()
}

/// The density of a reflection drawn from the visible normals for `local_o`: `D_wo(m) =
/// G1(wo) (wo.m) D(m) / cos_o` times the reflection's Jacobian `1 / (4 wo.m)`; with Smith's
/// masking `G1 = 2 cos_o / (cos_o + root_o)` that is `D / (2 (cos_o + root_o))`.
#[inline]
fn ggx_reflection_pdf(alpha: Vec2, local_o: Vec3, d: f32) -> f32 {
    d / (2.0 * (local_o.z + smith_root(alpha, local_o)))
}

/// Fresnel reflectance of a conductor of complex index `eta + i k` (per channel) for
/// unpolarised light from outside at `cos_i` to the (micro)normal.
pub fn conductor_fresnel(material: &GpuMaterial, cos_i: f32) -> Vec3 {
    let (eta, k) = (Vec3::from(material.eta), Vec3::from(material.k));
    Vec3::new(
        complex_fresnel(cos_i, eta.x, k.x),
        complex_fresnel(cos_i, eta.y, k.y),
        complex_fresnel(cos_i, eta.z, k.z),
    )
}

/// One channel of [`conductor_fresnel`], with the index as `n = eta + i k`:
/// `r_s = (cos_i - n cos_t) / (cos_i + n cos_t)`, `r_p = (n cos_i - cos_t) / (n cos_i + cos_t)`,
/// `n cos_t = sqrt(n^2 - sin_i^2)`.
fn complex_fresnel(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2 = 1.0 - cos_i * cos_i;
    // n^2 - sin^2 and its principal square root `(a, b)`.
    let (re, im) = (eta * eta - k * k - sin2, 2.0 * eta * k);
    let modulus = (re * re + im * im).sqrt();
    let a = (0.5 * (modulus + re)).max(0.0).sqrt();
    let b = (0.5 * (modulus - re)).max(0.0).sqrt().copysign(im);
    // |r_s|^2 with n cos_t = a + i b.
    let rs = ((cos_i - a).powi(2) + b * b) / ((cos_i + a).powi(2) + b * b).max(f32::MIN_POSITIVE);
    // |r_p|^2 = |n^2 cos_i - n cos_t|^2 / |n^2 cos_i + n cos_t|^2 with n^2 = (eta^2 - k^2) + i 2 eta k.
    let (n2_re, n2_im) = ((eta * eta - k * k) * cos_i, 2.0 * eta * k * cos_i);
    let num = (n2_re - a).powi(2) + (n2_im - b).powi(2);
    let den = (n2_re + a).powi(2) + (n2_im + b).powi(2);
    let rp = num / den.max(f32::MIN_POSITIVE);
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// The stretched view direction's cosine from which [`visible_normal`] takes a fixed frame.
const NEAR_NORMAL: f32 = 0.99999;

/// A microfacet normal drawn from GGX's normals visible from `wo` (Heitz 2018), in `frame`'s
/// coordinates and in world space: the hemisphere of the stretched view direction, its
/// projected disc warped to the visible part, then unstretched.
fn visible_normal(alpha: Vec2, frame: &Frame, wo: Vec3, u: (f32, f32)) -> (Vec3, Vec3) {
    let local_o = frame.to_local(wo);
    let v = Vec3::new(alpha.x * local_o.x, alpha.y * local_o.y, local_o.z).normalize();
    // Any frame about `v` will do, but one taken from tangential components that are
    // rounding noise near normal incidence would differ between backends (pbrt-v4's
    // bound).
    let t1 = if v.z < NEAR_NORMAL {
        Vec3::new(-v.y, v.x, 0.0) / (v.x * v.x + v.y * v.y).sqrt()
    } else {
        Vec3::X
    };
    let t2 = v.cross(t1);
    let r = u.0.sqrt();
    let phi = 2.0 * PI * u.1;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + v.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + v * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let m = Vec3::new(alpha.x * nh.x, alpha.y * nh.y, nh.z.max(0.0)).normalize();
    (m, frame.to_world(m))
}

/// Smith's `G2 / G1(wo)` for GGX at the local directions `local_o` and `local_i` (the latter
/// on either side: its cosine's magnitude counts), in the form that cancels `cos_o`: the
/// weight of a direction drawn from the visible normals, less its Fresnel term.
#[inline]
fn ggx_g2_over_g1(alpha: Vec2, local_o: Vec3, local_i: Vec3) -> f32 {
    let (cos_o, cos_i) = (local_o.z, local_i.z.abs());
    let (root_o, root_i) = (smith_root(alpha, local_o), smith_root(alpha, local_i));
    cos_i * (cos_o + root_o) / (cos_i * root_o + cos_o * root_i)
}

/// A reflection off a GGX microfacet drawn by [`visible_normal`].
struct GgxReflection {
    /// The direction, above the surface.
    dir: Vec3,
    /// The microfacet normal, the Fresnel term's.
    h: Vec3,
    /// `f cos / pdf` less the Fresnel term: `G2 / G1(wo)`; zero for a direction below the
    /// surface, which ends the path.
    g2_over_g1: f32,
    /// The direction's density; zero below the surface.
    pdf: f32,
}

/// Draws a [`GgxReflection`] for `wo`.
fn sample_ggx_reflection(alpha: Vec2, frame: &Frame, wo: Vec3, u: (f32, f32)) -> GgxReflection {
    let (m, h) = visible_normal(alpha, frame, wo, u);
    let dir = reflect(-wo, h);
    let (local_o, local_i) = (frame.to_local(wo), frame.to_local(dir));
    let above = local_o.z > 0.0 && local_i.z > 0.0;
    GgxReflection {
        dir,
        h,
        g2_over_g1: if above {
            ggx_g2_over_g1(alpha, local_o, local_i)
        } else {
            0.0
        },
        pdf: if above {
            ggx_reflection_pdf(alpha, local_o, ggx_d(alpha, m))
        } else {
            0.0
        },
    }
}

/// Draws a direction from a rough conductor's visible normals for `wo` towards where the
/// path came from; the weight is `albedo F G2 / G1(wo)`, zero below the surface.
fn sample_conductor(material: &GpuMaterial, frame: &Frame, wo: Vec3, u: (f32, f32)) -> BsdfSample {
    let r = sample_ggx_reflection(roughness(material), frame, wo, u);
    BsdfSample {
        dir: r.dir,
        weight: Vec3::from(material.albedo)
            * conductor_fresnel(material, wo.dot(r.h))
            * r.g2_over_g1,
        pdf: r.pdf,
        transmitted: false,
    }
}

/// Continues a path at a rough dielectric: a microfacet normal drawn from those visible from
/// `wo` (`u_dir`), then reflection with the Fresnel term at it as the chance (`u_lobe`), else
/// refraction through it (Walter et al. 2007). The weight is `G2 / G1(wo)`, the Fresnel term
/// cancelled by its chance, times `(eta_i / eta_t)^2` for radiance through a refraction
/// ([`Transport`]); zero where the direction leaves on the wrong side, which ends the path.
/// It reports no density ([`samples_lights`]).
fn sample_rough_dielectric(
    material: &GpuMaterial,
    incoming: Vec3,
    frame: &Frame,
    front: bool,
    (u_lobe, u_dir): (f32, (f32, f32)),
    transport: Transport,
) -> BsdfSample {
    let wo = -incoming;
    let eta = if front {
        1.0 / material.ior
    } else {
        material.ior
    };
    let alpha = roughness(material);
    let (_, h) = visible_normal(alpha, frame, wo, u_dir);
    let (dir, transmitted) = match fresnel_refract(incoming, h, eta) {
        (fresnel, Some(t)) if u_lobe >= fresnel => (t, true),
        _ => (reflect(incoming, h), false),
    };
    let (local_o, local_i) = (frame.to_local(wo), frame.to_local(dir));
    let on_its_side = if transmitted {
        local_i.z < 0.0
    } else {
        local_i.z > 0.0
    };
    let mut weight = if local_o.z > 0.0 && on_its_side {
        ggx_g2_over_g1(alpha, local_o, local_i)
    } else {
        0.0
    };
    if transmitted && transport == Transport::Radiance {
        weight *= eta * eta;
    }
    BsdfSample {
        dir,
        weight: Vec3::splat(weight),
        pdf: 0.0,
        transmitted,
    }
}

/// Draws a direction at a visible point: the cosine lobe about `facing`, from the pair `u`;
/// the weight is `f cos / pdf` of [`visible_point_f`] and the [`arrival`] of the direction
/// (the albedo on a diffuse surface).
#[inline]
pub fn sample_visible(material: &GpuMaterial, facing: Vec3, u: (f32, f32)) -> BsdfSample {
    let local = cosine_hemisphere(u.0, u.1);
    let weight = if material.kind == material_kind::COATED {
        coat::base_f(material) * (PI * coat::transmittance(material, local.z))
    } else {
        Vec3::from(material.albedo)
    };
    BsdfSample {
        dir: to_world(local, facing),
        weight,
        pdf: local.z * FRAC_1_PI,
        transmitted: false,
    }
}

/// Continues a path at a delta surface: mirrors reflect with their reflectance, smooth
/// conductors with it times their Fresnel term; glass reflects with probability equal to the
/// Fresnel term, else refracts, the weight then `(eta_i / eta_t)^2` for radiance and one for
/// flux ([`Transport`]). `front` says whether
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
    match material.kind {
        material_kind::MIRROR => return reflected(Vec3::from(material.albedo)),
        material_kind::CONDUCTOR => {
            let fresnel = conductor_fresnel(material, -incoming.dot(facing));
            return reflected(Vec3::from(material.albedo) * fresnel);
        }
        _ => {}
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

/// Draws how a path continues at any surface: [`sample_delta`] with `u_lobe` at delta
/// surfaces, the visible normals of a rough conductor or [`sample_visible`] with `u_dir`
/// elsewhere; at a coated surface `u_lobe` picks the coat's reflection or the base, `u_dir`
/// the direction.
#[inline]
pub fn sample(
    material: &GpuMaterial,
    incoming: Vec3,
    frame: &Frame,
    front: bool,
    (u_lobe, u_dir): (f32, (f32, f32)),
    transport: Transport,
) -> BsdfSample {
    if is_delta(material) {
        return sample_delta(material, incoming, frame.normal, front, u_lobe, transport);
    }
    match material.kind {
        material_kind::CONDUCTOR => sample_conductor(material, frame, -incoming, u_dir),
        material_kind::COATED => coat::sample(material, incoming, frame, u_lobe, u_dir),
        material_kind::GLASS => {
            sample_rough_dielectric(material, incoming, frame, front, (u_lobe, u_dir), transport)
        }
        _ => sample_visible(material, frame.normal, u_dir),
    }
}

/// How a photon continues from a surface it reached (the contract's photon bounce,
/// `ppm_core::rng`): `u.0` picks the lobe at a delta or coated surface and plays Russian
/// roulette where the photon scatters diffusely, surviving below the largest channel of the
/// sampled weight (at most one); `u.1` draws a diffuse or glossy direction. The sample's
/// `weight` is the factor on the photon's power (divided by the survival where roulette
/// played); `None` ends the path: absorbed, or a glossy direction below the surface.
#[inline]
pub fn photon_bounce(
    material: &GpuMaterial,
    incoming: Vec3,
    frame: &Frame,
    front: bool,
    u: (f32, (f32, f32)),
) -> Option<BsdfSample> {
    let mut scattered = sample(material, incoming, frame, front, u, Transport::Importance);
    let roulette = match material.kind {
        material_kind::DIFFUSE => Some(u.0),
        material_kind::COATED => coat::roulette_number(material, -incoming.dot(frame.normal), u.0),
        _ => None,
    };
    if let Some(u_roulette) = roulette {
        let survive = scattered.weight.max_element().min(1.0);
        if u_roulette >= survive {
            return None;
        }
        scattered.weight /= survive;
    } else if scattered.weight == Vec3::ZERO {
        return None;
    }
    Some(scattered)
}

/// One input of the BSDF: a backend's twin must give [`BsdfCase::expected`]. 192 bytes, the
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
    /// The surface's `u` direction ([`frame`]'s).
    pub u_direction: [f32; 3],
    /// [`Transport`] as `u32`.
    pub transport: u32,
    /// Pair that draws a diffuse or glossy direction.
    pub u_dir: [f32; 2],
    /// Padding.
    pub _pad: [u32; 2],
}

/// What the BSDF gives for one [`BsdfCase`]: [`sample`], and at its direction [`eval_cos`],
/// [`pdf`] and [`glossy_lobe`]. 64 bytes, bsdf_vectors.wgsl's `BsdfOutcome`.
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
    /// [`eval_cos`] at the sampled direction.
    pub f_cos: [f32; 3],
    /// [`pdf`] of the sampled direction.
    pub pdf_of_dir: f32,
    /// [`glossy_lobe`]'s `f cos` at the sampled direction.
    pub glossy_f_cos: [f32; 3],
    /// [`glossy_lobe`]'s density of the sampled direction.
    pub glossy_pdf: f32,
}

impl BsdfCase {
    /// The outcome by this module.
    pub fn expected(&self) -> BsdfOutcome {
        let transport = match self.transport {
            0 => Transport::Radiance,
            _ => Transport::Importance,
        };
        let frame = frame(&self.material, Vec3::from(self.facing), || {
            Vec3::from(self.u_direction)
        });
        let wo = -Vec3::from(self.incoming);
        let s = sample(
            &self.material,
            -wo,
            &frame,
            self.front != 0,
            (self.u_lobe, (self.u_dir[0], self.u_dir[1])),
            transport,
        );
        let front = self.front != 0;
        let (glossy_f_cos, glossy_pdf) = glossy_lobe(&self.material, &frame, front, wo, s.dir);
        BsdfOutcome {
            dir: s.dir.into(),
            pdf: s.pdf,
            weight: s.weight.into(),
            transmitted: u32::from(s.transmitted),
            f_cos: eval_cos(&self.material, &frame, wo, s.dir).into(),
            pdf_of_dir: pdf(&self.material, &frame, wo, s.dir),
            glossy_f_cos: glossy_f_cos.into(),
            glossy_pdf,
        }
    }
}

/// A conductor of index `eta + i k`, roughness `alpha`, reflectance factor 0.9.
pub fn conductor(eta: [f32; 3], k: [f32; 3], alpha: f32) -> GpuMaterial {
    GpuMaterial {
        albedo: [0.9; 3],
        kind: material_kind::CONDUCTOR,
        eta,
        alpha,
        alpha_v: alpha,
        k,
        ..Zeroable::zeroed()
    }
}

/// A coated diffuse surface's record, its coat's tables included: what the compiler makes of
/// one and what the test vectors use.
pub fn coated(albedo: [f32; 3], ior: f32, alpha: f32, nonlinear: bool) -> GpuMaterial {
    let (internal, transmittance) = coat_tables(ior, alpha);
    GpuMaterial {
        albedo,
        kind: material_kind::COATED,
        ior,
        alpha,
        alpha_v: alpha,
        coat_internal: internal,
        coat_nonlinear: u32::from(nonlinear),
        // Mitsuba 3's weight: the coat's reflectance (one) against the base's mean.
        coat_specular_weight: 1.0 / (1.0 + albedo.iter().sum::<f32>() / 3.0),
        coat_transmittance: transmittance,
        ..Zeroable::zeroed()
    }
}

/// Every material over incidences from normal to grazing, from both sides, with both
/// transports and with numbers that reflect and refract at glass: the vectors a backend's
/// twin must reproduce. Glass and coat cases whose number lies within 1e-3 of the chance
/// of reflecting are left out, where a last-place difference could pick the other lobe.
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
        conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.3),
        conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.05),
        conductor([1.0, 1.0, 1.0], [0.0, 0.0, 0.0], 0.8),
        conductor([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0),
        // Either side of SMOOTH_ALPHA: a delta lobe, then the narrowest rough one.
        conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.5 * SMOOTH_ALPHA),
        conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 2.0 * SMOOTH_ALPHA),
        // Rough glass, and the narrowest rough glass.
        GpuMaterial {
            kind: material_kind::GLASS,
            ior: 1.5,
            alpha: 0.3,
            alpha_v: 0.3,
            ..Zeroable::zeroed()
        },
        GpuMaterial {
            kind: material_kind::GLASS,
            ior: 1.8,
            alpha: 2.0 * SMOOTH_ALPHA,
            alpha_v: 2.0 * SMOOTH_ALPHA,
            ..Zeroable::zeroed()
        },
        // Anisotropic: wide along the tangent, narrow across it; smooth across it.
        GpuMaterial {
            alpha_v: 0.04,
            ..conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.5)
        },
        GpuMaterial {
            alpha: 1e-4,
            ..conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.2)
        },
        GpuMaterial {
            kind: material_kind::GLASS,
            ior: 1.5,
            alpha: 0.05,
            alpha_v: 0.4,
            ..Zeroable::zeroed()
        },
        coated([0.8, 0.5, 0.1], 1.5, 0.0, false),
        coated([0.8, 0.5, 0.1], 1.5, 0.0, true),
        coated([0.3, 0.9, 0.6], 1.6, 0.3, true),
        coated([0.0; 3], 1.5, 0.05, false),
    ];
    let normals = [Vec3::Y, Vec3::new(0.3, -0.5, 0.8).normalize()];
    // Off every frame's axes, so that anisotropic lobes see oblique directions.
    let u_direction = Vec3::new(0.6, 0.7, -0.2);
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
                                u_direction: u_direction.into(),
                                transport: transport as u32,
                                u_dir,
                                _pad: [0; 2],
                            };
                            let eta = if front {
                                1.0 / material.ior
                            } else {
                                material.ior
                            };
                            let chance = match material.kind {
                                material_kind::GLASS if !is_delta(&material) => {
                                    let wo = -incoming;
                                    let u = (u_dir[0], u_dir[1]);
                                    let frame = frame(&material, facing, || u_direction);
                                    let alpha = roughness(&material);
                                    let (_, h) = visible_normal(alpha, &frame, wo, u);
                                    fresnel_refract(incoming, h, eta).0
                                }
                                material_kind::GLASS => fresnel_refract(incoming, facing, eta).0,
                                material_kind::COATED => specular_probability(&material, cos_i),
                                _ => -1.0,
                            };
                            let near_threshold = (chance - u_lobe).abs() < 1e-3;
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
                assert_relative_eq!(s.pdf, visible_point_pdf(n, s.dir), epsilon = 1e-5);
                assert_relative_eq!(
                    s.pdf,
                    pdf(&white, &Frame::around(n), n, s.dir),
                    epsilon = 1e-5
                );
                // Uniform directions: (cos theta, phi) on a grid of the hemisphere.
                let cos_t = (i as f32 + 0.5) / k as f32;
                let phi = 2.0 * std::f32::consts::PI * (j as f32 + 0.5) / k as f32;
                let sin_t = (1.0 - cos_t * cos_t).sqrt();
                let wi = to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t), n);
                integral += f64::from(visible_point_pdf(n, wi)) * 2.0 * std::f64::consts::PI
                    / f64::from(k * k);
            }
        }
        assert_relative_eq!(integral, 1.0, epsilon = 1e-3);
        assert_eq!(visible_point_pdf(n, -n), 0.0);
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
                    &Frame::around(n),
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
        assert_eq!(pdf(&g, &Frame::around(n), n, n), 0.0);
    }

    /// A rough dielectric splits light by the Fresnel term at its microfacets and keeps all
    /// of it but what single scattering cannot return: over its numbers a photon's expected
    /// weight is at most one (near one for a narrow lobe; 0.88 and 0.45 at alpha 0.3 and 1
    /// seen from inside, where microfacets past the critical angle reflect and shadow), a
    /// narrow lobe refracts with the smooth boundary's chance, radiance through a refraction
    /// is scaled by `(eta_i / eta_t)^2`, and no bounce reports a density.
    #[test]
    fn a_rough_dielectric_splits_by_fresnel_and_loses_only_what_single_scattering_cannot_return() {
        let n = Vec3::Y;
        for ((alpha, alpha_v), at_least) in [
            ((0.02, 0.02), 0.99),
            ((0.3, 0.3), 0.85),
            ((1.0, 1.0), 0.4),
            ((0.05, 0.5), 0.8),
        ] {
            let rough = GpuMaterial {
                alpha,
                alpha_v,
                ..glass(1.5)
            };
            assert!(!is_delta(&rough) && !samples_lights(&rough));
            for (front, cos) in [(true, 0.8f32), (true, 0.2), (false, 0.9)] {
                let facing = if front { n } else { -n };
                let frame = Frame::with_tangent(facing, Vec3::new(0.6, 0.3, 0.8));
                let incoming = Vec3::new((1.0 - cos * cos).sqrt(), -cos, 0.0) * facing.y;
                let eta = if front { 1.0 / 1.5 } else { 1.5 };
                let k = 64;
                let (mut flux, mut refracted) = (0.0f64, 0.0f64);
                for l in 0..k {
                    for i in 0..k {
                        for j in 0..k {
                            let mid = |x: usize| (x as f32 + 0.5) / k as f32;
                            let u = (mid(l), (mid(i), mid(j)));
                            let photon =
                                sample(&rough, incoming, &frame, front, u, Transport::Importance);
                            let eye =
                                sample(&rough, incoming, &frame, front, u, Transport::Radiance);
                            assert_eq!((photon.dir, photon.pdf), (eye.dir, 0.0));
                            assert!(photon.weight.x <= 1.0 + 1e-5, "{photon:?}");
                            let scale = if eye.transmitted { eta * eta } else { 1.0 };
                            assert_relative_eq!(eye.weight.x, photon.weight.x * scale);
                            flux += f64::from(photon.weight.x);
                            refracted +=
                                f64::from(u8::from(photon.transmitted && photon.weight.x > 0.0));
                        }
                    }
                }
                let total = f64::from((k * k * k) as u32);
                let kept = flux / total;
                assert!(
                    kept <= 1.0 && kept >= at_least,
                    "alpha {alpha} cos {cos}: {kept}"
                );
                if alpha == 0.02 {
                    let smooth = fresnel_refract(incoming, facing, eta).0;
                    assert_relative_eq!(refracted / total, 1.0 - f64::from(smooth), epsilon = 0.02);
                }
            }
        }
    }

    /// At grazing angles, where `tan` overflows and `cos^2` underflows in f32, the rough
    /// lobe's value, density and weight stay finite and its weight at most one.
    #[test]
    fn a_rough_conductor_stays_finite_at_grazing_angles() {
        let n = Vec3::Z;
        let frame = Frame::with_tangent(n, Vec3::new(1.0, 1.0, 0.0));
        for (alpha, alpha_v) in [
            (2.0 * SMOOTH_ALPHA, 2.0 * SMOOTH_ALPHA),
            (0.3, 0.3),
            (1.0, 1.0),
            (1e-4, 0.5),
        ] {
            let metal = GpuMaterial {
                alpha_v,
                ..conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], alpha)
            };
            for cos in [1e-3f32, 1e-12, 1e-30, f32::MIN_POSITIVE] {
                let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
                let wi = Vec3::new(-(1.0 - cos * cos).sqrt(), 0.0, cos);
                for (o, i) in [(wo, wi), (wo, Vec3::Z), (Vec3::Z, wi)] {
                    assert!(
                        eval_cos(&metal, &frame, o, i).is_finite(),
                        "alpha {alpha} cos {cos}"
                    );
                    let density = pdf(&metal, &frame, o, i);
                    assert!(density.is_finite(), "alpha {alpha} cos {cos}");
                }
                for u in [(0.01, 0.2), (0.5, 0.5), (0.99, 0.9)] {
                    let s = sample(&metal, -wo, &frame, true, (0.5, u), Transport::Radiance);
                    assert!(s.weight.is_finite() && s.pdf.is_finite(), "{s:?}");
                    assert!(s.weight.max_element() <= 1.0, "{s:?}");
                }
            }
        }
    }

    /// The conductor's Fresnel term: `((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2)` at normal
    /// incidence, one at grazing incidence, one everywhere for a lossless metal (`eta = 0`),
    /// and a dielectric's (`k = 0`) equal to the smooth glass's.
    #[test]
    fn the_conductor_fresnel_term_meets_its_closed_forms() {
        let gold = conductor([0.18, 0.42, 1.37], [3.42, 2.35, 1.77], 0.0);
        let normal = conductor_fresnel(&gold, 1.0);
        for c in 0..3 {
            let (e, k) = (gold.eta[c], gold.k[c]);
            let expected = ((e - 1.0).powi(2) + k * k) / ((e + 1.0).powi(2) + k * k);
            assert_relative_eq!(normal[c], expected, max_relative = 1e-5);
        }
        assert_relative_eq!(conductor_fresnel(&gold, 0.0).x, 1.0, max_relative = 1e-5);
        let lossless = conductor([0.0; 3], [1.0; 3], 0.0);
        for cos in [1.0, 0.7, 0.2, 0.01] {
            assert_relative_eq!(
                conductor_fresnel(&lossless, cos).x,
                1.0,
                max_relative = 1e-5
            );
        }
        let dielectric = conductor([1.5; 3], [0.0; 3], 0.0);
        for cos in [1.0f32, 0.6, 0.1] {
            let d = Vec3::new((1.0 - cos * cos).sqrt(), -cos, 0.0);
            let (glass, _) = fresnel_refract(d, Vec3::Y, 1.0 / 1.5);
            assert_relative_eq!(
                conductor_fresnel(&dielectric, cos).x,
                glass,
                max_relative = 1e-4
            );
        }
        // A smooth conductor is a delta lobe that reflects its Fresnel term.
        assert!(is_delta(&gold) && !holds_visible_points(&gold));
        let d = Vec3::new(0.6, -0.8, 0.0);
        let s = sample_delta(&gold, d, Vec3::Y, true, 0.5, Transport::Radiance);
        assert_relative_eq!(s.weight.x, 0.9 * conductor_fresnel(&gold, 0.8).x);
    }

    /// A photon's roulette is unbiased: over its number, the expected factor on its power is
    /// the albedo, while only the largest channel's share of photons survives; a delta
    /// surface keeps every photon.
    #[test]
    fn a_photon_bounce_keeps_the_expected_power() {
        let red = GpuMaterial {
            albedo: [0.6, 0.3, 0.1],
            ..Zeroable::zeroed()
        };
        let k = 10_000;
        let (mut power, mut survivors) = (Vec3::ZERO, 0);
        for i in 0..k {
            let u = ((i as f32 + 0.5) / k as f32, (0.3, 0.7));
            if let Some(s) = photon_bounce(&red, -Vec3::Z, &Frame::around(Vec3::Z), true, u) {
                power += s.weight;
                survivors += 1;
            }
        }
        assert_relative_eq!(survivors as f32 / k as f32, 0.6, epsilon = 1e-3);
        assert!(
            (power / k as f32 - Vec3::new(0.6, 0.3, 0.1))
                .abs()
                .max_element()
                < 1e-3
        );
        let mirror = GpuMaterial {
            albedo: [0.9; 3],
            kind: material_kind::MIRROR,
            ..Zeroable::zeroed()
        };
        let up = Frame::around(Vec3::Z);
        let kept = photon_bounce(&mirror, -Vec3::Z, &up, true, (0.99, (0.5, 0.5)));
        assert_eq!(kept.map(|s| s.weight), Some(Vec3::splat(0.9)));
    }

    /// An anisotropic lobe follows its frame: roughness `(a, b)` about a tangent is
    /// roughness `(b, a)` about the bitangent (the frame turned a quarter), for value and
    /// density alike, and the lobe reaches further along the rougher direction.
    #[test]
    fn an_anisotropic_lobe_turns_with_its_tangent() {
        let n = Vec3::new(0.2, 0.9, -0.1).normalize();
        let frame = Frame::with_tangent(n, Vec3::new(0.3, -0.4, 0.9));
        let turned = Frame::with_tangent(n, frame.bitangent);
        let metal = |alpha, alpha_v| GpuMaterial {
            alpha_v,
            ..conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], alpha)
        };
        let (wide_along, wide_across) = (metal(0.5, 0.08), metal(0.08, 0.5));
        let wo = (n * 0.8 + (frame.tangent + frame.bitangent) * 0.4).normalize();
        let mirror = reflect(-wo, n);
        for (i, j) in [(0.1f32, 0.0f32), (0.0, 0.1), (0.3, -0.2), (-0.25, 0.4)] {
            let wi = (mirror + frame.tangent * i + frame.bitangent * j).normalize();
            let (a, b) = (
                eval_cos(&wide_along, &frame, wo, wi),
                eval_cos(&wide_across, &turned, wo, wi),
            );
            assert!(
                (a - b).abs().max_element() <= 1e-4 * a.max_element(),
                "{a} {b}"
            );
            let (a, b) = (
                pdf(&wide_along, &frame, wo, wi),
                pdf(&wide_across, &turned, wo, wi),
            );
            assert_relative_eq!(a, b, max_relative = 1e-4);
        }
        let off = |d: Vec3| (mirror + d * 0.3).normalize();
        let along = pdf(&wide_along, &frame, wo, off(frame.tangent));
        let across = pdf(&wide_along, &frame, wo, off(frame.bitangent));
        assert!(along > 10.0 * across, "along {along}, across {across}");
    }

    /// The eye pass weighs a light sample at a glossy bounce against the bounce with
    /// `glossy_lobe`: its `f cos / pdf` must be the weight the bounce carries (else the two
    /// strategies estimate different integrals), and its density must integrate to the share
    /// of bounces kept (else the weights do not sum to one).
    #[test]
    fn the_glossy_lobe_is_what_an_eye_path_s_bounce_samples() {
        let glass = |ior, alpha, alpha_v| GpuMaterial {
            kind: material_kind::GLASS,
            ior,
            alpha,
            alpha_v,
            ..Zeroable::zeroed()
        };
        let materials = [
            conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.3),
            conductor([0.15, 0.4, 1.4], [3.6, 2.5, 1.9], 0.05),
            GpuMaterial {
                alpha_v: 0.05,
                ..conductor([0.2, 0.9, 1.1], [3.9, 2.4, 1.8], 0.4)
            },
            coated([0.3, 0.9, 0.6], 1.6, 0.3, true),
            coated([0.8; 3], 1.5, 0.1, false),
            glass(1.5, 0.3, 0.3),
            glass(1.33, 0.1, 0.1),
            glass(1.5, 0.4, 0.08),
        ];
        // Off orthonormal_basis(+y)'s axes, so that anisotropic lobes are seen obliquely.
        let frame = Frame::with_tangent(Vec3::Y, Vec3::new(1.0, 0.0, 1.0));
        const N: u32 = 1 << 16;
        for material in materials {
            for (front, cos_o) in [true, false]
                .into_iter()
                .flat_map(|f| [0.95f32, 0.5, 0.15].map(|c| (f, c)))
            {
                let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), cos_o, 0.0);
                let (mut kept, mut integral) = (0u32, 0.0f64);
                for i in 0..N {
                    let u = (
                        (i as f32 + 0.5) / N as f32,
                        ((i.wrapping_mul(40503)) % N) as f32 / N as f32,
                    );
                    // Below any coat's chance of reflecting, so that the path continues; glass
                    // picks reflection or refraction over all numbers.
                    let u_lobe = match material.kind {
                        material_kind::GLASS => ((i.wrapping_mul(7919)) % N) as f32 / N as f32,
                        _ => 0.0,
                    };
                    let s = sample(
                        &material,
                        -wo,
                        &frame,
                        front,
                        (u_lobe, u),
                        Transport::Radiance,
                    );
                    if s.weight.x > 0.0 {
                        kept += 1;
                        let (f_cos, pdf) = glossy_lobe(&material, &frame, front, wo, s.dir);
                        let w = f_cos / pdf;
                        assert!(
                            (w - s.weight).abs().max_element() <= 1e-3 * s.weight.max_element(),
                            "{material:?} front {front} cos_o {cos_o}: {w} against {}",
                            s.weight
                        );
                    }
                    let wi = crate::sampling::uniform_cone(u.1, u.0, -1.0);
                    integral += f64::from(glossy_lobe(&material, &frame, front, wo, wi).1);
                }
                let integral = integral * 4.0 * std::f64::consts::PI / f64::from(N);
                let share = f64::from(kept) / f64::from(N);
                assert!(
                    (integral - share).abs() < 0.02,
                    "{material:?} front {front} cos_o {cos_o}: density integrates to {integral}, kept {share}"
                );
            }
        }
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
            material_kind::CONDUCTOR,
            material_kind::COATED,
        ] {
            assert!(outcomes.iter().any(|(c, _)| c.material.kind == kind));
        }
        // Both lobes of a smooth and of a rough coat: the reflection, and the base's.
        for smooth in [true, false] {
            let lobe = |reflected: bool| {
                outcomes.iter().any(|(c, _)| {
                    let cos = -Vec3::from(c.incoming).dot(Vec3::from(c.facing));
                    c.material.kind == material_kind::COATED
                        && (c.material.alpha == 0.0) == smooth
                        && (c.u_lobe < specular_probability(&c.material, cos)) == reflected
                })
            };
            assert!(lobe(true) && lobe(false), "smooth {smooth}");
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
