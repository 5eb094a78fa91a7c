//! A camera move's inheritance (docs/algorithm.md 3d) over the slots in parallel:
//! [`ppm_core::camera_move::inherit_slot`] for each slot of the new view, reading the slots
//! of the old one as they were kept when the move began.

use ppm_core::camera_move::{CameraMove, CameraMoveStats, inherit_slot, on_an_edge};
use ppm_core::layout::{GpuMaterial, HitPoint, SlotBounds};
use rayon::prelude::*;

/// A camera move between its passes: the request and the old view's slots.
pub struct CameraInProgress {
    /// The cameras before and after.
    pub request: CameraMove,
    /// The slots of the old view, as the move found them.
    pub before: Vec<HitPoint>,
    /// Their bounds (empty where none were recorded).
    pub before_bounds: Vec<SlotBounds>,
    /// An eye pass has started every slot fresh since the move began.
    pub traced: bool,
}

/// Each slot of `hit_points` (with its bounds, where `bounds` holds them) not on an edge of
/// the new view takes over the light of `moving`'s old slots near its visible point. The
/// edges are found first, over the fresh slots, so that no slot reads a neighbour that has
/// inherited already.
pub fn inherit_main(
    hit_points: &mut [HitPoint],
    bounds: &mut [SlotBounds],
    materials: &[GpuMaterial],
    moving: &CameraInProgress,
) -> CameraMoveStats {
    let before = (moving.before.as_slice(), moving.before_bounds.as_slice());
    let edges: Vec<bool> = (0..hit_points.len())
        .into_par_iter()
        .map(|slot| on_an_edge(hit_points, slot, &moving.request, materials))
        .collect();
    let inherit = |(hp, b): (&mut HitPoint, Option<&mut SlotBounds>), edge: bool| {
        u64::from(!edge && inherit_slot(hp, b, &moving.request, materials, before))
    };
    let inherited: u64 = if bounds.len() == hit_points.len() {
        hit_points
            .par_iter_mut()
            .zip(bounds.par_iter_mut())
            .zip(&edges)
            .map(|((hp, b), &edge)| inherit((hp, Some(b)), edge))
            .sum()
    } else {
        hit_points
            .par_iter_mut()
            .zip(&edges)
            .map(|(hp, &edge)| inherit((hp, None), edge))
            .sum()
    };
    CameraMoveStats {
        inherited,
        reset: hit_points.len() as u64 - inherited,
    }
}
