//! The variance of a local move's correction, a path's two deposits counted as one
//! (docs/algorithm.md 3c).
//!
//! A correction traces the same paths in pose A, with negative power, and in pose B, and a
//! slot adds what both leave in its disc. Its variance is the sum over paths of the square of
//! each path's net deposit in the disc. Summing each deposit's own square instead counts
//! twice a path the move barely changed: in a small move (a drag's step) a path that meets the
//! moved object lands almost where it did, with the same power, and its two deposits cancel in
//! the flux but not in the squares. The slot then gives up history the correction did not
//! cost (a drag's error right after it was 30% higher on cornell-box).
//!
//! So pose B pairs each of its deposits with the deposit its path stored in the same order in
//! pose A ([`partner`]), if that one faces the same way, and carries its position and
//! luminance. A disc that holds both adds the cross term `2 l_A l_B` to their squares, so it
//! sums the square of their sum; a disc that holds one of them counts that one's square
//! ([`variance_term`]). A pair that cancels exactly ([`Partner::cancels`]: a path the move
//! did not change, up to that deposit) counts nothing. Pose A records its paths' first
//! [`PAIRED_DEPOSITS`] stored deposits; later ones count alone, as before.

use crate::layout::Photon;
use glam::Vec3;

/// Stored deposits per path that pose B pairs with pose A's (docs/algorithm.md 3c). A drag's
/// error right after it falls with each of the first four paired and no further when every
/// deposit is, while pose A's record of a path stays a fixed size.
pub const PAIRED_DEPOSITS: usize = 4;

/// A pose-A deposit a pose-B deposit is paired with: where it landed, its power's luminance
/// (negative: pose A's power is), and its packed normal. Zero luminance stands for none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partner {
    /// Where it landed.
    pub position: Vec3,
    /// Luminance of its power; zero stands for no partner.
    pub luminance: f32,
    /// Octahedral encoding of its normal ([`Photon::normal_oct`]).
    pub normal_oct: u32,
}

impl Partner {
    /// The partner a pose-A deposit makes.
    pub fn of(photon: &Photon) -> Self {
        Self {
            position: photon.position.into(),
            luminance: crate::update::luminance(photon.power),
            normal_oct: photon.normal_oct,
        }
    }

    /// Whether pose B's `deposit` is this deposit with its power negated, bit for bit: the
    /// same position and the opposite luminance. Its path met no moved object in either pose
    /// before it (the same random numbers trace the same path), so the pair's net deposit is
    /// zero in every disc. A third of a cornell-box drag step's pairs cancel.
    #[inline]
    pub fn cancels(&self, deposit: &Photon) -> bool {
        self.position == Vec3::from(deposit.position)
            && self.luminance == -crate::update::luminance(deposit.power)
    }
}

/// The partner of pose B's `deposit`: `candidate`, the deposit its path stored in the same
/// order in pose A (within the first [`PAIRED_DEPOSITS`]), if it faces the same way, so that
/// a disc gathers both or neither for their normals.
#[inline]
pub fn partner(deposit: &Photon, candidate: Option<&Partner>) -> Option<Partner> {
    candidate
        .filter(|a| a.luminance != 0.0 && a.normal_oct == deposit.normal_oct)
        .copied()
}

/// What a deposit of power luminance `own` adds to the correction's variance in a disc that
/// holds it: its square, and where its partner of luminance `a` lies in the same disc
/// (`partner_in_disc`) the cross term `2 a own`, which makes the pair count `(a + own)^2`, but
/// never less than [`PAIR_FLOOR`] of their squares' sum; a pair that `cancels`
/// ([`Partner::cancels`], and then both lie in every disc that holds one) counts nothing.
#[inline]
pub fn variance_term(own: f32, partner_in_disc: Option<f32>, cancels: bool) -> f32 {
    own * own
        + partner_in_disc.map_or(0.0, |a| match cancels {
            true => -(a * a + own * own),
            false => cross_term(a, own),
        })
}

