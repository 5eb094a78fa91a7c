//! Where a slot's light may come from: conservative tests that a local move uses to decide,
//! from what a slot recorded and from the two poses of a moved object, whether the move may
//! change the slot's view or its direct light. Every doubt answers yes: a needless yes costs
//! a reset or a correction whose paired rays cancel, a wrong no keeps stale light.

use glam::Vec3;

/// Pieces the segments between two boxes are cut into along their length: the box around
/// each piece is tested, so the test is as tight as a piece is short.
const PIECES: u32 = 16;

/// An axis-aligned box by its corners (`lo > hi` on some axis: the box of nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub lo: Vec3,
    /// Largest corner.
    pub hi: Vec3,
}

impl Aabb {
    /// The box from `lo` to `hi`.
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        Self { lo, hi }
    }

    /// The box of the triangle's vertices.
    pub fn of_triangle(v: [Vec3; 3]) -> Self {
        Self::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }

    /// Whether the two boxes share a point (closed boxes).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        !self.is_empty()
            && !other.is_empty()
            && self.lo.cmple(other.hi).all()
            && other.lo.cmple(self.hi).all()
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb::new(self.lo.min(other.lo), self.hi.max(other.hi))
    }

    /// Distance from `p` to the nearest point of the box (0 inside it).
    pub fn distance_from(&self, p: Vec3) -> f32 {
        (self.lo - p).max(p - self.hi).max(Vec3::ZERO).length()
    }

    /// Distance from `p` to the farthest point of the box.
    pub fn farthest_from(&self, p: Vec3) -> f32 {
        (self.lo - p).abs().max((self.hi - p).abs()).length()
    }
}

/// Whether some segment from a point of `from` to a point of `to` may meet `target`.
///
/// A point `(1 - s) p + s q` of such a segment lies, for `s` in `[s0, s1]`, in the box
/// spanned by the boxes `(1 - s0) from + s0 to` and `(1 - s1) from + s1 to` (the set is
/// linear in `s`, so its extremes sit at the ends). The test checks that box for each of
/// `PIECES` (16) pieces of `[0, 1]`: never a wrong no, and a yes only within a piece's reach.
pub fn segments_may_meet(from: &Aabb, to: &Aabb, target: &Aabb) -> bool {
    if from.is_empty() || to.is_empty() || target.is_empty() {
        return false;
    }
    if !from.union(to).overlaps(target) {
        return false;
    }
    let at = |s: f32| Aabb::new(from.lo.lerp(to.lo, s), from.hi.lerp(to.hi, s));
    (0..PIECES).any(|k| {
        let s0 = k as f32 / PIECES as f32;
        let s1 = (k + 1) as f32 / PIECES as f32;
        at(s0).union(&at(s1)).overlaps(target)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::segment_meets_box;
    use crate::rng::{PassKind, StreamKey};

    fn unit(lo: [f32; 3]) -> Aabb {
        let lo = Vec3::from(lo);
        Aabb::new(lo, lo + Vec3::ONE)
    }

    #[test]
    fn a_box_between_two_others_is_met_and_one_beside_them_is_not() {
        let (a, b) = (unit([0.0, 0.0, 0.0]), unit([10.0, 0.0, 0.0]));
        assert!(segments_may_meet(&a, &b, &unit([5.0, 0.0, 0.0])));
        assert!(!segments_may_meet(&a, &b, &unit([5.0, 3.0, 0.0])));
        // Inside the box around both, but off every segment: the pieces tell it apart.
        assert!(!segments_may_meet(
            &unit([0.0, 0.0, 0.0]),
            &unit([10.0, 10.0, 0.0]),
            &unit([8.0, 1.0, 0.0])
        ));
    }

    #[test]
    fn nothing_meets_nothing() {
        let empty = Aabb::new(Vec3::ONE, Vec3::ZERO);
        assert!(empty.is_empty());
        assert!(!segments_may_meet(&empty, &unit([0.0; 3]), &unit([0.0; 3])));
    }

    /// Never a wrong no: segments between random points of random boxes that meet a random
    /// target (exactly, by the slab test) are always answered yes.
    #[test]
    fn every_segment_that_meets_the_target_is_answered_yes() {
        let key = |path| StreamKey {
            seed: 11,
            kind: PassKind::Photon,
            pass_index: 0,
            path,
        };
        let mut met = 0;
        for path in 0..20_000 {
            let k = key(path);
            let v = |d: u32| Vec3::new(k.uniform(d), k.uniform(d + 1), k.uniform(d + 2)) * 10.0;
            let boxed = |d: u32| {
                let (a, b) = (v(d), v(d + 3) * 0.3);
                Aabb::new(a, a + b)
            };
            let (from, to, target) = (boxed(0), boxed(6), boxed(12));
            let inside = |b: &Aabb, d: u32| {
                b.lo + (b.hi - b.lo) * Vec3::new(k.uniform(d), k.uniform(d + 1), k.uniform(d + 2))
            };
            let (p, q) = (inside(&from, 18), inside(&to, 21));
            let len = (q - p).length();
            if len > 0.0 && segment_meets_box(p, (q - p) / len, len, target.lo, target.hi) {
                met += 1;
                assert!(
                    segments_may_meet(&from, &to, &target),
                    "{from:?} {to:?} {target:?}"
                );
            }
        }
        assert!(met > 300, "only {met} segments met their target");
    }

    #[test]
    fn distances_to_a_box() {
        let b = unit([1.0, 0.0, 0.0]);
        assert_eq!(b.distance_from(Vec3::new(0.0, 0.5, 0.5)), 1.0);
        assert_eq!(b.distance_from(Vec3::new(1.5, 0.5, 0.5)), 0.0);
        let far = b.farthest_from(Vec3::ZERO);
        assert!((far - Vec3::new(2.0, 1.0, 1.0).length()).abs() < 1e-6);
    }
}
