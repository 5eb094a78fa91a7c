//! The gather checks: a backend's own photon and gather passes, for each gather kind, against
//! ppm-core's gather rule applied on the host by brute force to the backend's own photons and
//! slots (docs/algorithm.md 1.4 and 3, "Who gathers what"). The static tier checks ordinary
//! photons; the local tier local mode's correction; the dynamic tier every kind the thesis's
//! modes use, in the order the driver runs them.

use super::{BackendFactory, ConformanceOptions, cornell, err, eye_params, params_for};
use crate::driver::pass_params;
use glam::Vec3;
use ppm_core::bsdf;
use ppm_core::compile::{CompiledScene, compile_scene};
use ppm_core::emission::{PhotonSource, ordinary_emission};
use ppm_core::layout::{
    EmissionRegion, GatherParams, GpuBounds, GuidedEmission, HitPoint, Photon, PhotonPassParams,
    RecordedPath, gather_kind, hit_flags, region_mode,
};
use ppm_core::local_move::{CORRECTION_GATHER, CorrectionApply, CorrectionPhotons, Pose};
use ppm_core::params::RenderParams;
use ppm_core::passes::{Backend, BackendError};
use ppm_core::region::emitting_region;
use ppm_core::rng::{PassKind, StreamKey};
use ppm_core::update::gather::{Found, SlotState, found_in_disc, gather_rule, gathers};
use ppm_core::update::pairing::{Partner, pose_a_partners};

/// Where a step's photons start.
#[derive(Clone, Copy)]
enum Source {
    Lights,
    /// Through the emitting region of [`region_mode`] `mode`, with path weights.
    Region(u32),
    /// Around a few recorded ordinary emissions, weighted.
    Guided,
}

/// One gather, after a photon pass of its own (an apply reads the pending sums instead), or a
/// photon pass held for the next step to add to.
struct Step {
    name: &'static str,
    kind: u32,
    source: Source,
    power_scale: f32,
    /// The photon pass's gather floor, in initial radii (local mode's correction).
    floor_radii: f32,
    /// What becomes of its photons.
    flow: Flow,
}

/// Whether a step's photons are gathered alone, or are a local move's correction in one of
/// its poses ([`LocalMoves::correction_photons`](ppm_core::passes::LocalMoves::correction_photons)).
#[derive(Clone, Copy, PartialEq)]
enum Flow {
    Alone,
    /// Pose A of local mode's correction: held for pose B, its deposits recorded for pose B
    /// to pair with.
    Held,
    /// Pose B: the scene's move made, the held pass's paths traced again, their deposits
    /// paired with pose A's and added to them; both gathered at once and applied
    /// ([`LocalMoves::apply_correction`](ppm_core::passes::LocalMoves::apply_correction)).
    Added,
}

const fn step(name: &'static str, kind: u32, source: Source, power_scale: f32) -> Step {
    Step {
        name,
        kind,
        source,
        power_scale,
        floor_radii: 0.0,
        flow: Flow::Alone,
    }
}

const ORDINARY: Step = step("ordinary", gather_kind::ORDINARY, Source::Lights, 1.0);

/// Every kind the thesis's modes gather, as they run them: the thesis's raw region passes,
/// area mode's deferred ones, difference mode's deferred ordinary photons, and the guided
/// photons.
const THESIS_STEPS: [Step; 9] = {
    use gather_kind::*;
    let (neg, pos) = (REGION_NEGATIVE, REGION_POSITIVE);
    let point = Source::Region(region_mode::POINT);
    let area = Source::Region(region_mode::AREA);
    [
        step("guided", GUIDED, Source::Guided, 1.0),
        step("thesis compensation", neg | RAW_COUNT, point, -1.0),
        step("thesis region", pos | RAW_COUNT, point, 1.0),
        step("area compensation", neg | DEFERRED, area, -1.0),
        step("area region", pos | DEFERRED, area, 1.0),
        step("area apply", REGION_APPLY, Source::Lights, 0.0),
        step("difference, pose A", neg | DEFERRED, Source::Lights, -1.0),
        step("difference, pose B", pos | DEFERRED, Source::Lights, 1.0),
        step("difference apply", REGION_APPLY, Source::Lights, 0.0),
    ]
};

