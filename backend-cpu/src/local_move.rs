//! A local move's passes (docs/algorithm.md 3b and 3c) over the slots in parallel:
//! [`ppm_core::local_move`]'s per-slot functions, with pose A kept beside pose B for the
//! move's duration (its buffers shared, not copied), so that a pair traces pose A only where
//! its path or light may differ there; and the pairs a move found in its pose B kept for the
//! next move, whose pose A that is, so that a drag traces each pose once.

use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::check::slot_is_finite;
use ppm_core::layout::{GpuCamera, HitPoint, SlotBounds, hit_flags};
use ppm_core::local_move::{
    LocalMove, PairInPose, View, correct_direct, prepare_slot, reset_if_seen,
};
use ppm_core::passes::LocalMoveStats;
use ppm_core::reach::Aabb;
use ppm_core::screen_cover::covered_pixels_in_tree;
use rayon::prelude::*;

/// Where a local move stands between its passes.
pub enum Stage {
    /// Begun in pose A; the scene update to pose B comes next.
    Begun,
    /// In pose B; the resets come next.
    PoseB,
    /// Resets done; the direct-light change comes next.
    Reset,
}

/// A local move in progress: its request, pose A, and its stage.
pub struct MoveInProgress {
    /// What moves.
    pub request: LocalMove,
    /// Pose A, as the backend held it when the move began.
    pub before: SceneData,
    /// Where the move stands.
    pub stage: Stage,
}

/// The pairs a move traced in its pose B, slot by slot (none for slots it did not correct):
/// the next move's pose A, if that move starts from this pose with the same settings.
pub struct KnownPairs {
    /// The pose they were traced in ([`SceneData::pose`]).
    pose: u64,
    /// What keyed and traced them.
    request: LocalMove,
    slots: Vec<Box<[PairInPose]>>,
}

impl KnownPairs {
    /// The pairs, if traced in `pose` by a move keyed and traced as `request` is.
    fn valid_for(&self, pose: u64, request: &LocalMove) -> bool {
        self.pose == pose
            && self.request.seed == request.seed
            && self.request.paths == request.paths
    }
}

/// A slot's recorded box, or every point where none was recorded.
fn slot_box(bounds: &[SlotBounds], i: usize) -> Aabb {
    bounds.get(i).map_or(Aabb::new(Vec3::MIN, Vec3::MAX), |b| {
        Aabb::new(b.min.into(), b.max.into())
    })
}

/// [`prepare_slot`] for every slot.
pub fn begin_main(hit_points: &mut [HitPoint], bounds: &[SlotBounds], request: &LocalMove) {
    let moved = request.moved();
    hit_points
        .par_iter_mut()
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, hp)| prepare_slot(hp, &slot_box(bounds, i), request, &moved));
}

/// The resets of a local move in pose B (`scene`, `camera`): each slot whose view the move
/// may change starts over ([`reset_if_seen`]). Returns the counters, and whether every slot
/// it started over is finite ([`slot_is_finite`], screened as each is written: the others
/// keep what earlier passes screened, and a sweep of every slot cost a fiftieth of a step).
pub fn resets_main(
    hit_points: &mut [HitPoint],
    bounds: &[SlotBounds],
    (scene, camera): (&SceneData, &GpuCamera),
    request: &LocalMove,
) -> (LocalMoveStats, bool) {
    let covered = moved_cover(scene, camera, &request.objects);
    let nearest = request.nearest_after(camera.eye.into());
    let (reset, corrected, probed, finite) = hit_points
        .par_iter_mut()
        .enumerate()
        .with_min_len(256)
        .map(|(i, hp)| {
            let covered = covered[hp.pixel as usize];
            let poses = (scene, camera, nearest);
            let (view, reset) = reset_if_seen(hp, &slot_box(bounds, i), covered, poses, request);
            let corrected = !reset && hp.flags & hit_flags::DIRECT_MAY_CHANGE != 0;
            (
                u64::from(reset),
                u64::from(corrected),
                u64::from(view == View::Probe),
                !reset || slot_is_finite(hp),
            )
        })
        .reduce(
            || (0, 0, 0, true),
            |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2, a.3 & b.3),
        );
    let stats = LocalMoveStats {
        reset,
        kept: hit_points.len() as u64 - reset,
        direct_corrected: corrected,
        probed,
        rays: 0,
    };
    (stats, finite)
}

