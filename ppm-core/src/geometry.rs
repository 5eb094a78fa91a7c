//! Ray geometry shared by every pass: triangle intersection, local frames, mirror and
//! refraction directions, and the packed normal of a photon record.

use crate::layout::GpuTriangle;
use glam::Vec3;

/// Distance along `dir` to the triangle, or `f32::INFINITY` on a miss (Moller-Trumbore).
///
/// Both faces are hit: surfaces are two-sided for transport, one-sided only for emission.
/// Only hits with `tmin < t < tmax` count; a degenerate triangle is never hit.
#[inline]
pub fn intersect_triangle(origin: Vec3, dir: Vec3, tri: &GpuTriangle, tmin: f32, tmax: f32) -> f32 {
    let e1 = Vec3::from(tri.e1);
    let e2 = Vec3::from(tri.e2);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 || !det.is_finite() {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let s = origin - Vec3::from(tri.v0);
    let b1 = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return f32::INFINITY;
    }
    let q = s.cross(e1);
    let b2 = dir.dot(q) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return f32::INFINITY;
    }
    let t = e2.dot(q) * inv_det;
    if t > tmin && t < tmax {
        t
    } else {
        f32::INFINITY
    }
}

/// Tangent and bitangent completing `n` to a right-handed orthonormal frame (Duff et al. 2017).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// `local` expressed in the frame whose +z is `n`.
#[inline]
pub fn to_world(local: Vec3, n: Vec3) -> Vec3 {
    let (t, b) = orthonormal_basis(n);
    t * local.x + b * local.y + n * local.z
}

/// The frame a BSDF works in at a surface point: the unit normal on the path's side and a
/// tangent. Isotropic lobes take any tangent ([`Frame::around`]); an anisotropic one is
/// oriented by the surface's texture coordinates ([`Frame::with_tangent`], docs/materials.md,
/// "Anisotropic roughness").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Unit tangent, along which a lobe's roughness is `alpha`.
    pub tangent: Vec3,
    /// `normal x tangent`, along which it is `alpha_v`.
    pub bitangent: Vec3,
    /// Unit normal on the side the path is on.
    pub normal: Vec3,
}

impl Frame {
    /// The frame [`orthonormal_basis`] completes about `normal`.
    #[inline]
    pub fn around(normal: Vec3) -> Self {
        let (tangent, bitangent) = orthonormal_basis(normal);
        Self {
            tangent,
            bitangent,
            normal,
        }
    }

    /// The frame about `normal` whose tangent is `direction` less its part along the normal;
    /// [`Frame::around`] where nothing is left of it (a degenerate or non-finite direction).
    #[inline]
    pub fn with_tangent(normal: Vec3, direction: Vec3) -> Self {
        let scale = direction.abs().max_element();
        if !(scale > 0.0 && scale.is_finite()) {
            return Self::around(normal);
        }
        let d = direction / scale;
        let tangent = d - normal * normal.dot(d);
        // Parallel to the normal within rounding, or a NaN in one component (which the
        // largest component's test above passes over): no direction in the plane.
        if !tangent.is_finite() || tangent.length_squared() <= 1e-12 {
            return Self::around(normal);
        }
        let tangent = tangent.normalize();
        Self {
            tangent,
            bitangent: normal.cross(tangent),
            normal,
        }
    }

    /// `v` in this frame's coordinates: along the tangent, the bitangent and the normal.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.tangent.dot(v),
            self.bitangent.dot(v),
            self.normal.dot(v),
        )
    }

    /// `local` back in world coordinates.
    #[inline]
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        self.tangent * local.x + self.bitangent * local.y + self.normal * local.z
    }
}

/// Mirror direction of `d` about the normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// Fresnel reflectance of a smooth dielectric for unpolarised light, and the refracted
/// direction when there is one (`None` on total internal reflection).
///
/// `d` is the unit incident direction, `n` the unit normal on the incident side
/// (`d.dot(n) < 0`), `eta` the ratio of the incident to the transmitted index.
#[inline]
pub fn fresnel_refract(d: Vec3, n: Vec3, eta: f32) -> (f32, Option<Vec3>) {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (1.0, None);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let f = 0.5 * (r_s * r_s + r_p * r_p);
    let t = d * eta + n * (eta * cos_i - cos_t);
    (f.clamp(0.0, 1.0), Some(t.normalize()))
}

