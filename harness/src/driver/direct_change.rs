//! Local mode's direct-light correction (docs/algorithm.md 3c): how much a move changes the
//! light a kept slot sees directly, averaged over its pixel, and how well that is known.
//!
//! A slot's direct sum holds one sample per iteration, each at the visible point of that
//! iteration's jittered eye path: the pixel's average. So the change is estimated the same
//! way, by eye paths through stratified points of the pixel ([`direct_samples_for`]), each
//! traced in both poses with the same random numbers and lit there with the same light
//! sample; the pairs' spread says how well the mean is known. Traced on the host with the CPU backend's
//! scene, whatever backend renders (as [`super::probe`]): a few thousand slots' paths.
//!
//! Every move draws a slot's pairs from the same random numbers, so what they found in a
//! move's pose B is what the next move's would find in its pose A: it is kept
//! ([`PairsInPose`]) and a drag traces each pose once. Each move's correction stays
//! unbiased, its pairs being drawn independently of the slot's iterations; successive
//! moves' errors then cancel along a drag (their sum is one estimate of the whole change)
//! instead of adding up.

use super::probe::{HostPose, ProbeSettings, Traced, eye_path};
use glam::Vec3;
use ppm_core::direct_light::slot_direct;
use ppm_core::eye_path::{EyePath, Watch, camera_segment};
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

/// A pair's eye path in the pose it was traced in, and its direct light there if it was
/// evaluated: the next move's pose A.
#[derive(Clone, Copy)]
struct PairInPose {
    path: EyePath,
    light: Option<Vec3>,
}

/// Each corrected slot's pairs in a move's pose B, by slot (none for the others), kept for
/// the next move, whose pose A that is.
#[derive(Default)]
pub(super) struct PairsInPose {
    /// What they were traced with: a move that traces with other settings (the ray offset
    /// follows the scene's extent) does not take them.
    settings: Option<ProbeSettings>,
    slots: Vec<Box<[PairInPose]>>,
}

impl PairsInPose {
    /// Pair `k` of slot `slot`, if it was traced.
    fn get(&self, slot: usize, k: u32) -> Option<&PairInPose> {
        self.slots.get(slot)?.get(k as usize)
    }
}