/// Local mode's flux-only correction within a floor disc: pose A's photons held, pose B's (the
/// same paths after the scene's move) paired with pose A's and added to them, gathered once
/// ([`CORRECTION_GATHER`]) and applied ([`APPLY_CORRECTION`]).
const LOCAL_STEPS: [Step; 2] = {
    let correction = CORRECTION_GATHER;
    [
        Step {
            floor_radii: 3.0,
            flow: Flow::Held,
            ..step("local correction, pose A", correction, Source::Lights, -1.0)
        },
        Step {
            floor_radii: 3.0,
            flow: Flow::Added,
            ..step(
                "local correction, both poses",
                correction,
                Source::Lights,
                1.0,
            )
        },
    ]
};

/// The apply that follows the correction's gather.
const APPLY_CORRECTION: u32 = gather_kind::REGION_APPLY | gather_kind::ADD_FLUX;

/// `gather-formulas` (static tier): ordinary photons through the backend's own passes; then a
/// gather of another kind than the photon pass named must be refused.
pub(super) fn check_ordinary(
    make: BackendFactory,
    o: &ConformanceOptions,
) -> Result<String, String> {
    let mut bench = Bench::new(make, o)?;
    let outcome = bench.run(&ORDINARY)?.ok_or("an ordinary step gathers")?;
    outcome.verdict()?;
    let other = GatherParams {
        alpha: bench.params.alpha,
        kind: gather_kind::GUIDED,
        ..Default::default()
    };
    match bench.backend.gather_pass(&other) {
        Err(BackendError::GatherKind { .. }) => {
            Ok(format!("{outcome}; a guided gather of its map refused"))
        }
        other => Err(format!(
            "a guided gather of an ordinary pass's map gave {other:?}, not BackendError::GatherKind"
        )),
    }
}

/// `correction-kinds` (local tier): local mode's correction as [`check_every_kind`] checks
/// the thesis's kinds.
pub(super) fn check_local_kinds(
    make: BackendFactory,
    o: &ConformanceOptions,
) -> Result<String, String> {
    check_steps(make, o, &LOCAL_STEPS)
}

/// `gather-kinds` (dynamic tier): every kind the thesis's modes gather, on slots of which
/// every third is flagged updated, so that each kind's choice of who gathers and who is served
/// shows, and every second has a wide correction disc, which only local mode's correction
/// reads.
pub(super) fn check_every_kind(
    make: BackendFactory,
    o: &ConformanceOptions,
) -> Result<String, String> {
    check_steps(make, o, &THESIS_STEPS)
}

/// An ordinary pass, then `steps` on slots prepared for a move, each against the gather rule.
fn check_steps(
    make: BackendFactory,
    o: &ConformanceOptions,
    steps: &[Step],
) -> Result<String, String> {
    let mut bench = Bench::new(make, o)?;
    if let Some(outcome) = bench.run(&ORDINARY)? {
        outcome.verdict()?;
    }
    bench.prepare_move()?;
    let mut outcomes = Vec::new();
    for step in steps {
        outcomes.extend(bench.run(step)?);
    }
    let failed: Vec<String> = outcomes.iter().filter_map(|o| o.verdict().err()).collect();
    if !failed.is_empty() {
        return Err(failed.join("; "));
    }
    let worst = outcomes
        .iter()
        .min_by_key(|o| o.checked - o.off)
        .expect("steps ran");
    Ok(format!(
        "{} gathers of each kind as the gather rule by brute force; the least close: {worst}",
        outcomes.len()
    ))
}

/// How one gather compared.
struct Outcome {
    name: &'static str,
    kind: u32,
    /// The kind applied after it, if one was (local mode's correction).
    then: Option<u32>,
    checked: usize,
    off: usize,
}

impl Outcome {
    /// `kind K (name)`, and the kind applied after it.
    fn kinds(&self) -> String {
        let first = format!("kind {:#x} ({})", self.kind, self.name);
        match self.then {
            Some(then) => format!("{first} then kind {then:#x} (apply)"),
            None => first,
        }
    }
}

