//! Hit-point update after a move (docs/algorithm.md 2.4): the eye pass runs again on the new pose,
//! and only slots whose visible point changed start over; every slot's direct sum restarts.

use crate::eye_pass::eye_pass_main;
use crate::gather_pass::Pending;
use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::layout::{ChainLight, EyePassParams, GpuCamera, HitPoint, eye_flags, hit_flags};
use ppm_core::passes::UpdateStats;
use rayon::prelude::*;

/// Object index stored in a hit point's flags.
pub fn object_of(hp: &HitPoint) -> u32 {
    hp.flags >> hit_flags::OBJECT_SHIFT
}

/// Compares a fresh eye pass with `hit_points` and resets the slots that changed (and their
/// pending region photons); `chain` takes what the fresh paths' glossy bounces found.
pub fn update_hit_points_main(
    params: &EyePassParams,
    camera: &GpuCamera,
    scene: &SceneData,
    epsilon: f32,
    hit_points: &mut [HitPoint],
    pending: &mut [Pending],
    chain: Option<&mut [ChainLight]>,
) -> UpdateStats {
    // Each slot's last sample again: the re-trace reads the stratum from the slot's copy.
    let mut fresh = hit_points.to_vec();
    let fresh_params = EyePassParams {
        flags: params.flags & !(eye_flags::KEEP_STATISTICS | eye_flags::RECORD_BOUNDS)
            | eye_flags::RETRACE,
        ..*params
    };
    let eye = eye_pass_main(&fresh_params, camera, scene, &mut fresh, None, chain);
    let updated: u64 = hit_points
        .par_iter_mut()
        .zip(&fresh)
        .zip(pending.par_iter_mut())
        .map(|((old, new), pending)| {
            let same = old.is_valid() == new.is_valid()
                && (!new.is_valid()
                    || (object_of(old) == object_of(new)
                        && Vec3::from(old.position).distance(Vec3::from(new.position)) <= epsilon));
            if same {
                old.flags &= !hit_flags::UPDATED;
                old.direct = [0.0; 3];
                old.iterations = 0;
                0
            } else {
                *old = *new;
                *pending = [0.0; 4];
                if new.is_valid() {
                    old.flags |= hit_flags::UPDATED;
                }
                1
            }
        })
        .sum();
    UpdateStats {
        updated,
        kept: hit_points.len() as u64 - updated,
        rays: eye.rays,
    }
}
