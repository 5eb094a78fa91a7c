//! Eye pass (docs/algorithm.md 1.1): each slot's visible point, where its eye path first meets a
//! non-specular surface ([`ppm_core::eye_path::slot_eye_path`]), over the slots in parallel.

use crate::trace::SceneData;
use ppm_core::eye_path::{extended_bounds, slot_eye_path};
use ppm_core::layout::{ChainLight, EyePassParams, GpuCamera, HitPoint, SlotBounds, eye_flags};
use ppm_core::passes::EyeStats;
use rayon::iter::Either;
use rayon::prelude::*;

/// Writes the visible point of every slot of `hit_points` (`width * height * spp` slots,
/// slot = pixel * spp + sample), starting the slots fresh or keeping their statistics as
/// `params.flags` says; with [`eye_flags::RECORD_BOUNDS`], extends each slot's `bounds`;
/// with `chain` (a scene with glossy surfaces), writes the light its glossy bounces found.
pub fn eye_pass_main(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    hit_points: &mut [HitPoint],
    bounds: Option<&mut [SlotBounds]>,
    chain: Option<&mut [ChainLight]>,
) -> EyeStats {
    let slots = hit_points.len();
    let record = params.flags & eye_flags::RECORD_BOUNDS != 0;
    let bounds = if record { bounds } else { None };
    let (rays, visible) = hit_points
        .par_iter_mut()
        .zip(each_or_none(bounds, slots))
        .zip(each_or_none(chain, slots))
        .enumerate()
        .with_min_len(256)
        .map(|(slot, ((hp, b), c))| {
            let path = slot_eye_path(params, camera, scene, slot as u32, hp);
            if let Some(b) = b {
                *b = extended_bounds(*b, hp, path.vertices);
            }
            if let (Some(c), Some(found)) = (c, path.chain) {
                *c = found;
            }
            (path.rays, u64::from(hp.is_valid()))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    EyeStats {
        rays,
        hit_points: visible,
    }
}

/// Each element of `slice` as `Some`, or `None` `len` times.
fn each_or_none<T: Send>(
    slice: Option<&mut [T]>,
    len: usize,
) -> impl IndexedParallelIterator<Item = Option<&mut T>> {
    match slice {
        Some(slice) => Either::Left(slice.par_iter_mut().map(Some)),
        None => Either::Right((0..len).into_par_iter().map(|_| None)),
    }
}