/// [`ppm_core::local_move::moved_cover`], found over the moved objects' own subtrees
/// ([`covered_pixels_in_tree`]): a moved mesh of tens of thousands of triangles was a drag
/// step's largest part after the tree's refit when each triangle was projected.
fn moved_cover(scene: &SceneData, camera: &GpuCamera, objects: &[u32]) -> Vec<bool> {
    let roots: Vec<u32> = objects
        .iter()
        .map(|&o| scene.spans[o as usize].root)
        .filter(|&root| root != u32::MAX)
        .collect();
    covered_pixels_in_tree(camera, &scene.nodes, &scene.triangles, &roots)
}

/// The direct-light change of a local move in pose B (`after`): each kept slot flagged
/// `DIRECT_MAY_CHANGE` with a direct sum is corrected by its pairs ([`correct_direct`]),
/// pose A traced only where they may differ, and not at all where `known` holds them.
/// Returns the counters, the pairs in pose B (for the next move), and whether every
/// corrected direct sum is finite (the only field the change writes).
pub fn direct_change_main(
    hit_points: &mut [HitPoint],
    (before, after, camera): (&SceneData, &SceneData, &GpuCamera),
    request: &LocalMove,
    known: Option<&KnownPairs>,
) -> (LocalMoveStats, KnownPairs, bool) {
    let known = known.filter(|k| k.valid_for(before.pose, request));
    let moved = request.moved();
    // Each corrected sum screened as it is written.
    let (pairs, finite): (Vec<_>, Vec<bool>) = hit_points
        .par_iter_mut()
        .enumerate()
        .map(|(slot, hp)| {
            let known = known.and_then(|p| p.slots.get(slot)).map(|p| &p[..]);
            let poses = (before, after, camera);
            let pairs = correct_direct(hp, slot as u32, poses, (request, &moved), known);
            let finite = pairs.is_none() || hp.direct.iter().all(|v| v.is_finite());
            (pairs, finite)
        })
        .unzip();
    let finite = finite.iter().all(|&f| f);
    let stats = LocalMoveStats {
        direct_corrected: pairs.iter().filter(|p| p.is_some()).count() as u64,
        ..LocalMoveStats::default()
    };
    let pairs = KnownPairs {
        pose: after.pose,
        request: request.clone(),
        slots: pairs.into_iter().map(Option::unwrap_or_default).collect(),
    };
    (stats, pairs, finite)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_core::compile::{CompiledScene, compile_scene};
    use ppm_core::eye_path::EyePathSettings;
    use ppm_core::layout::HitPoint;
    use ppm_core::local_move::{DirectChange, Pair, change_of};
    use ppm_core::scene::{Move, Scene};

    const SIZE: u32 = 48;
    const SAMPLES: u32 = 4;

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

    /// The move of `object` from `scene` to `next` (compiled as `a`) as the passes see it,
    /// every slot flagged for the direct-light change, with one iteration of direct light.
    fn request(a: &CompiledScene, (scene, next): (&Scene, &Scene), object: usize) -> LocalMove {
        let bounds = |s: &Scene| {
            let (lo, hi) = s.objects[object].bounds();
            Aabb::new(lo, hi)
        };
        LocalMove {
            objects: vec![object as u32],
            groups: ppm_core::compile::object_group(object),
            before: vec![bounds(scene)],
            after: vec![bounds(next)],
            lights: a
                .lights
                .iter()
                .map(|l| {
                    let v0 = Vec3::from(l.v0);
                    Aabb::of_triangle([v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)])
                })
                .collect(),
            seed: 3,
            paths: EyePathSettings {
                max_depth: 8,
                ray_epsilon: 1e-4 * a.extent,
                sample_lights: false,
            },
            r2_initial: 1.0,
            r2_floor: 1.0,
            widest: 1.0,
            direct_samples: SAMPLES,
        }
    }

    /// Slots flagged for the direct-light change, each with one iteration of direct light.
    fn slots() -> Vec<HitPoint> {
        (0..SIZE * SIZE)
            .map(|pixel| HitPoint {
                flags: hit_flags::DIRECT_MAY_CHANGE,
                iterations: 1,
                direct: [1.0; 3],
                ..HitPoint::empty(pixel)
            })
            .collect()
    }

    /// The direct sums after the move's change from `a` to `b`, and the pairs in `b`.
    fn changed(
        (a, b): (&CompiledScene, &CompiledScene),
        request: &LocalMove,
        known: Option<&KnownPairs>,
    ) -> (Vec<[f32; 3]>, KnownPairs) {
        let mut slots = slots();
        let (before, after) = (SceneData::new(a), SceneData::new(b));
        let poses = (&before, &after, &b.camera);
        let (_, pairs, finite) = direct_change_main(&mut slots, poses, request, known);
        assert!(finite, "the corrected direct sums are finite");
        (slots.iter().map(|hp| hp.direct).collect(), pairs)
    }

    /// The change screens what it writes: a corrected sum that comes out not finite is
    /// reported, so the backend names it (the pass sweeps every slot only then).
    #[test]
    fn a_corrected_sum_left_not_finite_is_reported() {
        let (_, scene, m) = moved_scenes().swap_remove(0);
        let mut next = scene.clone();
        next.apply(&m);
        let (a, b) = (
            compile_scene(&scene, SIZE, SIZE),
            compile_scene(&next, SIZE, SIZE),
        );
        let request = request(&a, (&scene, &next), m.object);
        let (before, after) = (SceneData::new(&a), SceneData::new(&b));
        let poses = (&before, &after, &b.camera);
        let mut fine = slots();
        let (stats, _, finite) = direct_change_main(&mut fine, poses, &request, None);
        assert!(finite && stats.direct_corrected > 0, "{stats:?}");
        let mut broken = slots();
        broken[SIZE as usize * 20 + 17].direct[1] = f32::INFINITY;
        let (_, _, finite) = direct_change_main(&mut broken, poses, &request, None);
        assert!(!finite);
    }

    /// Pose A is traced only where pose B's pair may differ from it, and that changes no
    /// correction: on every scene of [`moved_scenes`], the changes equal those of every pair
    /// traced in full in both poses, and some of them are not zero.
    #[test]
    fn pairs_that_cannot_change_are_traced_once_and_change_nothing() {
        for (name, scene, m) in moved_scenes() {
            let mut next = scene.clone();
            next.apply(&m);
            let (a, b) = (
                compile_scene(&scene, SIZE, SIZE),
                compile_scene(&next, SIZE, SIZE),
            );
            let (before, after) = (SceneData::new(&a), SceneData::new(&b));
            let request = request(&a, (&scene, &next), m.object);
            let moved = request.moved();
            let mut changed = 0;
            for slot in 0..SIZE * SIZE {
                let pairs: Vec<Pair> = (0..SAMPLES)
                    .map(|k| Pair::new(slot, slot, k, &request))
                    .collect();
                let once: Vec<Vec3> = pairs
                    .iter()
                    .map(|p| {
                        let poses = (&before, &after, &b.camera);
                        p.difference(poses, (&request.lights, &moved), None).0
                    })
                    .collect();
                let in_full: Vec<Vec3> = pairs
                    .iter()
                    .map(|p| {
                        let direct =
                            |pose: &SceneData| p.direct(pose, &p.trace(pose, &b.camera, &[]));
                        direct(&after) - direct(&before)
                    })
                    .collect();
                let (x, y): (DirectChange, DirectChange) = (change_of(&once), change_of(&in_full));
                assert_eq!(x, y, "{name}: slot {slot}");
                changed += usize::from(x.mean != [0.0; 3]);
            }
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
            let mut known: Option<KnownPairs> = None;
            for w in 0..3 {
                let ab = (&compiled[w], &compiled[w + 1]);
                let request = request(&compiled[w], (&poses[w], &poses[w + 1]), m.object);
                let (fresh, _) = changed(ab, &request, None);
                let (reused, pairs) = changed(ab, &request, known.as_ref());
                assert_eq!(
                    fresh, reused,
                    "{name}, move {w}: reused pairs change the result"
                );
                if let Some(kept) = &known {
                    let wrong = |f: &dyn Fn(&PairInPose) -> PairInPose| KnownPairs {
                        pose: kept.pose,
                        request: kept.request.clone(),
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
                            v.position.y += 0.25 * compiled[w].extent;
                        }
                        p
                    });
                    for (what, wrong) in [("lights", brighter), ("paths", moved_point)] {
                        let (directs, _) = changed(ab, &request, Some(&wrong));
                        let differ = fresh.iter().zip(&directs).filter(|(a, b)| a != b).count();
                        assert!(
                            differ > 10,
                            "{name}, move {w}: wrong {what} changed {differ} slots"
                        );
                        // Pairs traced with another ray offset are not taken.
                        let mut other = wrong;
                        other.request.paths.ray_epsilon *= 2.0;
                        let (directs, _) = changed(ab, &request, Some(&other));
                        assert_eq!(
                            directs, fresh,
                            "{name}, move {w}: pairs of other settings taken"
                        );
                    }
                }
                known = Some(pairs);
            }
        }
    }
}