/// The share of its two squares a pair counts at least, unless it cancels exactly. Where few
/// changed paths pass, a disc's variance rests on a handful of pairs; changed paths that land
/// almost where they did, with the same power, would leave it near zero although another
/// could as well have landed elsewhere, and the slot would keep its stale history whole
/// (wedding-band's drag, whose corrections are sparse, ends further from the truth so). A
/// pair that cancels exactly is a path the move did not change, and counts nothing
/// (docs/algorithm.md 3c).
pub const PAIR_FLOOR: f32 = 0.25;

/// The cross term of a pair of luminances `a` (pose A) and `b` (pose B), floored
/// ([`PAIR_FLOOR`]).
#[inline]
pub fn cross_term(a: f32, b: f32) -> f32 {
    (2.0 * a * b).max(-(1.0 - PAIR_FLOOR) * (a * a + b * b))
}

/// Each of pose B's deposits `pose_b` paired with the deposit its path stored in the same
/// order in pose A, `pose_a` (both in path order, as read back), where they pair.
pub fn pose_a_partners(pose_a: &[Photon], pose_b: &[Photon]) -> Vec<Option<Partner>> {
    let mut nth = 0;
    pose_b
        .iter()
        .enumerate()
        .map(|(i, b)| {
            nth = match i > 0 && pose_b[i - 1].path == b.path {
                true => nth + 1,
                false => 0,
            };
            let first = pose_a.partition_point(|a| a.path < b.path);
            let candidate = pose_a
                .get(first + nth)
                .filter(|a| a.path == b.path && nth < PAIRED_DEPOSITS)
                .map(Partner::of);
            partner(b, candidate.as_ref())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(power: f32, normal_oct: u32) -> Photon {
        Photon {
            position: [1.0, 0.0, 0.0],
            path: 7,
            power: [power; 3],
            normal_oct,
        }
    }

    /// A disc holding both deposits of a pair sums the square of their sum (the difference's
    /// square for a path the move dimmed), but not less than the floor's share of their
    /// squares (a path the move did not change); a disc holding one counts its square alone.
    #[test]
    fn a_pair_counts_its_net_deposit_in_a_disc_that_holds_both() {
        for (a, b) in [(-2.0f32, 2.0f32), (-2.0, 1.5), (-0.5, 3.0)] {
            let (pose_a, pose_b) = (photon(a, 9), photon(b, 9));
            let pair = partner(&pose_b, Some(&Partner::of(&pose_a))).expect("they pair");
            // Luminance weights sum to one, so a grey power's luminance is the power.
            let both =
                variance_term(a, None, false) + variance_term(b, Some(pair.luminance), false);
            let floor = PAIR_FLOOR * (a * a + b * b);
            approx::assert_relative_eq!(both, ((a + b) * (a + b)).max(floor), max_relative = 1e-5);
            approx::assert_relative_eq!(variance_term(b, None, false), b * b, max_relative = 1e-6);
        }
    }

    /// A pair that cancels, pose B's deposit pose A's with its power negated, counts nothing
    /// in a disc that holds both; moved or with another power, a pair does not cancel.
    #[test]
    fn a_pair_that_cancels_counts_nothing() {
        let pose_a = Partner::of(&photon(-2.0, 9));
        let same = photon(2.0, 9);
        assert!(pose_a.cancels(&same));
        let pair = variance_term(-2.0, None, false) + variance_term(2.0, Some(-2.0), true);
        assert_eq!(pair, 0.0);
        let moved = Photon {
            position: [1.0, 1e-6, 0.0],
            ..same
        };
        assert!(!pose_a.cancels(&moved));
        assert!(!pose_a.cancels(&photon(1.5, 9)));
        assert!(!pose_a.cancels(&photon(-2.0, 9)));
    }

    /// A deposit facing another way, or without one in pose A, has no partner.
    #[test]
    fn only_a_deposit_facing_the_same_way_is_a_partner() {
        let a = Partner::of(&photon(-2.0, 9));
        assert_eq!(partner(&photon(2.0, 9), Some(&a)), Some(a));
        assert_eq!(partner(&photon(2.0, 8), Some(&a)), None);
        assert_eq!(partner(&photon(2.0, 9), None), None);
        assert_eq!(partner(&photon(2.0, 9), Some(&Partner::default())), None);
    }
}
