//! Photon pass (docs/algorithm.md 1.3): photons leave the lights with the light's whole power,
//! bounce with Russian roulette, and deposit at non-specular surfaces.

use crate::path_record::{BatchRecord, PathRecord};
use crate::trace::SceneData;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{Photon, PhotonPassParams, photon_flags};
use ppm_core::passes::PhotonStats;
use ppm_core::photon_path::{KeptPass, PathRecorder, trace_photon_path};
use ppm_core::rng::StreamKey;
use ppm_core::update::pairing::{PAIRED_DEPOSITS, Partner, partner};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Photons traced per parallel task: large enough to amortise scheduling, small enough to balance.
const CHUNK: u32 = 2048;

/// One pass's deposits, with the weight of the path that made each when the pass needs it.
pub struct Deposits {
    /// The deposits, in path order.
    pub photons: Vec<Photon>,
    /// Per deposit, its path's weight relative to an ordinary photon (region passes only).
    pub weights: Option<Vec<f32>>,
    /// Per deposit, the pose-A deposit it is paired with: position and luminance, zero
    /// luminance for none ([`photon_flags::PAIR_DEPOSITS`] in pose B only).
    pub partners: Option<Vec<[f32; 4]>>,
    /// Both deposits of each pair that cancels ([`Partner::cancels`]), as indices into the
    /// pose-A deposits followed by this pass's: they add nothing to a gather, which may leave
    /// them out.
    pub cancelled: Vec<u32>,
    /// Counters.
    pub stats: PhotonStats,
    /// The paths' segments, where the pass keeps them ([`KeptPass::wanted`]).
    pub paths: Option<PathRecord>,
}

