//! Local mode's direct-light correction (docs/algorithm.md 3c): how much a move changes the
//! light a kept slot sees directly, averaged over its pixel, and how well that is known.
//!
//! A slot's direct sum holds one sample per iteration, each at the visible point of that
//! iteration's jittered eye path: the pixel's average. So the change is estimated the same
//! way, by eye paths through stratified points of the pixel ([`direct_samples_for`]), each
//! traced in both poses with the same random numbers and lit there with the same light
//! sample; the pairs' spread says how well the mean is known. Traced on the host with the CPU backend's
//! scene, whatever backend renders (as [`super::probe`]): a few thousand slots' paths.

use super::probe::{HostPose, ProbeSettings, eye_path};
use backend_cpu::direct_light::slot_direct;
use glam::Vec3;
use ppm_core::layout::{DirectLightParams, HitPoint, direct_accumulate};
use ppm_core::rng::{PassKind, StratifiedStream, StreamKey};
use ppm_core::update::luminance;
use rayon::prelude::*;

/// The most paired samples a slot gets: eye paths through stratified points of its pixel,
/// one light sample each.
pub const MOST_SAMPLES: u32 = 16;

/// Paired samples per slot for a correction of `share` passes' worth of photons
/// (`MoveParams::correction_for`): 4 per pass, from 4 to [`MOST_SAMPLES`]. A long history is
/// worth a well-known change (16 samples cost cornell-box's canonical move about 60 ms on
/// two cores); a drag step's short one is not (16 samples took a cornell-box drag step from
/// 96 to 148 ms, 4 iterations).
pub fn direct_samples_for(share: f32) -> u32 {
    (4.0 * share).round().clamp(4.0, MOST_SAMPLES as f32) as u32
}

/// Which samples of each slot's sequences a correction draws.
pub struct Samples {
    /// Index of the first: a move's own.
    pub first: u32,
    /// How many.
    pub count: u32,
}

/// Keys the correction's random numbers apart from every iteration's.
const CHANGE_SEED: u32 = 0x5eed_c0de;

/// A slot's estimated change of its mean direct radiance (per iteration, throughput
/// included).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectChange {
    /// The mean change over the paired samples.
    pub mean: [f32; 3],
    /// The variance of that mean's luminance, at least `lum(mean)^2 / k` for `k` samples: as
    /// uncertain as an all-or-nothing change seen by that many, so that pairs that happen to
    /// agree do not pass for an exact change.
    pub variance: f32,
}

/// The change from pose `before` to pose `after` of the direct light of each slot of `slots`
/// that `corrected` flags (`None` for the others), slot `i` keyed by its index.
pub(super) fn direct_changes(
    before: &HostPose,
    after: &HostPose,
    slots: &[HitPoint],
    corrected: &[bool],
    samples: &Samples,
    settings: &ProbeSettings,
) -> Vec<Option<DirectChange>> {
    let poses = [before, after].map(|p| (p.compiled, p.scene()));
    // Its eye paths take the light samples the eye pass takes at glossy bounces.
    let settings = ProbeSettings {
        sample_lights: true,
        ..*settings
    };
    let light = DirectLightParams {
        seed: settings.seed ^ CHANGE_SEED,
        samples: 1,
        ray_epsilon: settings.ray_epsilon,
        accumulate: direct_accumulate::REPLACE,
        ..DirectLightParams::default()
    };
    slots
        .par_iter()
        .zip(corrected)
        .enumerate()
        .map(|(slot, (hp, &corrected))| {
            corrected.then(|| {
                let slot = slot as u32;
                let points =
                    StratifiedStream::new(settings.seed ^ CHANGE_SEED, PassKind::Eye, slot);
                let diffs: Vec<Vec3> = (0..samples.count)
                    .map(|s| {
                        let k = samples.first.wrapping_add(s);
                        let key = StreamKey {
                            seed: settings.seed ^ CHANGE_SEED,
                            kind: PassKind::Eye,
                            pass_index: k,
                            path: slot,
                        };
                        let jitter = points.pair(0, k);
                        let params = DirectLightParams {
                            iteration: k,
                            ..light
                        };
                        let [a, b] = poses.map(|(pose, scene)| {
                            let path = eye_path(scene, pose, hp.pixel, jitter, &key, 0, &settings);
                            let visible = path.visible.unwrap_or(HitPoint::empty(hp.pixel));
                            slot_direct(&params, scene, &visible, &path.chain, slot).0
                        });
                        b - a
                    })
                    .collect();
                change_of(&diffs)
            })
        })
        .collect()
}

/// The mean of paired differences and its variance (see [`DirectChange::variance`]).
fn change_of(diffs: &[Vec3]) -> DirectChange {
    let k = diffs.len() as f32;
    let mean = diffs.iter().sum::<Vec3>() / k;
    let lum = |v: Vec3| luminance(v.into());
    let spread = diffs
        .iter()
        .map(|d| (lum(*d) - lum(mean)).powi(2))
        .sum::<f32>();
    let sample_variance = spread / (k * (k - 1.0)).max(1.0);
    DirectChange {
        mean: mean.into(),
        variance: sample_variance.max(lum(mean).powi(2) / k),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No change is exactly none; pairs that agree are still as uncertain as an
    /// all-or-nothing change seen by as many samples; pairs that disagree give their sample
    /// variance of the mean.
    #[test]
    fn the_change_and_how_well_it_is_known() {
        let none = change_of(&[Vec3::ZERO; 4]);
        assert_eq!((none.mean, none.variance), ([0.0; 3], 0.0));
        let agree = change_of(&[Vec3::splat(-2.0); 4]);
        assert_eq!(agree.mean, [-2.0; 3]);
        assert!((agree.variance - 1.0).abs() < 1e-5, "{agree:?}");
        // Luminances 0 and -4 in turn: mean -2, squared deviations 16 in all over 4 pairs,
        // so the mean's variance is 16 / (4 x 3).
        let split = change_of(&[Vec3::ZERO, Vec3::splat(-4.0), Vec3::ZERO, Vec3::splat(-4.0)]);
        assert_eq!(split.mean, [-2.0; 3]);
        assert!((split.variance - 16.0 / 12.0).abs() < 1e-4, "{split:?}");
    }

    /// Four pairs a pass, from 4 to the most.
    #[test]
    fn a_longer_history_draws_more_pairs() {
        assert_eq!(direct_samples_for(1.0), 4);
        assert_eq!(direct_samples_for(2.0), 8);
        assert_eq!(direct_samples_for(8.0), MOST_SAMPLES);
    }
}