impl Outcome {
    /// A photon at distance^2 within rounding of r2 may fall on either side: one slot in a
    /// thousand may differ.
    fn verdict(&self) -> Result<(), String> {
        match self.off * 1000 > self.checked {
            true => Err(format!(
                "{}: {} of {} slots differ from the gather rule applied by brute force",
                self.kinds(),
                self.off,
                self.checked
            )),
            false => Ok(()),
        }
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}, {} of {} slots match",
            self.kinds(),
            self.checked - self.off,
            self.checked
        )
    }
}

/// A backend with one eye pass traced, and the host's copy of the pending sums it cannot read
/// back (compared when an apply folds them in).
struct Bench {
    backend: Box<dyn Backend>,
    compiled: CompiledScene,
    params: RenderParams,
    pending: Vec<[f32; 4]>,
    /// Emitting regions by [`region_mode`], around a box in the middle of the scene.
    regions: [EmissionRegion; 2],
    paths: Vec<RecordedPath>,
    next_pass: u32,
    /// A held step's photons, their weights and its pass index, for the step that adds to
    /// them.
    held: Option<(Vec<Photon>, Vec<f32>, u32)>,
    /// The scene after its first move: pose B of local mode's correction.
    moved: CompiledScene,
}

impl Bench {
    fn new(make: BackendFactory, o: &ConformanceOptions) -> Result<Self, String> {
        let scene = cornell()?;
        let mut params = params_for(&scene, o);
        params.width = params.width.min(32);
        params.height = params.height.min(32);
        let mut compiled = compile_scene(&scene, params.width, params.height);
        let mut moved = compile_scene(&scene.at_frame(1), params.width, params.height);
        // A mover's box around the whole scene: every path of local mode's correction crosses
        // it as it leaves the light, so the correction stores every deposit for the check.
        let (lo, hi) = compiled
            .object_bounds
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), [a, b]| {
                (lo.min(*a), hi.max(*b))
            });
        let margin = Vec3::splat(0.01 * compiled.extent);
        let everything = vec![GpuBounds::new(lo - margin, hi + margin)];
        compiled.movers.clone_from(&everything);
        moved.movers = everything;
        let mut backend = make().map_err(err)?;
        backend.load_scene(&compiled).map_err(err)?;
        backend
            .eye_pass(&eye_params(&params, compiled.extent))
            .map_err(err)?;
        let slots = backend.read_hit_points().map_err(err)?.len();
        let (lo, hi) = compiled
            .triangles
            .iter()
            .flat_map(|t| {
                let v0 = Vec3::from(t.v0);
                [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)]
            })
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let (centre, half) = ((lo + hi) * 0.5, (hi - lo) * 0.1);
        let corners: Vec<Vec3> = (0..8)
            .map(|i| centre + half * Vec3::new(sign(i, 1), sign(i, 2), sign(i, 4)))
            .collect();
        let region = |mode| {
            emitting_region(&compiled.lights, &corners, mode)
                .map_err(|e| format!("no emitting region around the scene's centre: {e:?}"))
        };
        let regions = [region(region_mode::AREA)?, region(region_mode::POINT)?];
        let paths = (0..16)
            .map(|path| {
                let key = StreamKey {
                    seed: params.seed,
                    kind: PassKind::Photon,
                    pass_index: 0,
                    path,
                };
                let e = ordinary_emission(&compiled.lights, &compiled.materials, &key);
                RecordedPath {
                    origin: e.origin.into(),
                    light: e.light,
                    direction: e.direction.into(),
                    _pad0: 0,
                }
            })
            .collect();
        Ok(Self {
            backend,
            compiled,
            params,
            pending: vec![[0.0; 4]; slots],
            regions,
            paths,
            next_pass: 0,
            held: None,
            moved,
        })
    }

    /// Flags every third slot `UPDATED`, as a hit-point update would after a move, and
    /// widens every second slot's correction disc to 4 initial radii, as a local move does
    /// far from the objects it moved (only gathers under a floor may read it).
    fn prepare_move(&mut self) -> Result<(), String> {
        let mut slots = self.backend.read_hit_points().map_err(err)?;
        for hp in slots.iter_mut().step_by(3) {
            hp.flags |= hit_flags::UPDATED;
        }
        let wide = (4.0 * self.params.initial_radius).powi(2);
        for hp in slots.iter_mut().step_by(2) {
            hp.correction_r2 = wide;
        }
        self.backend.write_hit_points(&slots).map_err(err)
    }

    /// Runs `step` on the backend and on the host, from the slots the backend holds before it
    /// (a held step only traces).
    fn run(&mut self, step: &Step) -> Result<Option<Outcome>, String> {
        let before = self.backend.read_hit_points().map_err(err)?;
        let n = self.params.photons_per_pass;
        let is_apply = step.kind & gather_kind::KIND_MASK == gather_kind::REGION_APPLY;
        let (mut photons, mut weights, r2_floor) = match is_apply {
            true => (Vec::new(), Vec::new(), 0.0),
            false => self.photon_pass(step, n)?,
        };
        let mut partners: Vec<Option<Partner>> = vec![None; photons.len()];
        match step.flow {
            Flow::Alone => {}
            Flow::Held => {
                self.held = Some((photons, weights, self.next_pass - 1));
                return Ok(None);
            }
            Flow::Added => {
                let (p, w, _) = self.held.take().ok_or("no held step to add to")?;
                partners = pose_a_partners(&p, &photons);
                partners.splice(0..0, p.iter().map(|_| None));
                photons.splice(0..0, p);
                weights.splice(0..0, w);
            }
        }
        let grows = matches!(
            step.kind & gather_kind::KIND_MASK,
            gather_kind::ORDINARY | gather_kind::GUIDED
        );
        let gather = GatherParams {
            alpha: self.params.alpha,
            emitted_increment: if grows { n as f32 } else { 0.0 },
            kind: step.kind,
            region_photons: n as f32,
        };
        let then = (step.flow == Flow::Added).then_some(APPLY_CORRECTION);
        match then {
            Some(_) => {
                let local = self.backend.local_moves().ok_or("no local-move passes")?;
                let apply = CorrectionApply {
                    alpha: self.params.alpha,
                    photons: n,
                };
                local.apply_correction(&apply).map_err(err)?;
            }
            None => {
                self.backend.gather_pass(&gather).map_err(err)?;
            }
        }
        let after = self.backend.read_hit_points().map_err(err)?;
        let r2_initial = self.params.initial_radius * self.params.initial_radius;
        let apply = GatherParams {
            kind: APPLY_CORRECTION,
            ..gather
        };
        let expected: Vec<SlotState> = before
            .iter()
            .zip(&self.pending)
            .map(|(hp, pending)| {
                let gathering = !is_apply && gathers(hp.flags, step.kind);
                let (reflectance, found) = match gathering {
                    true => (
                        self.reflectance(hp),
                        found_in_disc(hp, (&photons, &weights, &partners), r2_floor),
                    ),
                    false => (Vec3::ZERO, Found::default()),
                };
                let state = SlotState::of(hp, *pending);
                let state = gather_rule(&gather, r2_initial, reflectance.into(), state, &found);
                match then {
                    Some(_) => gather_rule(&apply, r2_initial, [0.0; 3], state, &Found::default()),
                    None => state,
                }
            })
            .collect();
        self.pending = expected.iter().map(|s| s.pending).collect();
        Ok(Some(Outcome {
            name: step.name,
            kind: step.kind,
            then,
            checked: after.len(),
            off: differing(&expected, &after),
        }))
    }

    /// Traces `step`'s photons for its kind; returns the deposits, the path weight of each
    /// (recomputed from its path's random numbers, as the contract keys them) and the floor.
    /// Deposits must carry the sign of the power scale: the host's rule, fed the backend's
    /// own photons, would follow a mis-signed pass.
    fn photon_pass(&mut self, step: &Step, n: u32) -> Result<(Vec<Photon>, Vec<f32>, f32), String> {
        let r2_floor = (step.floor_radii * self.params.initial_radius).powi(2);
        let pass = match (step.flow, &self.held) {
            (Flow::Added, Some((_, _, pass))) => *pass,
            _ => self.next_pass,
        };
        let params = PhotonPassParams {
            gather_r2_floor: r2_floor,
            ..pass_params::photon_pass(
                &self.params,
                self.compiled.extent,
                pass,
                n,
                step.power_scale,
                step.kind,
            )
        };
        self.next_pass += 1;
        let source = photon_source(&self.regions, &self.paths, step.source);
        let pose = match step.flow {
            Flow::Alone => None,
            Flow::Held => Some(Pose::A),
            Flow::Added => Some(Pose::B),
        };
        match pose {
            None => {
                self.backend.photon_pass(&params, &source).map_err(err)?;
            }
            Some(pose) => {
                let local = self.backend.local_moves().ok_or("no local-move passes")?;
                if pose == Pose::B {
                    local.update_scene(&self.moved).map_err(err)?;
                }
                let request = CorrectionPhotons {
                    pose,
                    pass: params,
                    r2_floor,
                    pair_deposits: true,
                    cull_uncrossed: false,
                };
                local.correction_photons(&request).map_err(err)?;
            }
        }
        let photons = self.backend.read_photons().map_err(err)?;
        if let Some(ph) = photons
            .iter()
            .find(|ph| ph.power.iter().any(|&c| c * step.power_scale < 0.0))
        {
            return Err(format!(
                "kind {:#x} ({}): a photon pass of power scale {} deposits power {:?} (path {})",
                step.kind, step.name, step.power_scale, ph.power, ph.path
            ));
        }
        let weights = photons
            .iter()
            .map(|ph| match source.keeps_weights() {
                true => {
                    let key = StreamKey {
                        seed: params.seed,
                        kind: source.pass_kind(),
                        pass_index: params.pass_index,
                        path: ph.path,
                    };
                    let c = &self.compiled;
                    source.emit(&c.lights, &c.materials, &key).weight
                }
                false => 1.0,
            })
            .collect();
        Ok((photons, weights, r2_floor))
    }

    /// The slot's eye-path throughput times its BSDF.
    fn reflectance(&self, hp: &HitPoint) -> Vec3 {
        let material = &self.compiled.materials[hp.material as usize];
        Vec3::from(hp.throughput) * bsdf::visible_point_f(material)
    }
}

