//! The variance of a local move's correction, a path's two deposits counted as one
//! (docs/algorithm.md 3c).
//!
//! A correction traces the same paths in pose A, with negative power, and in pose B, and a
//! slot adds what both leave in its disc. Its variance is the sum over paths of the square of
//! each path's net deposit in the disc. Summing each deposit's own square instead counts
//! twice a path the move barely changed: in a small move (a drag's step) a path that meets the
//! moved object lands almost where it did, with the same power, and its two deposits cancel in
//! the flux but not in the squares. The slot then gives up history the correction did not
//! cost (a drag's error right after it was 30% higher).
//!
//! So pose B weighs each of its deposits against the deposit of the same path and rank (the
//! same count of deposits stored before it) in pose A: where the two lie within
//! [`PAIR_RADIUS`] floor radii of each other and face the same way, the B deposit carries the
//! cross term, so that a disc holding both sums the square of their sum. A disc that holds
//! one of them alone, which only a pair straddling its rim can do, is off by the cross term;
//! the slot's sum is clamped at zero ([`crate::update::history_kept`] keeps all history for
//! none). Pose A records its paths' first [`PAIRED_DEPOSITS`] stored deposits; later ones
//! count alone, as before.

use crate::layout::Photon;
use glam::Vec3;

/// Stored deposits per path that pose B pairs with pose A's: on cornell-box's drag, pairing
/// the first 1, 2, 3 or 4 measured 0.074, 0.067, 0.063 and 0.062 a quarter second after it,
/// pairing all of them 0.062.
pub const PAIRED_DEPOSITS: usize = 4;

/// How near a path's deposits in the two poses must lie to count as one, in radii of the
/// correction's floor disc: on cornell-box's drag 0.5 measured 0.061 a quarter second after
/// it, 1.0 measured 0.062 (more pairs straddle a disc's rim).
pub const PAIR_RADIUS: f32 = 0.5;

/// A pose-A deposit as pose B's pass pairs with it: where it landed, its power's luminance
/// (negative: pose A's power is), and its packed normal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partner {
    /// Where it landed.
    pub position: Vec3,
    /// Luminance of its power; zero stands for no deposit.
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
}

/// The squared luminance pose B's `deposit` adds to a slot's correction variance, given the
/// deposit of the same path and rank in pose A (if any) and the correction's squared floor
/// radius `r2_floor`: its own square, plus twice the product with its partner's luminance
/// where the two count as one.
#[inline]
pub fn paired_square(deposit: &Photon, partner: Option<&Partner>, r2_floor: f32) -> f32 {
    let own = crate::update::luminance(deposit.power);
    let cross = partner
        .filter(|a| {
            let d2 = (a.position - Vec3::from(deposit.position)).length_squared();
            a.normal_oct == deposit.normal_oct && d2 < PAIR_RADIUS * PAIR_RADIUS * r2_floor
        })
        .map_or(0.0, |a| 2.0 * a.luminance * own);
    own * own + cross
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(x: f32, power: f32, normal_oct: u32) -> Photon {
        Photon {
            position: [x, 0.0, 0.0],
            path: 7,
            power: [power; 3],
            normal_oct,
        }
    }

    /// A disc holding both deposits of a pair sums the square of their sum: zero for a path
    /// the move did not change, the difference's square for one it dimmed.
    #[test]
    fn a_pair_in_one_disc_counts_its_net_deposit() {
        for (a, b) in [(-2.0f32, 2.0f32), (-2.0, 1.5), (-0.5, 3.0)] {
            let partner = Partner::of(&photon(1.0, a, 9));
            let square = paired_square(&photon(1.2, b, 9), Some(&partner), 1.0);
            // Luminance weights sum to one, so a grey power's luminance is the power.
            let disc = partner.luminance * partner.luminance + square;
            approx::assert_relative_eq!(disc, (a + b) * (a + b), max_relative = 1e-5);
        }
    }

    /// Deposits too far apart, facing another way, or without a partner count alone.
    #[test]
    fn unpaired_deposits_count_their_own_square() {
        let partner = Partner::of(&photon(0.0, -2.0, 9));
        let alone = 4.0;
        // The floor's radius is 2, so pairs lie within 1 of each other.
        assert_eq!(
            paired_square(&photon(1.5, 2.0, 9), Some(&partner), 4.0),
            alone
        );
        assert_eq!(
            paired_square(&photon(0.5, 2.0, 8), Some(&partner), 4.0),
            alone
        );
        assert_eq!(paired_square(&photon(0.5, 2.0, 9), None, 4.0), alone);
        assert_eq!(
            paired_square(&photon(0.5, 2.0, 9), Some(&Partner::default()), 4.0),
            alone
        );
        assert_eq!(
            paired_square(&photon(0.5, 2.0, 9), Some(&partner), 4.0),
            4.0 - 8.0
        );
    }
}