/// Packs a unit vector into 16+16 bits by the octahedral map (Cigolle et al. 2014).
#[inline]
pub fn oct_encode(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let (mut x, mut y) = (n.x / l1, n.y / l1);
    if n.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * sign_nonzero(ox);
        y = (1.0 - ox.abs()) * sign_nonzero(oy);
    }
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0 + 0.5).floor() as u32;
    q(x) | (q(y) << 16)
}

/// Unpacks [`oct_encode`]; the result is unit length up to rounding.
#[inline]
pub fn oct_decode(bits: u32) -> Vec3 {
    oct_unfold(bits).normalize()
}

/// Whether the packed normal `bits` points into the hemisphere of `n`: the test a gather makes
/// for every photon in its disc, on the unnormalised decoding (a positive scale keeps the
/// sign of the dot product, so the square root and division are skipped).
#[inline]
pub fn oct_faces(bits: u32, n: Vec3) -> bool {
    oct_unfold(bits).dot(n) > 0.0
}

/// The octahedral map unfolded back to a direction of L1 length 1 (not yet unit length): what
/// [`oct_faces`] dots with the normal, for a backend that decodes each photon once.
#[inline]
pub fn oct_unfold(bits: u32) -> Vec3 {
    let d = |v: u32| v as f32 * (2.0 / 65535.0) - 1.0;
    let (x, y) = (d(bits & 0xffff), d(bits >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - y.abs()) * sign_nonzero(x),
            (1.0 - x.abs()) * sign_nonzero(y),
        )
    } else {
        (x, y)
    };
    Vec3::new(x, y, z)
}

#[inline]
fn sign_nonzero(v: f32) -> f32 {
    if v >= 0.0 { 1.0 } else { -1.0 }
}

