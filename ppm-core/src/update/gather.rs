//! The gather rule (docs/algorithm.md 1.4 and 3, "Who gathers what"): what one slot does with
//! the photons it found in one pass's map, for every gather kind. Written once here; the wgpu
//! backend's twin is `gather_rule` in update.wgsl, and both reproduce [`test_cases`] (a backend
//! test runs them through the WGSL). A backend's gather pass finds each slot's photons, calls
//! [`gather_rule`], and writes the result back: the policy is not the backend's to choose.

use super::luminance as lum;
use super::pairing::{Partner, variance_term};
use super::{Statistics, compensation_update, history_kept, luminance, ppm_update};
use crate::geometry::oct_faces;
use crate::layout::{GatherParams, HitPoint, Photon, gather_kind, hit_flags};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// The fields of a slot that a gather reads and writes, with its pending sum (the deferred
/// region photons of area and local modes). 48 bytes, the layout of `SlotState` in
/// update.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SlotState {
    /// Accumulated flux.
    pub tau: [f32; 3],
    /// Photon count `N`.
    pub n: f32,
    /// Deferred flux (x, y, z) and signed count, or with
    /// [`gather_kind::ADD_FLUX`] the correction's variance (w).
    pub pending: [f32; 4],
    /// Squared radius.
    pub r2: f32,
    /// Photons emitted over the slot's life (the estimate's normaliser).
    pub emitted: f32,
    /// The slot's [`hit_flags`].
    pub flags: u32,
    /// The photons of `n` that corrections discounted ([`HitPoint::discounted`]).
    pub discounted: f32,
}

impl SlotState {
    /// The gather rule's view of slot `hp` with its pending sum.
    pub fn of(hp: &HitPoint, pending: [f32; 4]) -> Self {
        Self {
            tau: hp.tau,
            n: hp.n,
            pending,
            r2: hp.r2,
            emitted: hp.emitted,
            flags: hp.flags,
            discounted: hp.discounted,
        }
    }

    /// Writes the statistics a gather may change back into slot `hp` (the pending sum lives
    /// apart, in the backend's own buffer).
    pub fn store(&self, hp: &mut HitPoint) {
        (hp.n, hp.r2, hp.tau) = (self.n, self.r2, self.tau);
        (hp.emitted, hp.discounted) = (self.emitted, self.discounted);
    }

    /// Whether the statistics [`check_hit_points`](crate::check::check_hit_points) names that
    /// a gather writes (flux, count, radius, emitted) are finite, without a branch: a gather
    /// screens what it stores, since every other field was screened by the pass that wrote it.
    pub fn is_finite(&self) -> bool {
        let [x, y, z] = self.tau;
        [x, y, z, self.n, self.r2, self.emitted]
            .iter()
            .fold(true, |ok, v| ok & v.is_finite())
    }
}

/// The squared radius of the disc slot `hp` searches a map within: its own, or in a pass
/// with a floor (`gather_r2_floor`, local mode's correction) the widest of its own, the
/// floor and its `correction_r2`. The WGSL twin is `search_r2` in update.wgsl.
#[inline]
pub fn search_r2(hp: &HitPoint, r2_floor: f32) -> f32 {
    if r2_floor > 0.0 {
        hp.r2.max(r2_floor).max(hp.correction_r2)
    } else {
        hp.r2
    }
}

/// What photons found within a disc of squared radius `searched` stand for in the slot's own
/// disc of `r2`: their density times its area, `r2 / searched` where the search was wider.
#[inline]
pub fn disc_shrink(r2: f32, searched: f32) -> f32 {
    if searched > r2 { r2 / searched } else { 1.0 }
}

/// What a slot found in the current photon map, already scaled to its own disc (the search
/// disc may be wider, [`search_r2`]: flux and weight times [`disc_shrink`], `power_sq` times
/// its square; the count is not scaled). 32 bytes, the layout of `Found` in update.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Found {
    /// Summed photon power.
    pub flux: [f32; 3],
    /// Photons found.
    pub count: f32,
    /// Summed path weights (region passes; the count otherwise).
    pub weight: f32,
    /// Summed squared luminance of the photons' power (a local move's correction variance).
    pub power_sq: f32,
    /// Padding.
    pub _pad: [f32; 2],
}