/// The contract's form of `source`.
fn photon_source<'a>(
    regions: &[EmissionRegion; 2],
    paths: &'a [RecordedPath],
    source: Source,
) -> PhotonSource<'a> {
    match source {
        Source::Lights => PhotonSource::Lights,
        Source::Region(mode) => PhotonSource::Region(regions[mode as usize]),
        Source::Guided => PhotonSource::Guided {
            guide: GuidedEmission {
                cos_cone: 10f32.to_radians().cos(),
                beta: 0.25,
                paths: paths.len() as u32,
                weighted: 1,
            },
            paths,
        },
    }
}

fn sign(i: u32, bit: u32) -> f32 {
    if i & bit == 0 { -1.0 } else { 1.0 }
}

/// Slots whose statistics differ from `expected` beyond f32 summation order: relative 1e-4 of
/// the slot's value, or a millionth of the largest value of that field over the slots.
fn differing(expected: &[SlotState], got: &[HitPoint]) -> usize {
    let fields = |s: &SlotState| [s.n, s.r2, s.tau[0], s.tau[1], s.tau[2], s.emitted];
    let got_fields = |h: &HitPoint| [h.n, h.r2, h.tau[0], h.tau[1], h.tau[2], h.emitted];
    let mut scale = [0f32; 6];
    for s in expected {
        for (m, v) in scale.iter_mut().zip(fields(s)) {
            *m = m.max(v.abs());
        }
    }
    expected
        .iter()
        .zip(got)
        .filter(|(e, g)| {
            let close = |(a, b, m): (f32, f32, f32)| {
                (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6 * m
            };
            let (e, g) = (fields(e), got_fields(g));
            !(0..6).map(|i| (e[i], g[i], scale[i])).all(close)
        })
        .count()
}
