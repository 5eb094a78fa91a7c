//! Moves (docs/algorithm.md 2 and 3): the scene changes pose and the render keeps what the mode
//! lets it keep.
//!
//! Thesis and area modes remove light through the emitting rectangle with negative photons in
//! pose A and re-add it with positive ones in pose B; difference mode traces ordinary photons
//! in both poses with the same random numbers, so their deferred sum is exactly the change of
//! every path (docs/algorithm.md 3, "Convergence", names the gap it closes). After the
//! compensation, testing photons record the emissions that reach the reset slots, and guided
//! passes alternate with ordinary ones. Restart starts over on the new pose.

use super::{Renderer, dynamic, local};
use glam::Vec3;
use ppm_core::emission::{PhotonSource, ordinary_emission};
use ppm_core::layout::{EmissionRegion, GuidedEmission, RecordedPath, gather_kind, region_mode};
use ppm_core::params::{Estimator, MoveMode};
use ppm_core::passes::{BackendError, PhotonStats};
use ppm_core::refit::recompile_moved;
use ppm_core::region::{RegionError, emitting_region};
use ppm_core::rng::{DIFFERENCE_PASS_BASE, PassKind, StreamKey};
use ppm_core::scene::{Move, Scene};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Photons of one kind: emitted and deposited.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct Tally {
    /// Photons emitted.
    pub emitted: u64,
    /// Deposits stored.
    pub deposited: u64,
}

impl Tally {
    /// Adds a pass's counters.
    pub fn add(&mut self, stats: &PhotonStats) {
        self.emitted += stats.emitted;
        self.deposited += stats.deposited;
    }
}

/// Photons emitted and deposited, per kind (the thesis's tables 4.1 and 4.2).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PhotonCounts {
    /// Ordinary photons.
    pub ordinary: Tally,
    /// Compensation (negative) photons.
    pub compensation: Tally,
    /// Positive region or difference photons.
    pub region: Tally,
    /// Testing photons.
    pub testing: Tally,
    /// Guided photons.
    pub guided: Tally,
}

/// What a move did.
#[derive(Clone, Debug, Serialize)]
pub struct MoveReport {
    /// Mode used.
    pub mode: MoveMode,
    /// Area of the emitting rectangle (0 when the mode uses none or restarted).
    pub region_area: f32,
    /// Slots reset by the update.
    pub updated: u64,
    /// Slots that kept their statistics.
    pub kept: u64,
    /// Kept slots whose direct-light sum was corrected by paired shadow rays (local mode: a
    /// ray of theirs crossed a mover's box); the other modes restart every slot's sum.
    pub direct_corrected: u64,
    /// Local mode: the share of the difference passes' deposits stored (their paths crossed
    /// a mover's box), against what ordinary passes deposit per photon; the rest were culled.
    pub changed_share: Option<f64>,
    /// Local mode: the share of pose B's difference paths not traced, since they crossed no
    /// mover's box in pose A and would store nothing.
    pub culled_share: Option<f64>,
    /// Testing-photon paths recorded for guiding.
    pub recorded_paths: usize,
    /// Why the move restarted instead of compensating, if it did.
    pub restarted: Option<String>,
    /// Seconds the move took (compensation, update, region and testing passes).
    pub seconds: f64,
    /// Local mode: where those seconds went, part by part in order (the host's refit and
    /// request, then each of the backend's passes), to see what a step costs.
    pub parts: Vec<MovePart>,
}

/// A part of a move and the seconds it took.
#[derive(Clone, Debug, Serialize)]
pub struct MovePart {
    /// What it did.
    pub part: &'static str,
    /// Seconds it took.
    pub seconds: f64,
}

/// Times a move part by part: each [`Laps::lap`] names the part that ended.
pub(super) struct Laps {
    last: Instant,
    pub parts: Vec<MovePart>,
}

impl Laps {
    /// Laps from `start` on.
    pub fn from(start: Instant) -> Self {
        Self {
            last: start,
            parts: Vec::new(),
        }
    }

    /// The part since the last lap (or the start) ended: `part` names it.
    pub fn lap(&mut self, part: &'static str) {
        let now = Instant::now();
        let seconds = (now - self.last).as_secs_f64();
        self.parts.push(MovePart { part, seconds });
        self.last = now;
    }
}