/// What `hp` finds among `photons` within its radius, or the wider disc a floor gives it
/// ([`search_r2`]) scaled to its own ([`Found`]): each photon tested in turn, its path weight
/// from `weights` and, where a correction's pose B paired it, the variance term of its pair
/// ([`variance_term`]). The plain form of every gather, which the conformance suite recomputes
/// by and a plain backend gathers with.
pub fn found_in_disc(
    hp: &HitPoint,
    (photons, weights, partners): (&[Photon], &[f32], &[Option<Partner>]),
    r2_floor: f32,
) -> Found {
    let r2 = search_r2(hp, r2_floor);
    let (x, normal) = (Vec3::from(hp.position), Vec3::from(hp.normal));
    let (mut count, mut weight, mut flux, mut power_sq) = (0u32, 0.0, Vec3::ZERO, 0.0);
    let inside = |p: Vec3| (p - x).length_squared() < r2;
    for ((ph, w), partner) in photons.iter().zip(weights).zip(partners) {
        if inside(Vec3::from(ph.position)) && oct_faces(ph.normal_oct, normal) {
            count += 1;
            weight += w;
            flux += Vec3::from(ph.power);
            let both = partner.filter(|a| inside(a.position)).map(|a| a.luminance);
            let cancels = partner.is_some_and(|a| a.cancels(ph));
            power_sq += variance_term(lum(ph.power), both, cancels);
        }
    }
    let shrink = disc_shrink(hp.r2, r2);
    Found {
        flux: (flux * shrink).into(),
        count: count as f32,
        weight: weight * shrink,
        power_sq: power_sq * shrink * shrink,
        _pad: [0.0; 2],
    }
}

/// Whether a slot belongs to the set a pass of `kind` serves, visible point or not: such a
/// slot counts the pass's photons in `emitted`. Region passes serve the slots a move kept,
/// guided passes the ones it updated, every other kind every slot.
pub fn serves(flags: u32, kind: u32) -> bool {
    let updated = flags & hit_flags::UPDATED != 0;
    match kind & gather_kind::KIND_MASK {
        gather_kind::REGION_NEGATIVE | gather_kind::REGION_POSITIVE => !updated,
        gather_kind::GUIDED => updated,
        _ => true,
    }
}

/// Whether a slot gathers a pass of `kind`: it is served and has a visible point.
pub fn gathers(flags: u32, kind: u32) -> bool {
    flags & hit_flags::VALID != 0 && serves(flags, kind)
}

/// Whether a pass of `kind` reads or writes the pending sums (a backend may leave them
/// unallocated until one does).
pub fn uses_pending(kind: u32) -> bool {
    kind & gather_kind::DEFERRED != 0 || kind & gather_kind::KIND_MASK == gather_kind::REGION_APPLY
}

/// One slot's new state after a pass of `params.kind`. `reflectance` is the slot's eye-path
/// throughput times its BRDF (`albedo / pi`), `r2_initial` the render's initial squared
/// radius. [`gather_kind::REGION_APPLY`] ignores `found` and folds the pending sum in.
pub fn gather_rule(
    params: &GatherParams,
    r2_initial: f32,
    reflectance: [f32; 3],
    slot: SlotState,
    found: &Found,
) -> SlotState {
    let kind = params.kind & gather_kind::KIND_MASK;
    if kind == gather_kind::REGION_APPLY {
        return apply_pending(params, r2_initial, slot);
    }
    let mut s = slot;
    if !gathers(s.flags, params.kind) {
        if serves(s.flags, params.kind) {
            s.emitted += params.emitted_increment;
        }
        return s;
    }
    let region = matches!(
        kind,
        gather_kind::REGION_NEGATIVE | gather_kind::REGION_POSITIVE
    );
    // Region photons stand for `emitted / N_c` ordinary photons each, times their path
    // weight (docs/algorithm.md 3, "Power of a region photon").
    let scale = if region {
        s.emitted / params.region_photons
    } else {
        1.0
    };
    let m = if region && params.kind & gather_kind::RAW_COUNT == 0 {
        found.weight * scale
    } else {
        found.count
    };
    let factor = reflectance.map(|r| r * scale);
    let dtau = [0, 1, 2].map(|c| found.flux[c] * factor[c]);
    if params.kind & gather_kind::DEFERRED != 0 {
        let sign = if kind == gather_kind::REGION_NEGATIVE {
            -1.0
        } else {
            1.0
        };
        // A flux-only correction keeps the variance of its flux where the count would go.
        let count = if params.kind & gather_kind::ADD_FLUX != 0 {
            found.power_sq * luminance(factor) * luminance(factor)
        } else {
            sign * m
        };
        let p = s.pending;
        s.pending = [p[0] + dtau[0], p[1] + dtau[1], p[2] + dtau[2], p[3] + count];
        return s;
    }
    let before = Statistics {
        n: s.n,
        r2: s.r2,
        tau: s.tau,
    };
    let after = if kind == gather_kind::REGION_NEGATIVE {
        compensation_update(before, m, dtau, params.alpha, r2_initial)
    } else {
        ppm_update(before, m, dtau, params.alpha)
    };
    (s.n, s.r2, s.tau) = (after.n, after.r2, after.tau);
    // Photons a negative pass removed leave no discount behind them.
    s.discounted = s.discounted.min(s.n);
    s.emitted += params.emitted_increment;
    if kind == gather_kind::REGION_NEGATIVE && m > 0.0 && after.n == 0.0 {
        // Emptied: its statistics start over, so does their normaliser; otherwise the
        // photons it gathers next would be divided by everything emitted before.
        s.emitted = 0.0;
    }
    s
}

