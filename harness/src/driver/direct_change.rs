//! Local mode's direct-light correction (docs/algorithm.md 3c): how much a move changes the
//! light a kept slot sees directly, averaged over its pixel, and how well that is known.
//!
//! A slot's direct sum holds one sample per iteration, each at the visible point of that
//! iteration's jittered eye path: the pixel's average. So the change is estimated the same
//! way, by eye paths through stratified points of the pixel ([`direct_samples_for`]), each
//! traced in both poses with the same random numbers and lit there with the same light
//! sample; the pairs' spread says how well the mean is known. Traced on the host with the CPU backend's
//! scene, whatever backend renders (as [`super::probe`]): a few thousand slots' paths.

use super::probe::{EyePath, HostPose, ProbeSettings, Traced, Watch, eye_path};
use backend_cpu::direct_light::slot_direct;
use glam::Vec3;
use ppm_core::layout::{DirectLightParams, HitPoint, direct_accumulate};
use ppm_core::reach::{Aabb, segments_may_meet};
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

/// What a move may change a slot's direct light through: the moved objects' boxes in both
/// poses, and the lights' boxes.
pub(super) struct Reach<'a> {
    pub lights: &'a [Aabb],
    pub moved: &'a [Aabb],
}

impl Reach<'_> {
    /// Whether a ray from a point of `from` to a light may cross a moved box: a light
    /// sample's shadow ray, or a BSDF sample's ray that reaches a light (docs/algorithm.md
    /// 3c).
    pub fn direct_may_change(&self, from: &Aabb) -> bool {
        self.lights
            .iter()
            .any(|l| self.moved.iter().any(|m| segments_may_meet(from, l, m)))
    }
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
    reach: &Reach,
) -> Vec<Option<DirectChange>> {
    // Copied once, before the threads share them.
    let (before, after) = (before.traced(), after.traced());
    slots
        .par_iter()
        .zip(corrected)
        .enumerate()
        .map(|(slot, (hp, &corrected))| {
            corrected.then(|| {
                let diffs: Vec<Vec3> = (0..samples.count)
                    .map(|s| {
                        let k = samples.first.wrapping_add(s);
                        let pair = Pair::new(slot as u32, hp.pixel, k, settings);
                        pair.difference(&before, &after, reach)
                    })
                    .collect();
                change_of(&diffs)
            })
        })
        .collect()
}

/// One paired sample of a slot: an eye path through a point of its pixel and a light
/// sample where it ends, drawn from the same random numbers in both poses.
struct Pair {
    pixel: u32,
    slot: u32,
    jitter: (f32, f32),
    key: StreamKey,
    light: DirectLightParams,
    settings: ProbeSettings,
}

impl Pair {
    /// Sample `k` of slot `slot` (pixel `pixel`).
    fn new(slot: u32, pixel: u32, k: u32, settings: &ProbeSettings) -> Self {
        let seed = settings.seed ^ CHANGE_SEED;
        Self {
            pixel,
            slot,
            jitter: StratifiedStream::new(seed, PassKind::Eye, slot).pair(0, k),
            key: StreamKey {
                seed,
                kind: PassKind::Eye,
                pass_index: k,
                path: slot,
            },
            light: DirectLightParams {
                seed,
                iteration: k,
                samples: 1,
                ray_epsilon: settings.ray_epsilon,
                accumulate: direct_accumulate::REPLACE,
                ..DirectLightParams::default()
            },
            // Its eye paths take the light samples the eye pass takes at glossy bounces.
            settings: ProbeSettings {
                sample_lights: true,
                ..*settings
            },
        }
    }

    /// Its eye path in `pose`, noting whether it crossed one of `boxes`.
    fn trace(&self, (scene, compiled): &Traced, boxes: &[Aabb]) -> EyePath {
        let watch = Watch { groups: 0, boxes };
        eye_path(
            scene,
            compiled,
            self.pixel,
            self.jitter,
            &self.key,
            &watch,
            &self.settings,
        )
    }

    /// The direct light that `path` brings to the eye in `pose`.
    fn direct(&self, (scene, _): &Traced, path: &EyePath) -> Vec3 {
        let visible = path.visible.unwrap_or(HitPoint::empty(self.pixel));
        slot_direct(&self.light, scene, &visible, &path.chain, self.slot).0
    }