/// Traces paths `first_path .. first_path + photon_count`, each starting where `source` says;
/// deposits come back in path order whatever the threads, with their path weights for a
/// source that keeps them (region passes count `M` in ordinary-photon units with them).
/// `crossed` is the crossed-path mask that [`photon_flags::RECORD_CROSSED`] writes and
/// [`photon_flags::CULL_UNCROSSED`] reads; it must hold the bits a recording pass writes. An
/// ordinary pass that asks ([`KeptPass::wanted`]) also returns its paths' record, written
/// into the memory of `spare` (an earlier record's batches) where there is some. A pose-B pass
/// that pairs its deposits ([`photon_flags::PAIR_DEPOSITS`]) pairs them with `pose_a`, the
/// pose-A pass's deposits in path order.
pub fn photon_pass_main(
    params: &PhotonPassParams,
    scene: &SceneData,
    source: &PhotonSource<'_>,
    crossed: &[AtomicU32],
    spare: Vec<BatchRecord>,
    pose_a: &[Photon],
) -> Deposits {
    // No light, no photon: the pass emits its count and deposits nothing.
    let chunks = if scene.lights.is_empty() {
        0
    } else {
        params.photon_count.div_ceil(CHUNK)
    };
    let record_crossed = params.flags & photon_flags::RECORD_CROSSED != 0;
    let cull = params.flags & photon_flags::CULL_UNCROSSED != 0;
    let keep_paths = KeptPass::wanted(params, source);
    let pairs = params.flags & photon_flags::PAIR_DEPOSITS != 0;
    let mut spare: Vec<Option<BatchRecord>> = spare.into_iter().map(Some).collect();
    spare.resize_with(chunks as usize, || None);
    let traced: Vec<Traced> = (0..chunks)
        .into_par_iter()
        .zip(spare)
        .map(|(c, spare)| {
            let (mut deposits, mut weights, mut rays, mut culled) = (Vec::new(), Vec::new(), 0, 0);
            let (mut partners, mut cancelled) = (Vec::new(), Vec::new());
            let mut record = keep_paths.then(|| spare.unwrap_or_default().recycled(c * CHUNK));
            let end = ((c + 1) * CHUNK).min(params.photon_count);
            for local in c * CHUNK..end {
                let path = params.first_path + local;
                if cull && !mask_bit(crossed, params.mask_offset + path) {
                    culled += 1;
                    continue;
                }
                let key = StreamKey {
                    seed: params.seed,
                    kind: source.pass_kind(),
                    pass_index: params.pass_index,
                    path,
                };
                let emission = source.emit(&scene.lights, &scene.materials, &key);
                let before = deposits.len();
                let path_crossed = if emission.weight > 0.0 {
                    let (path_rays, path_crossed) = trace_photon_path(
                        scene,
                        params,
                        &scene.movers,
                        (&key, &emission),
                        &mut deposits,
                        record.as_mut().map(|r| r as &mut dyn PathRecorder),
                    );
                    rays += path_rays;
                    path_crossed
                } else {
                    false
                };
                if let Some(r) = &mut record {
                    r.end_path();
                }
                if record_crossed {
                    set_mask_bit(crossed, params.mask_offset + path, path_crossed);
                }
                if source.keeps_weights() {
                    weights.resize(weights.len() + deposits.len() - before, emission.weight);
                }
                if pairs {
                    let (first, stored) = of_path(pose_a, path);
                    for (nth, d) in deposits[before..].iter().enumerate() {
                        let candidate = stored.get(nth).filter(|_| nth < PAIRED_DEPOSITS);
                        let a = partner(d, candidate.map(Partner::of).as_ref());
                        if a.is_some_and(|a| a.cancels(d)) {
                            let own = pose_a.len() + before + nth;
                            cancelled.extend([(first + nth) as u32, own as u32]);
                        }
                        partners
                            .push(a.map_or([0.0; 4], |a| a.position.extend(a.luminance).into()));
                    }
                }
            }
            Traced {
                deposits,
                weights,
                partners,
                cancelled,
                rays,
                culled,
                record,
            }
        })
        .collect();
    let rays = traced.iter().map(|t| t.rays).sum();
    let culled = traced.iter().map(|t| t.culled).sum();
    let mut photons = Vec::new();
    let mut weights = Vec::new();
    let mut partners = Vec::new();
    let mut records = Vec::new();
    let mut cancelled = Vec::new();
    for t in traced {
        // A task numbered its own deposits from zero after pose A's.
        let (offset, a) = (photons.len() as u32, pose_a.len() as u32);
        cancelled.extend(
            t.cancelled
                .iter()
                .map(|&i| if i < a { i } else { i + offset }),
        );
        photons.extend(t.deposits);
        weights.extend(t.weights);
        partners.extend(t.partners);
        records.extend(t.record);
    }
    let paths = keep_paths.then(|| PathRecord::new(params, records));
    let stats = PhotonStats {
        emitted: u64::from(params.photon_count),
        deposited: photons.len() as u64,
        rays,
        culled,
    };
    Deposits {
        photons,
        weights: source.keeps_weights().then_some(weights),
        partners: pairs.then_some(partners),
        cancelled,
        stats,
        paths,
    }
}

/// What one parallel task traced.
struct Traced {
    deposits: Vec<Photon>,
    weights: Vec<f32>,
    partners: Vec<[f32; 4]>,
    /// As [`Deposits::cancelled`], this task's own deposits numbered from pose A's count.
    cancelled: Vec<u32>,
    rays: u64,
    culled: u64,
    record: Option<BatchRecord>,
}

/// Path `path`'s deposits among `deposits` (in path order), and the index of the first.
fn of_path(deposits: &[Photon], path: u32) -> (usize, &[Photon]) {
    let start = deposits.partition_point(|d| d.path < path);
    let end = start + deposits[start..].partition_point(|d| d.path == path);
    (start, &deposits[start..end])
}

/// Bit `bit` of the crossed-path mask; set past its end (and wherever no pass recorded it),
/// so a missing bit never culls.
fn mask_bit(mask: &[AtomicU32], bit: u32) -> bool {
    mask.get((bit / 32) as usize)
        .is_none_or(|w| w.load(Ordering::Relaxed) & (1 << (bit % 32)) != 0)
}

/// Sets or clears bit `bit` of the crossed-path mask (atomically: neighbouring paths share
/// the word, as on the GPU).
pub fn set_mask_bit(mask: &[AtomicU32], bit: u32, value: bool) {
    let word = &mask[(bit / 32) as usize];
    let m = 1 << (bit % 32);
    if value {
        word.fetch_or(m, Ordering::Relaxed);
    } else {
        word.fetch_and(!m, Ordering::Relaxed);
    }
}