/// Folds a slot's pending region photons into its statistics as one update and clears them:
/// eqs 1-3 when the net count grew, eqs 5-7 with their clamps when it fell; flux clamped at
/// zero. With [`gather_kind::ADD_FLUX`] only the flux is added, and the pending count, which
/// then holds the correction's variance, weighs how much of the slot's history stays
/// ([`history_kept`], docs/algorithm.md 3c).
fn apply_pending(params: &GatherParams, r2_initial: f32, slot: SlotState) -> SlotState {
    let mut s = slot;
    let [t0, t1, t2, m] = std::mem::take(&mut s.pending);
    if s.flags & hit_flags::VALID == 0 || (m == 0.0 && t0 == 0.0 && t1 == 0.0 && t2 == 0.0) {
        return s;
    }
    if params.kind & gather_kind::ADD_FLUX != 0 {
        let tau = [s.tau[0] + t0, s.tau[1] + t1, s.tau[2] + t2].map(|t| t.max(0.0));
        // What earlier corrections left of the history is what this one weighs against.
        let worth = (s.n - s.discounted).max(0.0);
        let kept = history_kept(worth, tau, m);
        s.tau = tau.map(|t| t * kept);
        s.emitted *= kept;
        s.discounted = s.n - worth * kept;
        return s;
    }
    let before = Statistics {
        n: s.n,
        r2: s.r2,
        tau: s.tau,
    };
    let after = if m >= 0.0 {
        let grown = ppm_update(before, m, [t0, t1, t2], params.alpha);
        Statistics {
            tau: grown.tau.map(|t| t.max(0.0)),
            ..grown
        }
    } else {
        compensation_update(before, -m, [t0, t1, t2], params.alpha, r2_initial)
    };
    if m < 0.0 && after.n == 0.0 {
        s.emitted = 0.0;
    }
    (s.n, s.r2, s.tau) = (after.n, after.r2, after.tau);
    s.discounted = s.discounted.min(s.n);
    s
}

/// One input of the gather rule: a backend's twin must turn `slot` into
/// `gather_rule(&params, r2_initial, reflectance, slot, &found)`. 112 bytes, the layout of
/// `GatherCase` in the wgpu backend's gather_vectors.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherCase {
    /// The slot before the pass.
    pub slot: SlotState,
    /// What it found.
    pub found: Found,
    /// Throughput times BRDF.
    pub reflectance: [f32; 3],
    /// The render's initial squared radius.
    pub r2_initial: f32,
    /// The pass.
    pub params: GatherParams,
}

impl GatherCase {
    /// The slot after the pass, by the rule.
    pub fn expected(&self) -> SlotState {
        gather_rule(
            &self.params,
            self.r2_initial,
            self.reflectance,
            self.slot,
            &self.found,
        )
    }
}

