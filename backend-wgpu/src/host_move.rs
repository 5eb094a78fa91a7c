//! A local move's passes on the host: the slots read back, ppm-core's per-slot functions run
//! over them with both poses traced through their flattened trees, and the slots written
//! back. The device kernels that replace this read and write no slot.

use glam::Vec3;
use ppm_core::compile::CompiledScene;
use ppm_core::layout::{HitPoint, SlotBounds, hit_flags};
use ppm_core::local_move::{
    LocalMove, PairInPose, View, correct_direct, moved_cover, prepare_slot, reset_if_seen,
};
use ppm_core::passes::LocalMoveStats;
use ppm_core::reach::Aabb;
use ppm_core::trace::FlatPose;

/// Where a local move stands between its passes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Begun in pose A; the scene update to pose B comes next.
    Begun,
    /// In pose B; the resets come next.
    PoseB,
    /// Resets done; the direct-light change comes next.
    Reset,
}

/// A local move in progress.
pub struct HostMove {
    /// What moves.
    pub request: LocalMove,
    /// Pose A.
    pub before: CompiledScene,
    /// Where the move stands.
    pub stage: Stage,
}

/// The pairs the last move traced in its pose B, and the pose and request they belong to.
pub struct KnownPairs {
    pose: u64,
    request: LocalMove,
    slots: Vec<Box<[PairInPose]>>,
}

/// A slot's recorded box, or every point where none was recorded.
fn slot_box(bounds: &[SlotBounds], i: usize) -> Aabb {
    bounds.get(i).map_or(Aabb::new(Vec3::MIN, Vec3::MAX), |b| {
        Aabb::new(b.min.into(), b.max.into())
    })
}

/// [`prepare_slot`] for every slot.
pub fn begin(slots: &mut [HitPoint], bounds: &[SlotBounds], request: &LocalMove) {
    let moved = request.moved();
    for (i, hp) in slots.iter_mut().enumerate() {
        prepare_slot(hp, &slot_box(bounds, i), request, &moved);
    }
}

/// [`reset_if_seen`] for every slot, in pose B (`after`).
pub fn resets(
    slots: &mut [HitPoint],
    bounds: &[SlotBounds],
    after: &CompiledScene,
    request: &LocalMove,
) -> LocalMoveStats {
    let pose = FlatPose::new(after);
    let camera = &after.camera;
    let covered = moved_cover(&pose, camera, &request.objects);
    let nearest = request.nearest_after(camera.eye.into());
    let mut stats = LocalMoveStats::default();
    for (i, hp) in slots.iter_mut().enumerate() {
        let covered = covered[hp.pixel as usize];
        let (view, reset) = reset_if_seen(
            hp,
            &slot_box(bounds, i),
            covered,
            (&pose, camera, nearest),
            request,
        );
        stats.reset += u64::from(reset);
        stats.probed += u64::from(view == View::Probe);
        stats.direct_corrected += u64::from(!reset && hp.flags & hit_flags::DIRECT_MAY_CHANGE != 0);
    }
    stats.kept = slots.len() as u64 - stats.reset;
    stats
}

/// [`correct_direct`] for every slot, from pose A (`before`) to pose B (`after`); `known`:
/// the last move's pairs. Returns the counters and this move's pairs.
pub fn direct_change(
    slots: &mut [HitPoint],
    (before, after): (&CompiledScene, &CompiledScene),
    request: &LocalMove,
    known: Option<&KnownPairs>,
) -> (LocalMoveStats, KnownPairs) {
    let known = known.filter(|k| {
        k.pose == before.pose && k.request.seed == request.seed && k.request.paths == request.paths
    });
    let moved = request.moved();
    let (a, b) = (FlatPose::new(before), FlatPose::new(after));
    let pairs: Vec<Box<[PairInPose]>> = slots
        .iter_mut()
        .enumerate()
        .map(|(slot, hp)| {
            let known = known.and_then(|k| k.slots.get(slot)).map(|p| &p[..]);
            let poses = (&a, &b, &after.camera);
            correct_direct(hp, slot as u32, poses, (request, &moved), known).unwrap_or_default()
        })
        .collect();
    let stats = LocalMoveStats {
        direct_corrected: pairs.iter().filter(|p| !p.is_empty()).count() as u64,
        ..LocalMoveStats::default()
    };
    let known = KnownPairs {
        pose: after.pose,
        request: request.clone(),
        slots: pairs,
    };
    (stats, known)
}