/// The change from pose `before` to pose `after` of the direct light of each slot of `slots`
/// that `corrected` flags (`None` for the others), slot `i` keyed by its index, from
/// `samples` pairs each; and the pairs in pose `after`. `known` holds pairs traced in pose
/// `before` by the last move, if it left that pose.
pub(super) fn direct_changes(
    (before, after): (&HostPose, &HostPose),
    slots: &[HitPoint],
    corrected: &[bool],
    samples: u32,
    settings: &ProbeSettings,
    reach: &Reach,
    known: Option<&PairsInPose>,
) -> (Vec<Option<DirectChange>>, PairsInPose) {
    // Copied once, before the threads share them.
    let (before, after) = (before.traced(), after.traced());
    let known = known.filter(|k| k.settings == Some(*settings));
    let (changes, pairs): (Vec<_>, Vec<_>) = slots
        .par_iter()
        .zip(corrected)
        .enumerate()
        .map(|(slot, (hp, &corrected))| {
            if !corrected {
                return (None, Box::default());
            }
            let (diffs, pairs): (Vec<Vec3>, Vec<PairInPose>) = (0..samples)
                .map(|k| {
                    let pair = Pair::new(slot as u32, hp.pixel, k, settings);
                    let known = known.and_then(|p| p.get(slot, k));
                    pair.difference(&before, &after, reach, known)
                })
                .unzip();
            (Some(change_of(&diffs)), pairs.into_boxed_slice())
        })
        .unzip();
    let settings = Some(*settings);
    (
        changes,
        PairsInPose {
            settings,
            slots: pairs,
        },
    )
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
        let visible = path
            .visible
            .map_or(HitPoint::empty(self.pixel), |v| v.hit_point(self.pixel));
        slot_direct(&self.light, *scene, &visible, &path.chain, self.slot).0
    }

    /// Its direct light in pose `after` less that in `before`, and the pair in pose `after`.
    /// `known` is the pair in pose `before`, if a move left it: its light is pose A's, and
    /// when its path went straight to its visible point without crossing a moved box, it is
    /// pose B's path too. Otherwise pose B is traced first. When its eye path neither bounced
    /// nor crossed a moved box, it is pose A's path too and is not traced again; when,
    /// besides, no ray from its visible point to a light may cross a moved box, the
    /// difference is exactly zero.
    fn difference(
        &self,
        before: &Traced,
        after: &Traced,
        reach: &Reach,
        known: Option<&PairInPose>,
    ) -> (Vec3, PairInPose) {
        let straight = |path: &EyePath| {
            let (origin, dir) = camera_segment(&after.1.camera, self.pixel, self.jitter);
            let watch = Watch {
                groups: 0,
                boxes: reach.moved,
            };
            !path.chained && !watch.crossed(origin, dir, path.first_t)
        };
        let b = match known {
            // Its crossing was just tested against this move's boxes, not the last move's.
            Some(a) if straight(&a.path) => EyePath {
                crossed: false,
                ..a.path
            },
            _ => self.trace(after, reach.moved),
        };
        let same_path = !b.crossed && !b.chained;
        // The box of the visible point and of its rays' origin, offset along the normal.
        let same_light = |hp: &HitPoint| {
            let x = Vec3::from(hp.position);
            let offset = x + Vec3::from(hp.normal) * self.settings.ray_epsilon;
            !reach.direct_may_change(&Aabb::new(x.min(offset), x.max(offset)))
        };
        let known_light = known.and_then(|a| a.light);
        if same_path
            && b.visible
                .map(|v| v.hit_point(self.pixel))
                .as_ref()
                .is_none_or(same_light)
        {
            let unchanged = PairInPose {
                path: b,
                light: known_light,
            };
            return (Vec3::ZERO, unchanged);
        }
        let a = known_light.unwrap_or_else(|| match known {
            Some(a) => self.direct(before, &a.path),
            None if same_path => self.direct(before, &b),
            None => self.direct(before, &self.trace(before, &[])),
        });
        let light = self.direct(after, &b);
        let pair = PairInPose {
            path: b,
            light: Some(light),
        };
        (light - a, pair)
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
    use ppm_core::compile::{CompiledScene, compile_scene};
    use ppm_core::scene::{Move, Scene};

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

    /// The scenes the tests below move, each with a move: cornell-box (paths straight to
    /// their visible points), wedding-band (paths off the rings' mirrors) and cornell-metal
    /// (light samples at glossy bounces; its copper block lifted between the gold block and
    /// the light, so that the gold's glossy light samples are blocked where no eye path
    /// crosses the copper's box).
    fn moved_scenes() -> Vec<(&'static str, Scene, Move)> {
        let lifted = Vec3::new(60.0, 250.0, 120.0);
        [
            ("cornell-box", None),
            ("wedding-band", None),
            ("cornell-metal", Some(("short-block", lifted))),
        ]
        .into_iter()
        .map(|(name, moved)| {
            let scene = scenes::builtin(name).unwrap().load().unwrap();
            let m = match moved {
                None => scene.moves[0],
                Some((object, translation)) => Move {
                    object: scene.object_index(object).unwrap(),
                    translation,
                    rotation: glam::Quat::IDENTITY,
                },
            };
            (name, scene, m)
        })
        .collect()
    }

    const SIZE: u32 = 48;

    /// What `direct_changes` needs besides the poses, for a move of `object` from `scene`
    /// to `next`: every slot corrected, its lights' and the object's boxes, the settings.
    struct Setting {
        slots: Vec<HitPoint>,
        corrected: Vec<bool>,
        lights: Vec<Aabb>,
        moved: [Aabb; 2],
        settings: ProbeSettings,
    }

    impl Setting {
        fn new(compiled: &CompiledScene, (scene, next): (&Scene, &Scene), object: usize) -> Self {
            let bounds = |s: &Scene| {
                let (lo, hi) = s.objects[object].bounds();
                Aabb::new(lo, hi)
            };
            let slots: Vec<HitPoint> = (0..SIZE * SIZE).map(HitPoint::empty).collect();
            Self {
                corrected: vec![true; slots.len()],
                slots,
                lights: compiled
                    .lights
                    .iter()
                    .map(|l| {
                        let v0 = Vec3::from(l.v0);
                        Aabb::of_triangle([v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)])
                    })
                    .collect(),
                moved: [bounds(scene), bounds(next)],
                settings: ProbeSettings {
                    seed: 3,
                    max_depth: 8,
                    ray_epsilon: 1e-4 * compiled.extent,
                    sample_lights: false,
                },
            }
        }

        fn changes(
            &self,
            poses: (&HostPose, &HostPose),
            known: Option<&PairsInPose>,
        ) -> (Vec<Option<DirectChange>>, PairsInPose) {
            let reach = Reach {
                lights: &self.lights,
                moved: &self.moved,
            };
            let (slots, corrected) = (&self.slots, &self.corrected);
            direct_changes(poses, slots, corrected, 4, &self.settings, &reach, known)
        }
    }

    /// Pose A is traced only where pose B's pair may differ from it, and that changes no
    /// correction: on every scene of [`moved_scenes`], the changes equal those of every pair
    /// traced in full in both poses, and some of them are not zero.
    #[test]
    fn pairs_that_cannot_change_are_traced_once_and_change_nothing() {
        for (name, scene, m) in moved_scenes() {
            let mut next = scene.clone();
            next.apply(&m);
            let a = compile_scene(&scene, SIZE, SIZE);
            let b = compile_scene(&next, SIZE, SIZE);
            let (before, after) = (HostPose::new(&a), HostPose::new(&b));
            let setting = Setting::new(&a, (&scene, &next), m.object);
            let (traced_once, _) = setting.changes((&before, &after), None);
            let in_full: Vec<Option<DirectChange>> = (0..SIZE * SIZE)
                .map(|slot| {
                    let diffs: Vec<Vec3> = (0..4)
                        .map(|k| {
                            let pair = Pair::new(slot, slot, k, &setting.settings);
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

    /// Along a drag (a third of each scene's move, three times), a move that takes its pose
    /// A's pairs from the last move finds the changes of one that traces both poses, bit for
    /// bit, and does take them: kept lights or kept paths made wrong change its result, unless
    /// they were traced with other settings.
    #[test]
    fn a_drag_traces_each_pose_once_and_changes_nothing() {
        for (name, scene, m) in moved_scenes() {
            let step = Move {
                translation: m.translation / 3.0,
                rotation: glam::Quat::IDENTITY.slerp(m.rotation, 1.0 / 3.0),
                ..m
            };
            let mut poses = vec![scene];
            for _ in 0..3 {
                let mut next = poses.last().unwrap().clone();
                next.apply(&step);
                poses.push(next);
            }
            let compiled: Vec<CompiledScene> =
                poses.iter().map(|s| compile_scene(s, SIZE, SIZE)).collect();
            let mut known: Option<PairsInPose> = None;
            for w in 0..3 {
                let (before, after) =
                    (HostPose::new(&compiled[w]), HostPose::new(&compiled[w + 1]));
                let setting = Setting::new(&compiled[w], (&poses[w], &poses[w + 1]), m.object);
                let (fresh, _) = setting.changes((&before, &after), None);
                let (reused, pairs) = setting.changes((&before, &after), known.as_ref());
                let differ = fresh.iter().zip(&reused).filter(|(a, b)| a != b).count();
                assert_eq!(differ, 0, "{name}, move {w}: slots whose change differs");
                if let Some(kept) = &known {
                    let wrong = |f: &dyn Fn(&PairInPose) -> PairInPose| PairsInPose {
                        settings: kept.settings,
                        slots: kept
                            .slots
                            .iter()
                            .map(|s| s.iter().map(f).collect())
                            .collect(),
                    };
                    let brighter = wrong(&|p| PairInPose {
                        light: p.light.map(|l| l * 2.0 + Vec3::ONE),
                        ..*p
                    });
                    let moved_point = wrong(&|p| {
                        let mut p = *p;
                        if let Some(v) = p.path.visible.as_mut() {
                            v.position[1] += 0.25 * compiled[w].extent;
                        }
                        p
                    });
                    for (what, wrong) in [("lights", brighter), ("paths", moved_point)] {
                        let (changes, _) = setting.changes((&before, &after), Some(&wrong));
                        let differ = fresh.iter().zip(&changes).filter(|(a, b)| a != b).count();
                        assert!(
                            differ > 10,
                            "{name}, move {w}: wrong {what} changed {differ} slots"
                        );
                        // Pairs traced with another ray offset are not taken.
                        let offset = setting.settings.ray_epsilon * 2.0;
                        let other = PairsInPose {
                            settings: wrong.settings.map(|s| ProbeSettings {
                                ray_epsilon: offset,
                                ..s
                            }),
                            ..wrong
                        };
                        let (changes, _) = setting.changes((&before, &after), Some(&other));
                        assert!(
                            changes == fresh,
                            "{name}, move {w}: pairs of other settings taken"
                        );
                    }
                }
                known = Some(pairs);
            }
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
