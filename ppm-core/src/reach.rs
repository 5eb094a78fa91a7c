//! Where a slot's light may come from: conservative tests that a local move uses to decide,
//! from what a slot recorded and from the two poses of a moved object, whether the move may
//! change the slot's view or its direct light. Every doubt answers yes: a needless yes costs
//! a reset or a correction whose paired rays cancel, a wrong no keeps stale light.

use glam::Vec3;

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

    /// Whether every point of `other` lies in the box.
    pub fn contains(&self, other: &Aabb) -> bool {
        self.lo.cmple(other.lo).all() && other.hi.cmple(self.hi).all()
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
/// The point `(1 - s) p + s q` of such a segment lies in the box `B(s)` between
/// `(1 - s) from.lo + s to.lo` and `(1 - s) from.hi + s to.hi`, so a segment can meet
/// `target` at `s` only where `B(s)` overlaps it. On each axis the overlap holds on an
/// interval of `s` (both bounds of `B(s)` are linear in `s`); the test asks whether the
/// three intervals share an `s` in `[0, 1]`, each widened a little for rounding: never a
/// wrong no, and a few divisions whatever the boxes (a local move asks it of every slot).
/// A target well apart from the box around `from` and `to` is answered no before any
/// division (`near_both`): most of a move's slots.
pub fn segments_may_meet(from: &Aabb, to: &Aabb, target: &Aabb) -> bool {
    if from.is_empty() || to.is_empty() || target.is_empty() {
        return false;
    }
    near_both(from, to, target) && swept_boxes_meet(from, to, target)
}

/// Whether `target` comes near the box around `from` and `to`, which holds every segment
/// between them: within a margin far wider than the rounding of [`swept_boxes_meet`], so that
/// a no here is a no there.
fn near_both(from: &Aabb, to: &Aabb, target: &Aabb) -> bool {
    let around = from.union(to);
    let scale = around.lo.abs().max(around.hi.abs());
    let margin = scale.max(target.lo.abs()).max(target.hi.abs()) * (16.0 * WIDEN);
    !((around.lo - margin).cmpgt(target.hi).any() || (around.hi + margin).cmplt(target.lo).any())
}

/// The sweep of [`segments_may_meet`]: whether the intervals of `s` where `B(s)` overlaps
/// `target` on each axis share a point of `[0, 1]`.
fn swept_boxes_meet(from: &Aabb, to: &Aabb, target: &Aabb) -> bool {
    let (mut first, mut last) = (0.0_f32, 1.0_f32);
    for k in 0..3 {
        // B(s).lo <= target.hi, and B(s).hi >= target.lo.
        let (a, b) = at_most(from.lo[k], to.lo[k], target.hi[k]);
        let (c, d) = at_most(-from.hi[k], -to.hi[k], -target.lo[k]);
        first = first.max(a).max(c);
        last = last.min(b).min(d);
    }
    first <= last
}

/// How much each bound of the target is widened, relative to the largest coordinate in play,
/// so that the rounding of an interval's ends never turns a meeting into a miss (f32 rounds at
/// about 6e-8 of it).
const WIDEN: f32 = 1e-5;

/// The interval of `s` in `[0, 1]` where `(1 - s) at0 + s at1 <= bound`, widened by
/// [`WIDEN`] (empty: first > last). Infinite or NaN inputs answer all of `[0, 1]`.
fn at_most(at0: f32, at1: f32, bound: f32) -> (f32, f32) {
    let bound = bound + WIDEN * bound.abs().max(at0.abs()).max(at1.abs());
    let slope = at1 - at0;
    if !(slope.is_finite() && bound.is_finite()) {
        return (0.0, 1.0);
    }
    if slope == 0.0 {
        return if at0 <= bound { (0.0, 1.0) } else { (1.0, 0.0) };
    }
    let s = (bound - at0) / slope;
    if slope > 0.0 { (0.0, s) } else { (s, 1.0) }
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

    /// A point of the unit cube from dimensions `d` to `d + 2` of `k`.
    fn random_point(k: &StreamKey, d: u32) -> Vec3 {
        Vec3::new(k.uniform(d), k.uniform(d + 1), k.uniform(d + 2))
    }

    /// Three random boxes within `[0, 13]^3`, from the stream of `path` (dimensions 0-17),
    /// and the stream.
    fn random_boxes(seed: u32, path: u32) -> (StreamKey, [Aabb; 3]) {
        let k = StreamKey {
            seed,
            kind: PassKind::Photon,
            pass_index: 0,
            path,
        };
        let boxed = |d: u32| {
            let lo = random_point(&k, d) * 10.0;
            Aabb::new(lo, lo + random_point(&k, d + 3) * 3.0)
        };
        (k, [boxed(0), boxed(6), boxed(12)])
    }

    #[test]
    fn a_box_between_two_others_is_met_and_one_beside_them_is_not() {
        let (a, b) = (unit([0.0, 0.0, 0.0]), unit([10.0, 0.0, 0.0]));
        assert!(segments_may_meet(&a, &b, &unit([5.0, 0.0, 0.0])));
        assert!(!segments_may_meet(&a, &b, &unit([5.0, 3.0, 0.0])));
        // Inside the box around both, but off every segment: the sweep tells it apart.
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
        let mut met = 0;
        for path in 0..20_000 {
            let (k, [from, to, target]) = random_boxes(11, path);
            let inside = |b: &Aabb, d: u32| b.lo + (b.hi - b.lo) * random_point(&k, d);
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

    /// And a yes only where a box of the sweep between the two boxes comes near the target:
    /// over random boxes, every target that no swept box `B(s)` (sampled densely) comes within
    /// 0.01 of is answered no, and the test answers no often.
    #[test]
    fn a_target_away_from_every_swept_box_is_answered_no() {
        let mut no = 0;
        for path in 0..5_000 {
            let (_, [from, to, target]) = random_boxes(12, path);
            let grown = Aabb::new(target.lo - 0.01, target.hi + 0.01);
            let swept_near = (0..=4096).any(|i| {
                let s = i as f32 / 4096.0;
                Aabb::new(from.lo.lerp(to.lo, s), from.hi.lerp(to.hi, s)).overlaps(&grown)
            });
            if !swept_near {
                no += 1;
                assert!(
                    !segments_may_meet(&from, &to, &target),
                    "{from:?} {to:?} {target:?}"
                );
            }
        }
        assert!(no > 2_500, "only {no} targets away from the sweep");
    }

    /// The quick no changes no answer: over random boxes, and targets set just beyond the
    /// box around the two (by a few ulps to a few thousandths of their size, on every side),
    /// the sweep alone answers no wherever the quick test does.
    #[test]
    fn the_quick_no_is_the_sweeps_no() {
        let mut quick = 0;
        for path in 0..20_000 {
            let (k, [from, to, target]) = random_boxes(13, path);
            let around = from.union(&to);
            let axis = (path % 3) as usize;
            let gap = [1e-7, 1e-6, 1e-5, 1e-4, 1e-3][(path / 3 % 5) as usize] * k.uniform(24);
            let mut near = target;
            let size = near.hi[axis] - near.lo[axis];
            if path % 2 == 0 {
                near.lo[axis] = around.hi[axis] * (1.0 + gap) + gap;
                near.hi[axis] = near.lo[axis] + size;
            } else {
                near.hi[axis] = around.lo[axis] * (1.0 - gap) - gap;
                near.lo[axis] = near.hi[axis] - size;
            }
            for t in [target, near] {
                if !near_both(&from, &to, &t) {
                    quick += 1;
                    assert!(!swept_boxes_meet(&from, &to, &t), "{from:?} {to:?} {t:?}");
                }
            }
        }
        assert!(quick > 5_000, "only {quick} quick answers");
    }

    #[test]
    fn a_box_contains_itself_and_smaller_boxes_only() {
        let b = unit([0.0; 3]);
        assert!(b.contains(&b));
        assert!(b.contains(&Aabb::new(Vec3::splat(0.2), Vec3::splat(0.8))));
        assert!(!b.contains(&unit([0.5, 0.0, 0.0])));
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