impl MoveReport {
    /// A move in `mode` that has done nothing yet.
    pub fn new(mode: MoveMode) -> Self {
        Self {
            mode,
            region_area: 0.0,
            updated: 0,
            kept: 0,
            direct_corrected: 0,
            changed_share: None,
            culled_share: None,
            recorded_paths: 0,
            restarted: None,
            seconds: 0.0,
            parts: Vec::new(),
        }
    }
}

/// What compensates a move in the thesis's modes: region photons through the emitting
/// rectangle (thesis and area modes) or difference photons over the whole emission (difference
/// mode). Local mode's correction is its own passes' ([`super::local`]).
pub(super) enum Compensation {
    Region {
        region: EmissionRegion,
        /// Thesis mode's raw counts applied pass by pass; otherwise weighted and deferred.
        raw: bool,
    },
    /// Difference mode's `difference_passes` passes of ordinary photons in each pose.
    Difference,
}

impl Renderer<'_> {
    /// Moves objects of the current pose rigidly, all at once, the way `mode` says: any
    /// object, any rigid transform, none of it declared in the scene.
    pub fn move_objects(
        &mut self,
        moves: &[Move],
        mode: MoveMode,
    ) -> Result<MoveReport, BackendError> {
        let mut next = self.scene.clone();
        for (i, m) in moves.iter().enumerate() {
            next.check_move(m)
                .map_err(|why| BackendError::Unsupported(format!("move {i}: {why}")))?;
            next.apply(m);
        }
        let moved: Vec<usize> = moves.iter().map(|m| m.object).collect();
        self.move_among(next, mode, Some(&moved))
    }

    /// Moves to `next` (the same scene in another pose) the way `mode` says.
    pub fn move_to(&mut self, next: Scene, mode: MoveMode) -> Result<MoveReport, BackendError> {
        self.move_among(next, mode, None)
    }

    /// [`Self::move_to`], where only the `candidates` objects may differ in `next` if the
    /// caller knows them: a small move in a large scene then compares only their triangles.
    pub fn move_among(
        &mut self,
        next: Scene,
        mode: MoveMode,
        candidates: Option<&[usize]>,
    ) -> Result<MoveReport, BackendError> {
        let start = Instant::now();
        let mut report = MoveReport::new(mode);
        let changed = match candidates {
            Some(objects) => self.scene.changed_among(&next, objects),
            None => self.scene.changed_objects(&next),
        };
        if changed.is_empty() {
            // Nothing moved: every slot keeps everything, in every mode.
            report.kept = if self.has_image() {
                u64::from(self.params.width * self.params.height * self.params.spp)
            } else {
                0
            };
            report.seconds = start.elapsed().as_secs_f64();
            return Ok(report);
        }
        // What moved may change what the slots see: the next iteration traces them.
        self.traced = false;
        let passes = match mode {
            MoveMode::Local => self.backend.local_moves().is_some(),
            _ => self.backend.dynamic().is_some(),
        };
        let plan = if !self.has_image() {
            Err("no iteration has run: nothing to keep".to_owned())
        } else if !passes && self.backend.local_moves().is_none() {
            Err(format!(
                "backend '{}' renders still frames only (no local-move passes)",
                self.backend.name()
            ))
        } else if !passes {
            Err(format!(
                "backend '{}' has local moves but not the passes of the thesis's modes",
                self.backend.name()
            ))
        } else if mode == MoveMode::Local {
            self.local_plan(&changed).map(|()| None)
        } else {
            self.compensation_plan(mode, &next, &changed).map(Some)
        };
        let plan = match plan {
            Ok(plan) => plan,
            Err(why) => {
                self.counters.frame += 1;
                let compiled = self.compile(&next);
                self.load(next, compiled)?;
                report.restarted = Some(why);
                report.seconds = start.elapsed().as_secs_f64();
                self.report.times.moves += report.seconds;
                return Ok(report);
            }
        };
        self.focus = mode == MoveMode::Local;
        let Some(plan) = plan else {
            return self.move_locally(next, &changed, report, start);
        };
        if let Compensation::Region { region, .. } = &plan {
            report.region_area = region.area;
        }
        // Negative photons in pose A, then (same random numbers) positive ones in pose B:
        // where nothing changed their paths coincide and the two cancel almost exactly.
        self.compensate(&plan, gather_kind::REGION_NEGATIVE)?;
        let compiled = recompile_moved(&self.compiled, &next, &changed, self.spare.take());
        local(self.backend)?.update_scene(&compiled)?;
        self.report.times.bvh_build += compiled.bvh_build_time.as_secs_f64();
        self.adopt(next, compiled);
        self.counters.frame += 1;
        // Each slot traces its last sample again in the new pose: the frame's for `ppm`, the
        // last iteration's for `sppm` (its random numbers; the jitter stratum the slot's own
        // count last drew, `eye_flags::RETRACE`).
        let key = match self.params.estimator {
            Estimator::Ppm => self.counters.frame,
            Estimator::Sppm => self.counters.iteration - 1,
        };
        let (params, epsilon) = (
            self.eye_params(key, false),
            self.moves.update_epsilon * self.extent,
        );
        let update = dynamic(self.backend)?.update_hit_points(&params, epsilon)?;
        self.report.rays.eye += update.rays;
        report.updated = update.updated;
        report.kept = update.kept;
        // Direct light is recomputed for all (docs/algorithm.md 2.4): the update restarted every
        // direct sum; `ppm` draws the frame's estimate, `sppm` a first sample at the updated
        // visible points.
        match self.params.estimator {
            Estimator::Ppm => self.direct_light(self.counters.frame, false)?,
            Estimator::Sppm => {
                self.direct_light(self.counters.iteration, true)?;
                self.counters.iteration += 1;
            }
        }
        self.compensate(&plan, gather_kind::REGION_POSITIVE)?;
        // Deferred passes are applied once, as a net change (none when none ran).
        let (ran, deferred) = match plan {
            Compensation::Region { raw, .. } => {
                self.counters.region_pass += self.moves.compensation_passes;
                (self.moves.compensation_passes, !raw)
            }
            Compensation::Difference => {
                self.counters.difference_pass += self.moves.difference_passes;
                (self.moves.difference_passes, true)
            }
        };
        if deferred && ran > 0 {
            self.gather(gather_kind::REGION_APPLY, 0.0, 0.0)?;
        }
        // Testing photons: ordinary photons gathered by the updated slots only; the paths
        // that reached them are rebuilt from their index and guide later passes.
        let n = self.params.photons_per_pass;
        let testing_index = self.counters.photon_pass;
        let params = self.photon_params(testing_index, n, 1.0, gather_kind::GUIDED);
        let t = Instant::now();
        let stats = self.backend.photon_pass(&params, &PhotonSource::Lights)?;
        self.count_photons(&stats, t);
        self.counters.photon_pass += 1;
        self.counts.testing.add(&stats);
        let landed = dynamic(self.backend)?.landing_paths()?;
        self.gather(gather_kind::GUIDED, n as f32, 0.0)?;
        let paths = self.recorded_paths(testing_index, &landed);
        report.recorded_paths = paths.len();
        self.guide = (!paths.is_empty()).then(|| {
            let guide = GuidedEmission {
                cos_cone: self.moves.cone_deg.to_radians().cos(),
                beta: self.moves.beta,
                paths: paths.len() as u32,
                weighted: u32::from(mode != MoveMode::Thesis),
            };
            (guide, paths)
        });
        self.counters.steps_since_move = 0;
        report.seconds = start.elapsed().as_secs_f64();
        self.report.times.moves += report.seconds;
        Ok(report)
    }

    /// How `mode` compensates a move of the `changed` objects to their pose in `next`, or why
    /// it must restart.
    fn compensation_plan(
        &self,
        mode: MoveMode,
        next: &Scene,
        changed: &[usize],
    ) -> Result<Compensation, String> {
        let poses = [&self.scene, next];
        let kind = match mode {
            MoveMode::Restart | MoveMode::Local => return Err("restart mode".to_owned()),
            MoveMode::Difference
                if poses
                    .iter()
                    .all(|s| changed.iter().all(|&o| s.objects[o].triangles.is_empty())) =>
            {
                return Err("nothing moves".to_owned());
            }
            MoveMode::Difference => return Ok(Compensation::Difference),
            MoveMode::Thesis => region_mode::POINT,
            MoveMode::Area => region_mode::AREA,
        };
        // The moved objects' vertices in both poses, collected only here: only the thesis's
        // region reads them, and a large moved mesh would cost every local drag step its copy.
        let vertices: Vec<Vec3> = poses
            .iter()
            .flat_map(|s| changed.iter().flat_map(|&o| s.objects[o].triangles.iter()))
            .flatten()
            .copied()
            .collect();
        match emitting_region(&self.lights, &vertices, kind) {
            Ok(region) => Ok(Compensation::Region {
                region,
                raw: mode == MoveMode::Thesis,
            }),
            Err(RegionError::Empty) => Err("nothing moves".to_owned()),
            Err(RegionError::Unbounded) => {
                Err("the moving object surrounds a light point".to_owned())
            }
        }
    }

    /// All negative (pose A) or all positive (pose B) passes of a move, gathered as `kind`.
    /// Together the passes of one sign remove (or re-add) their share once: each gathers with
    /// the photons of all of them as its `N_c`. Returns the passes' summed counters.
    pub(super) fn compensate(
        &mut self,
        plan: &Compensation,
        kind: u32,
    ) -> Result<PhotonStats, BackendError> {
        let mut total_stats = PhotonStats::default();
        let sign = if kind == gather_kind::REGION_NEGATIVE {
            -1.0
        } else {
            1.0
        };
        match plan {
            Compensation::Region { region, raw } => {
                // Thesis: raw counts, each pass applied as it comes (eqs 5-7, then 1-3). Area:
                // weighted counts, deferred and applied once as a net change.
                let flag = if *raw {
                    gather_kind::RAW_COUNT
                } else {
                    gather_kind::DEFERRED
                };
                let nc = self.moves.region_photons;
                let total = (nc * self.moves.compensation_passes) as f32;
                for k in 0..self.moves.compensation_passes {
                    let index = self.counters.region_pass + k;
                    let params = self.photon_params(index, nc, sign, kind | flag);
                    let t = Instant::now();
                    let source = PhotonSource::Region(*region);
                    let stats = self.backend.photon_pass(&params, &source)?;
                    self.count_photons(&stats, t);
                    total_stats.add(&stats);
                    self.count_compensation(kind, &stats);
                    self.gather(kind | flag, 0.0, total)?;
                }
            }
            Compensation::Difference => {
                // Ordinary photons, each standing for `emitted / total` ordinary photons (path
                // weight 1); deferred, so only the paths the move changed leave a net change.
                let (n, passes) = (self.params.photons_per_pass, self.moves.difference_passes);
                let total = (n * passes) as f32;
                let gathered = kind | gather_kind::DEFERRED;
                for k in 0..passes {
                    let index = DIFFERENCE_PASS_BASE + self.counters.difference_pass + k;
                    let params = self.photon_params(index, n, sign, gathered);
                    let t = Instant::now();
                    let stats = self.backend.photon_pass(&params, &PhotonSource::Lights)?;
                    self.count_photons(&stats, t);
                    total_stats.add(&stats);
                    self.count_compensation(kind, &stats);
                    self.gather(gathered, 0.0, total)?;
                }
            }
        }
        Ok(total_stats)
    }

    /// The ordinary pass whose paths a local move's correction of `n` photons in `passes`
    /// passes traces again, if any: a one-pass correction (a drag step's) right after an
    /// ordinary pass draws that pass's random numbers. In pose A its paths are the ones the
    /// pass traced there, which a backend that kept them ([`KEEP_PATHS`](ppm_core::layout::photon_flags::KEEP_PATHS))
    /// answers without tracing them again. Sharing numbers with a pass the history gathered
    /// leaves the correction unbiased: each of the two estimates is, and their sum's
    /// expectation is the sum of theirs.
    pub(super) fn reused_pass(&self, n: u32, passes: u32) -> Option<u32> {
        let right_after = self.counters.steps_since_move > 0 && self.counters.photon_pass > 0;
        (passes == 1 && n == self.params.photons_per_pass && right_after)
            .then(|| self.counters.photon_pass - 1)
    }

    fn count_compensation(&mut self, kind: u32, stats: &PhotonStats) {
        if kind == gather_kind::REGION_NEGATIVE {
            self.counts.compensation.add(stats);
        } else {
            self.counts.region.add(stats);
        }
    }

    /// The emissions of the testing paths `landed`, rebuilt from their random numbers; a
    /// stride subsample when there are more than `max_recorded`.
    fn recorded_paths(&self, pass_index: u32, landed: &[u32]) -> Vec<RecordedPath> {
        let stride = landed.len().div_ceil(self.moves.max_recorded.max(1)).max(1);
        landed
            .iter()
            .step_by(stride)
            .map(|&path| {
                let key = StreamKey {
                    seed: self.params.seed,
                    kind: PassKind::Photon,
                    pass_index,
                    path,
                };
                let e = ordinary_emission(&self.lights, &self.materials, &key);
                RecordedPath {
                    origin: e.origin.into(),
                    light: e.light,
                    direction: e.direction.into(),
                    _pad0: 0,
                }
            })
            .collect()
    }
}