/// Every gather kind with each of its flags, over slots that gather, that are only served,
/// that are neither, that are empty, that a negative pass empties, that hold a pending sum
/// of either sign or a correction's variance, with and without an earlier correction's
/// discount: the vectors a backend's twin of [`gather_rule`] must reproduce.
pub fn test_cases() -> Vec<GatherCase> {
    use gather_kind::*;
    let kinds = [
        ORDINARY,
        GUIDED,
        REGION_NEGATIVE,
        REGION_NEGATIVE | RAW_COUNT,
        REGION_POSITIVE,
        REGION_POSITIVE | RAW_COUNT,
        REGION_NEGATIVE | DEFERRED,
        REGION_POSITIVE | DEFERRED,
        REGION_NEGATIVE | DEFERRED | ADD_FLUX,
        REGION_POSITIVE | DEFERRED | ADD_FLUX,
        REGION_APPLY,
        REGION_APPLY | ADD_FLUX,
    ];
    let valid = hit_flags::VALID | hit_flags::FRONT;
    let slots = [
        // A converged slot, kept by a move.
        slot(valid, 812.0, 0.0123, [3.5, 2.25, 1.125], 4.0e6, [0.0; 4]),
        // The same slot, updated by the move.
        slot(
            valid | hit_flags::UPDATED,
            812.0,
            0.0123,
            [3.5, 2.25, 1.125],
            4.0e6,
            [0.0; 4],
        ),
        // Fresh: nothing gathered yet.
        slot(valid, 0.0, 0.04, [0.0; 3], 0.0, [0.0; 4]),
        // No visible point this iteration.
        slot(0, 30.0, 0.02, [0.5, 0.5, 0.5], 1.0e5, [0.0; 4]),
        // Few photons: a negative pass of many empties it.
        slot(valid, 3.0, 0.039, [0.25, 0.125, 0.0625], 2.0e5, [0.0; 4]),
        // Pending: a net gain, a net loss, and a correction's variance.
        slot(
            valid,
            400.0,
            0.01,
            [2.0, 1.0, 0.5],
            1.0e6,
            [0.25, 0.125, 0.0, 40.0],
        ),
        slot(
            valid,
            400.0,
            0.01,
            [2.0, 1.0, 0.5],
            1.0e6,
            [-0.5, -0.25, -0.1, -60.0],
        ),
        slot(
            valid,
            400.0,
            0.01,
            [2.0, 1.0, 0.5],
            1.0e6,
            [-2.5, 0.25, 0.1, 1.0e-3],
        ),
        // The same correction after an earlier one discounted part of the history.
        SlotState {
            discounted: 300.0,
            ..slot(
                valid,
                400.0,
                0.01,
                [2.0, 1.0, 0.5],
                1.0e6,
                [0.25, 0.25, 0.1, 1.0e-3],
            )
        },
    ];
    let finds = [
        Found::default(),
        Found {
            flux: [0.75, 0.5, 0.25],
            count: 17.0,
            weight: 13.5,
            power_sq: 0.0425,
            _pad: [0.0; 2],
        },
        Found {
            flux: [40.0, 35.0, 30.0],
            count: 900.0,
            weight: 1200.0,
            power_sq: 2.5,
            _pad: [0.0; 2],
        },
    ];
    let mut cases = Vec::new();
    for kind in kinds {
        for slot in slots {
            for found in finds {
                cases.push(GatherCase {
                    slot,
                    found,
                    reflectance: [0.21, 0.17, 0.052],
                    r2_initial: 0.04,
                    params: GatherParams {
                        alpha: 0.7,
                        emitted_increment: if kind & KIND_MASK == REGION_APPLY
                            || kind & KIND_MASK == REGION_NEGATIVE
                            || kind & KIND_MASK == REGION_POSITIVE
                        {
                            0.0
                        } else {
                            50_000.0
                        },
                        kind,
                        region_photons: 20_000.0,
                    },
                });
            }
        }
    }
    cases
}

