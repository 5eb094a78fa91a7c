//! The last ordinary pass's photon paths, kept when the pass asks
//! ([`photon_flags::KEEP_PATHS`]): a local move's pose-A correction is a
//! [`photon_flags::CHANGED_ONLY`] pass with the same random numbers in the same pose, so its
//! paths are these, and which of their deposits it stores depends only on which segments cross
//! a mover's box. Testing the kept segments against the boxes gives, bit for bit, what tracing
//! the paths again gives, for a fraction of the time (docs/algorithm.md 3c, "Cost follows
//! what the object touches").

use crate::photon_pass::{Deposits, set_mask_bit};
use crate::trace::SceneData;
use glam::Vec3;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{Photon, PhotonPassParams, photon_flags};
use ppm_core::passes::PhotonStats;
use ppm_core::photon_path::{KeptPass, PathRecorder};
use rayon::prelude::*;
use std::sync::atomic::AtomicU32;

/// One ray segment of a photon path as it was traced: from `origin` along `dir` up to `t`
/// (infinite where the path left the scene).
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    /// Where the ray started (offset off the surface, as traced).
    pub origin: Vec3,
    /// Its unit direction.
    pub dir: Vec3,
    /// Distance to the surface it met.
    pub t: f32,
}

/// What tracing one batch of consecutive paths recorded, in path order.
#[derive(Default)]
pub struct BatchRecord {
    /// Index within the pass of its first path.
    pub first_path: u32,
    /// Every path's segments, one after the other.
    pub segments: Vec<Segment>,
    /// Per path, where its segments end in `segments`.
    pub segment_ends: Vec<u32>,
    /// Per deposit, the index in its path of the segment it ends.
    pub deposit_segments: Vec<u32>,
    /// Per path, where its deposits end, counted from the batch's first.
    pub deposit_ends: Vec<u32>,
    /// Index in the pass's deposits of the batch's first.
    deposit_base: u32,
}

impl BatchRecord {
    /// An empty record for the batch starting at `first_path`, reusing this one's memory (a
    /// pass's record is some megabytes, which fresh pages would fault in at every pass).
    pub fn recycled(mut self, first_path: u32) -> Self {
        self.first_path = first_path;
        self.segments.clear();
        self.segment_ends.clear();
        self.deposit_segments.clear();
        self.deposit_ends.clear();
        self
    }

    /// Ends the current path.
    pub fn end_path(&mut self) {
        self.segment_ends.push(self.segments.len() as u32);
        self.deposit_ends.push(self.deposit_segments.len() as u32);
    }
}

impl PathRecorder for BatchRecord {
    fn segment(&mut self, origin: Vec3, dir: Vec3, t: f32) {
        self.segments.push(Segment { origin, dir, t });
    }

    fn deposit(&mut self, bounce: u32) {
        self.deposit_segments.push(bounce);
    }
}

/// One ordinary pass's paths in the pose it was traced in: their segments, and which segment
/// each deposit ends (the deposits themselves stay in the photon map).
pub struct PathRecord {
    pass: KeptPass,
    batches: Vec<BatchRecord>,
}

impl PathRecord {
    /// The record of the pass `params` from its batches' records, in path order.
    pub fn new(params: &PhotonPassParams, mut batches: Vec<BatchRecord>) -> Self {
        let mut base = 0;
        for b in &mut batches {
            b.deposit_base = base;
            base += b.deposit_segments.len() as u32;
        }
        Self {
            pass: KeptPass::of(params),
            batches,
        }
    }

    /// Its batches' records, for the next pass that keeps its paths to reuse.
    pub fn into_batches(self) -> Vec<BatchRecord> {
        self.batches
    }

    /// The sign that turns the recorded deposits into those of a pass of `params` from
    /// `source` ([`KeptPass::answers`]).
    pub fn answers(&self, params: &PhotonPassParams, source: &PhotonSource<'_>) -> Option<f32> {
        self.pass.answers(params, source)
    }

    /// The deposits a [`photon_flags::CHANGED_ONLY`] pass of these paths stores in `scene`
    /// (the pose they were traced in, with its movers' boxes), their power times `sign`: those
    /// of `deposits` (the recorded pass's, in path order, as the photon map holds them) that
    /// follow a segment meeting a mover's box, the segment ending at the deposit included.
    /// With [`photon_flags::RECORD_CROSSED`] it writes the crossed-path mask as tracing does.
    /// No ray is traced.
    pub fn replay(
        &self,
        params: &PhotonPassParams,
        scene: &SceneData,
        sign: f32,
        deposits: &[Photon],
        crossed: &[AtomicU32],
    ) -> Deposits {
        let record = params.flags & photon_flags::RECORD_CROSSED != 0;
        let chunks: Vec<Vec<Photon>> = self
            .batches
            .par_iter()
            .map(|b| {
                let mut kept = Vec::new();
                let (mut s0, mut d0) = (0, 0);
                for (i, (&s1, &d1)) in b.segment_ends.iter().zip(&b.deposit_ends).enumerate() {
                    let first = b.segments[s0 as usize..s1 as usize]
                        .iter()
                        .position(|g| scene.near_mover(g.origin, g.dir, g.t));
                    let path = params.first_path + b.first_path + i as u32;
                    if record {
                        set_mask_bit(crossed, params.mask_offset + path, first.is_some());
                    }
                    if let Some(first) = first {
                        let base = (b.deposit_base + d0) as usize;
                        let segments = &b.deposit_segments[d0 as usize..d1 as usize];
                        for (photon, _) in deposits[base..]
                            .iter()
                            .zip(segments)
                            .filter(|(_, s)| **s as usize >= first)
                        {
                            kept.push(Photon {
                                power: photon.power.map(|v| v * sign),
                                ..*photon
                            });
                        }
                    }
                    (s0, d0) = (s1, d1);
                }
                kept
            })
            .collect();
        let photons: Vec<Photon> = chunks.into_iter().flatten().collect();
        let stats = PhotonStats {
            emitted: u64::from(params.photon_count),
            deposited: photons.len() as u64,
            rays: 0,
            culled: 0,
        };
        Deposits {
            photons,
            weights: None,
            partners: None,
            cancelled: Vec::new(),
            stats,
            paths: None,
        }
    }
}