    /// Its direct light in pose `after` less that in `before`. Pose B is traced first.
    /// When its eye path neither bounced nor crossed a moved box, it is pose A's path too
    /// and is not traced again; when, besides, no ray from its visible point to a light may
    /// cross a moved box, the difference is exactly zero.
    fn difference(&self, before: &Traced, after: &Traced, reach: &Reach) -> Vec3 {
        let b = self.trace(after, reach.moved);
        let same_path = !b.crossed && !b.bounced;
        // The box of the visible point and of its rays' origin, offset along the normal.
        let same_light = |hp: &HitPoint| {
            let x = Vec3::from(hp.position);
            let offset = x + Vec3::from(hp.normal) * self.settings.ray_epsilon;
            !reach.direct_may_change(&Aabb::new(x.min(offset), x.max(offset)))
        };
        if same_path && b.visible.as_ref().is_none_or(same_light) {
            return Vec3::ZERO;
        }
        let a = if same_path {
            self.direct(before, &b)
        } else {
            self.direct(before, &self.trace(before, &[]))
        };
        self.direct(after, &b) - a
    }
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
    use ppm_core::compile::compile_scene;

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

    /// Pose A is traced only where pose B's pair may differ from it, and that changes no
    /// correction: on cornell-box (paths straight to their visible points), wedding-band
    /// (paths off the rings' mirrors) and cornell-metal (light samples at glossy bounces), the
    /// changes equal those of every pair traced in full in both poses, and some of them are
    /// not zero.
    #[test]
    fn pairs_that_cannot_change_are_traced_once_and_change_nothing() {
        // cornell-metal's copper block lifted between the gold block and the light: the gold's
        // glossy light samples are blocked where no eye path crosses the copper's box.
        let lifted = Vec3::new(60.0, 250.0, 120.0);
        for (name, moved) in [
            ("cornell-box", None),
            ("wedding-band", None),
            ("cornell-metal", Some(("short-block", lifted))),
        ] {
            let scene = scenes::builtin(name).unwrap().load().unwrap();
            let m = match moved {
                None => scene.moves[0],
                Some((object, translation)) => ppm_core::scene::Move {
                    object: scene.object_index(object).unwrap(),
                    translation,
                    rotation: glam::Quat::IDENTITY,
                },
            };
            let mut next = scene.clone();
            next.apply(&m);
            let (a, b) = (compile_scene(&scene, 48, 48), compile_scene(&next, 48, 48));
            let (before, after) = (HostPose::new(&a), HostPose::new(&b));
            let slots: Vec<HitPoint> = (0..48 * 48).map(HitPoint::empty).collect();
            let corrected = vec![true; slots.len()];
            let bounds = |s: &ppm_core::scene::Scene| {
                let (lo, hi) = s.objects[m.object].bounds();
                Aabb::new(lo, hi)
            };
            let lights: Vec<Aabb> = a
                .lights
                .iter()
                .map(|l| {
                    let v0 = Vec3::from(l.v0);
                    Aabb::of_triangle([v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)])
                })
                .collect();
            let settings = ProbeSettings {
                seed: 3,
                max_depth: 8,
                ray_epsilon: 1e-4 * a.extent,
                sample_lights: false,
            };
            let samples = Samples { first: 0, count: 4 };
            let reach = Reach {
                lights: &lights,
                moved: &[bounds(&scene), bounds(&next)],
            };
            let traced_once = direct_changes(
                &before, &after, &slots, &corrected, &samples, &settings, &reach,
            );
            let in_full: Vec<Option<DirectChange>> = (0..slots.len() as u32)
                .map(|slot| {
                    let diffs: Vec<Vec3> = (0..samples.count)
                        .map(|k| {
                            let pair = Pair::new(slot, slot, k, &settings);
                            let direct = |pose: &Traced| pair.direct(pose, &pair.trace(pose, &[]));
                            direct(&after.traced()) - direct(&before.traced())
                        })
                        .collect();
                    Some(change_of(&diffs))
                })
                .collect();
            let differ = traced_once.iter().zip(&in_full).filter(|(a, b)| a != b);
            assert_eq!(differ.count(), 0, "{name}: slots whose change differs");
            let changed = traced_once
                .iter()
                .filter(|c| c.is_some_and(|c| c.mean != [0.0; 3]))
                .count();
            assert!(changed > 20, "{name}: only {changed} slots changed");
        }
    }

    /// Four pairs a pass, from 4 to the most.
    #[test]
    fn a_longer_history_draws_more_pairs() {
        assert_eq!(direct_samples_for(1.0), 4);
        assert_eq!(direct_samples_for(2.0), 8);
        assert_eq!(direct_samples_for(8.0), MOST_SAMPLES);
    }
}