/// Whether the segment `origin + t dir`, `0 <= t <= t_max` (`t_max` may be infinite), meets
/// the closed box `[lo, hi]`: the slab test on all three axes at once, without branches (it runs
/// for every eye, shadow and cosine ray of a scene with movers), an axis parallel to the
/// direction set apart so that it never forms `0 * inf`. An empty box (`lo > hi`) is never met.
#[inline]
pub fn segment_meets_box(origin: Vec3, dir: Vec3, t_max: f32, lo: Vec3, hi: Vec3) -> bool {
    let a = (lo - origin) / dir;
    let b = (hi - origin) / dir;
    // A parallel axis admits every t when the origin lies within its slab, none otherwise.
    let parallel = dir.cmpeq(Vec3::ZERO);
    let within = origin.cmpge(lo) & origin.cmple(hi);
    let (all, none) = (
        Vec3::select(within, Vec3::NEG_INFINITY, Vec3::INFINITY),
        Vec3::select(within, Vec3::INFINITY, Vec3::NEG_INFINITY),
    );
    let enter = Vec3::select(parallel, all, a.min(b));
    let leave = Vec3::select(parallel, none, a.max(b));
    let t0 = enter.max_element().max(0.0);
    let t1 = leave.min_element().min(t_max);
    lo.cmple(hi).all() && t0 <= t1
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn tri(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> GpuTriangle {
        let (a, b, c) = (Vec3::from(v0), Vec3::from(v1), Vec3::from(v2));
        GpuTriangle {
            v0,
            e1: (b - a).into(),
            e2: (c - a).into(),
            normal: (b - a).cross(c - a).normalize_or_zero().into(),
            ..Default::default()
        }
    }

    /// A frame with a given tangent is orthonormal and right-handed about its normal, its
    /// tangent the direction's part in the plane; a direction along the normal, zero or not
    /// finite falls back on the basis about the normal.
    #[test]
    fn a_frame_keeps_the_part_of_its_tangent_in_the_plane() {
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let d = Vec3::new(2.0, 1.0, -0.5);
        let f = Frame::with_tangent(n, d);
        let in_plane = (d - n * n.dot(d)).normalize();
        assert!((f.tangent - in_plane).length() < 1e-6);
        assert!((f.bitangent - n.cross(f.tangent)).length() < 1e-6);
        let v = Vec3::new(0.1, 0.7, -0.3);
        assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
        for degenerate in [
            n * 3.0,
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::new(f32::NAN, 1.0, 0.0),
            Vec3::INFINITY,
        ] {
            assert_eq!(Frame::with_tangent(n, degenerate), Frame::around(n));
        }
    }

    #[test]
    fn ray_hits_triangle_at_the_plane_distance_from_both_sides() {
        let t = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let hit = intersect_triangle(Vec3::new(0.2, 0.2, 3.0), -Vec3::Z, &t, 0.0, f32::MAX);
        assert_relative_eq!(hit, 3.0);
        let back = intersect_triangle(Vec3::new(0.2, 0.2, -2.0), Vec3::Z, &t, 0.0, f32::MAX);
        assert_relative_eq!(back, 2.0);
        let miss = intersect_triangle(Vec3::new(0.8, 0.8, 3.0), -Vec3::Z, &t, 0.0, f32::MAX);
        assert_eq!(miss, f32::INFINITY);
    }

    #[test]
    fn degenerate_triangle_is_never_hit() {
        let t = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
        let hit = intersect_triangle(Vec3::new(0.5, 1.0, 0.0), -Vec3::Y, &t, 0.0, f32::MAX);
        assert_eq!(hit, f32::INFINITY);
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, -2.0, 0.5).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert_relative_eq!(t.dot(b), 0.0, epsilon = 1e-6);
            assert_relative_eq!(t.dot(n), 0.0, epsilon = 1e-6);
            assert_relative_eq!(t.cross(b).dot(n), 1.0, epsilon = 1e-5);
        }
    }

    #[test]
    fn fresnel_is_total_past_the_critical_angle_and_bounded_below_it() {
        let n = Vec3::Y;
        let steep = Vec3::new(0.9, -0.1, 0.0).normalize();
        assert_eq!(fresnel_refract(steep, n, 1.5).0, 1.0);
        assert!(fresnel_refract(steep, n, 1.0 / 1.5).1.is_some());
        let (f, t) = fresnel_refract(-Vec3::Y, n, 1.0 / 1.5);
        assert_relative_eq!(f, 0.04, epsilon = 1e-4);
        assert_relative_eq!(t.unwrap().y, -1.0, epsilon = 1e-6);
    }

    #[test]
    fn octahedral_normals_round_trip_closely() {
        for n in [
            Vec3::X,
            -Vec3::Y,
            -Vec3::Z,
            Vec3::new(0.3, -0.4, -0.866).normalize(),
            Vec3::new(-0.01, 0.99, 0.1).normalize(),
        ] {
            let back = oct_decode(oct_encode(n));
            assert!(back.dot(n) > 0.99999, "{n} -> {back}");
        }
    }

    #[test]
    fn segments_meet_boxes_they_cross_and_no_others() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let x = Vec3::X;
        // Through, stopping short, starting beyond, parallel inside and outside a slab.
        assert!(segment_meets_box(
            Vec3::new(-1.0, 0.5, 0.5),
            x,
            10.0,
            lo,
            hi
        ));
        assert!(!segment_meets_box(
            Vec3::new(-1.0, 0.5, 0.5),
            x,
            0.5,
            lo,
            hi
        ));
        assert!(!segment_meets_box(
            Vec3::new(2.0, 0.5, 0.5),
            x,
            f32::INFINITY,
            lo,
            hi
        ));
        assert!(segment_meets_box(
            Vec3::new(-1.0, 1.0, 0.5),
            x,
            f32::INFINITY,
            lo,
            hi
        ));
        assert!(!segment_meets_box(
            Vec3::new(-1.0, 1.5, 0.5),
            x,
            f32::INFINITY,
            lo,
            hi
        ));
        // Starting inside, diagonal, and the empty box.
        assert!(segment_meets_box(Vec3::splat(0.5), -x, 0.0, lo, hi));
        let d = Vec3::ONE.normalize();
        assert!(segment_meets_box(
            Vec3::splat(-1.0),
            d,
            f32::INFINITY,
            lo,
            hi
        ));
        let empty = crate::layout::GpuBounds::EMPTY;
        assert!(!segment_meets_box(
            Vec3::splat(-1.0),
            d,
            f32::INFINITY,
            empty.min.into(),
            empty.max.into()
        ));
    }
}