fn slot(flags: u32, n: f32, r2: f32, tau: [f32; 3], emitted: f32, pending: [f32; 4]) -> SlotState {
    SlotState {
        tau,
        n,
        pending,
        r2,
        emitted,
        flags,
        discounted: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use gather_kind::*;

    fn case(kind: u32, slot_index: usize) -> Vec<(GatherCase, SlotState)> {
        test_cases()
            .into_iter()
            .filter(|c| c.params.kind == kind)
            .skip(slot_index * 3)
            .take(3)
            .map(|c| (c, c.expected()))
            .collect()
    }

    #[test]
    fn an_ordinary_pass_counts_its_photons_in_every_slot_and_gathers_in_the_visible_ones() {
        for slot in 0..9 {
            for (c, after) in case(ORDINARY, slot) {
                assert_eq!(after.emitted, c.slot.emitted + 50_000.0);
                let visible = c.slot.flags & hit_flags::VALID != 0;
                assert_eq!(after.n > c.slot.n, visible && c.found.count > 0.0, "{c:?}");
                assert_eq!(after.pending, c.slot.pending);
            }
        }
    }

    #[test]
    fn region_passes_serve_the_kept_slots_and_guided_passes_the_updated_ones() {
        for (kind, kept_changes) in [(REGION_POSITIVE, true), (GUIDED, false)] {
            let (kept, updated) = (case(kind, 0), case(kind, 1));
            assert_eq!(kept[2].1 != kept[2].0.slot, kept_changes, "kind {kind}");
            assert_eq!(
                updated[2].1 != updated[2].0.slot,
                !kept_changes,
                "kind {kind}"
            );
        }
    }

    #[test]
    fn a_negative_pass_that_takes_every_photon_empties_the_slot_and_its_normaliser() {
        let (c, after) = case(REGION_NEGATIVE | RAW_COUNT, 4)[2];
        assert!(c.found.count > c.slot.n);
        assert_eq!((after.n, after.r2, after.emitted), (0.0, 0.04, 0.0));
        assert_eq!(after.tau, [0.0; 3]);
    }

    #[test]
    fn deferred_passes_only_add_to_the_pending_sum_with_their_sign() {
        let (neg, pos) = (
            case(REGION_NEGATIVE | DEFERRED, 0)[1],
            case(REGION_POSITIVE | DEFERRED, 0)[1],
        );
        for (_, after) in [neg, pos] {
            assert_eq!((after.n, after.tau), (neg.0.slot.n, neg.0.slot.tau));
        }
        assert_eq!(neg.1.pending[3], -pos.1.pending[3]);
        assert!(pos.1.pending[3] > 0.0);
        let corr = case(REGION_NEGATIVE | DEFERRED | ADD_FLUX, 0)[1].1;
        assert!(corr.pending[3] > 0.0, "a correction's variance is positive");
    }

    #[test]
    fn applying_clears_the_pending_sum_and_keeps_flux_non_negative() {
        for kind in [REGION_APPLY, REGION_APPLY | ADD_FLUX] {
            for slot in 5..8 {
                let (c, after) = case(kind, slot)[0];
                assert_eq!(after.pending, [0.0; 4]);
                assert!(after.tau.iter().all(|t| *t >= 0.0), "{c:?} -> {after:?}");
                assert_ne!(after, c.slot);
            }
        }
        let (_, gained) = case(REGION_APPLY, 5)[0];
        assert!(gained.n > 400.0 && gained.r2 < 0.01);
        let (_, lost) = case(REGION_APPLY, 6)[0];
        assert!(lost.n < 400.0 && lost.r2 > 0.01);
        let (c, corrected) = case(REGION_APPLY | ADD_FLUX, 7)[0];
        assert_eq!((corrected.n, corrected.r2), (c.slot.n, c.slot.r2));
        assert!(
            corrected.emitted < c.slot.emitted,
            "a noisy correction discounts history"
        );
    }

    /// Two corrections in a row leave the history what one correction of their summed
    /// relative variance would: the second weighs against what the first kept, not against
    /// the whole count, and the count, which sets how fast the radius shrinks, stays.
    #[test]
    fn successive_corrections_discount_the_history_once() {
        let params = GatherParams {
            alpha: 0.7,
            emitted_increment: 0.0,
            kind: REGION_APPLY | ADD_FLUX,
            region_photons: 0.0,
        };
        // Luminance 2 over 400 photons; a variance of 0.01 is the history's own.
        let start = slot(hit_flags::VALID, 400.0, 0.01, [2.0; 3], 1.0e6, [0.0; 4]);
        let correct = |s: SlotState, relative: f32| {
            let lum = luminance(s.tau);
            let pending = [0.0, 0.0, 0.0, relative * lum * lum];
            gather_rule(
                &params,
                0.04,
                [0.0; 3],
                SlotState { pending, ..s },
                &Found::default(),
            )
        };
        let twice = correct(correct(start, 0.0025), 0.0025);
        let once = correct(start, 0.005);
        assert_relative_eq!(once.emitted, 1.0e6 / 3.0, max_relative = 1e-5);
        assert_relative_eq!(twice.emitted, once.emitted, max_relative = 1e-5);
        assert_relative_eq!(twice.tau[0], once.tau[0], max_relative = 1e-5);
        assert_eq!((twice.n, twice.r2), (start.n, start.r2));
        assert_relative_eq!(twice.discounted, 400.0 * 2.0 / 3.0, max_relative = 1e-5);
    }
}
