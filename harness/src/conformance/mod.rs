//! The conformance suite: named checks that any backend implementing ppm-core's pass traits
//! must pass. A backend author calls [`run_conformance`] with a way to make the backend and
//! the [`Tier`] it claims, and gets a verdict per check; no check knows which backend it
//! tests. The CPU backend is the reference for the checks that compare.

use crate::diff::{
    OTHER_SEED_OFFSET, Recording, independent, record, record_schedule, runs_of, runs_of_schedule,
    same_seed,
};
use crate::driver::{Budget, Renderer, Schedule, local_move_request, pass_params, run};
use backend_cpu::CpuBackend;
use glam::Vec3;
use ppm_core::compile::{compile_scene, mover_boxes};
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{
    EyePassParams, HitPoint, NO_MATERIAL, PhotonPassParams, first_hit, gather_kind, hit_flags,
};
use ppm_core::params::{Estimator, MoveMode, MoveParams, RenderParams};
use ppm_core::passes::{Backend, BackendError, LocalMoveStats};
use ppm_core::qmc;
use ppm_core::rng::TEST_VECTORS;
use ppm_core::scene::path::{After, MovePath};
use ppm_core::scene::{Move, Scene};
use std::fmt;

mod gathers;

/// Makes a fresh backend for each check.
pub type BackendFactory<'a> = &'a mut dyn FnMut() -> Result<Box<dyn Backend>, BackendError>;

/// Sizes the checks render at.
#[derive(Clone, Debug)]
pub struct ConformanceOptions {
    /// Image side in pixels.
    pub size: u32,
    /// Photon passes per render.
    pub passes: u32,
    /// Photons per pass.
    pub photons_per_pass: u32,
    /// Runs per backend in the independent-seed comparison.
    pub runs: u32,
}

impl ConformanceOptions {
    /// Small enough for `cargo test` on a software adapter.
    pub fn quick() -> Self {
        Self {
            size: 48,
            passes: 4,
            photons_per_pass: 20_000,
            runs: 4,
        }
    }
}

/// What a backend claims to render: each tier's checks include the tiers below.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Tier {
    /// Still frames: any [`Backend`] plugs into the driver, the CLI and the suite (a move
    /// restarts on it).
    Static,
    /// Local moves, which keep what a move did not change: [`Backend::local_moves`] gives
    /// their passes, and local mode agrees with the CPU backend (the moves users use; the
    /// thesis's modes restart).
    Local,
    /// Every move mode: [`Backend::dynamic`] gives the thesis's passes too, and every mode
    /// agrees with the CPU backend.
    Dynamic,
}

impl fmt::Display for Tier {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Tier::Static => "static",
            Tier::Local => "local",
            Tier::Dynamic => "dynamic",
        })
    }
}

/// One check's outcome.
#[derive(Clone, Debug)]
pub struct CheckResult {
    /// Check name.
    pub name: String,
    /// Passed or not.
    pub passed: bool,
    /// What was measured, or why it failed.
    pub detail: String,
}

/// Every check's outcome.
#[derive(Clone, Debug)]
pub struct Verdict {
    /// Backend name.
    pub backend: String,
    /// The tier checked.
    pub tier: Tier,
    /// Results, in the order run.
    pub checks: Vec<CheckResult>,
}

impl Verdict {
    /// Whether every check passed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.passed)
    }

    /// The result of the check called `name`.
    pub fn check(&self, name: &str) -> Option<&CheckResult> {
        self.checks.iter().find(|c| c.name == name)
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "conformance of backend '{}', tier {}:",
            self.backend, self.tier
        )?;
        for c in &self.checks {
            writeln!(
                f,
                "  {:<4} {:<28} {}",
                if c.passed { "ok" } else { "FAIL" },
                c.name,
                c.detail
            )?;
        }
        write!(
            f,
            "{}",
            if self.passed() {
                "all checks passed"
            } else {
                "some checks FAILED"
            }
        )
    }
}

type Check = fn(BackendFactory, &ConformanceOptions) -> Result<String, String>;

/// The named checks, in order, with their tier.
pub const CHECKS: &[(&str, Tier, Check)] = &[
    ("rng-vectors", Tier::Static, check_rng_vectors),
    ("hit-point-layout", Tier::Static, check_hit_point_layout),
    ("eye-pass", Tier::Static, check_eye_pass),
    ("photon-power", Tier::Static, check_photon_power),
    ("gather-formulas", Tier::Static, gathers::check_ordinary),
    ("determinism", Tier::Static, check_determinism),
    ("agreement/same-seed", Tier::Static, check_same_seed),
    ("agreement/independent", Tier::Static, check_independent),
    ("stress-family", Tier::Static, check_still_stress),
    ("local-passes", Tier::Local, check_local_passes),
    ("local-resets", Tier::Local, check_local_resets),
    (
        "local-direct-change",
        Tier::Local,
        check_local_direct_change,
    ),
    ("correction-kinds", Tier::Local, gathers::check_local_kinds),
    ("camera-move", Tier::Local, check_camera_move),
    (
        "moves/local/same-seed",
        Tier::Local,
        check_local_moves_same_seed,
    ),
    ("moves/independent", Tier::Local, check_moves_independent),
    ("dynamic-passes", Tier::Dynamic, check_dynamic_passes),
    ("gather-kinds", Tier::Dynamic, gathers::check_every_kind),
    ("moves/same-seed", Tier::Dynamic, check_moves_same_seed),
    ("moves/stress-family", Tier::Dynamic, check_moving_stress),
];

/// Runs every check of `tier` and the tiers below against backends made by `make`.
pub fn run_conformance(make: BackendFactory, options: &ConformanceOptions, tier: Tier) -> Verdict {
    let backend = make()
        .map(|b| b.name().to_owned())
        .unwrap_or_else(|e| format!("(cannot start: {e})"));
    let checks = CHECKS
        .iter()
        .filter(|(_, of, _)| *of <= tier)
        .map(|(name, _, check)| {
            let (passed, detail) = match check(&mut *make, options) {
                Ok(detail) => (true, detail),
                Err(detail) => (false, detail),
            };
            CheckResult {
                name: (*name).to_owned(),
                passed,
                detail,
            }
        })
        .collect();
    Verdict {
        backend,
        tier,
        checks,
    }
}

fn err(e: impl fmt::Display) -> String {
    e.to_string()
}

fn cornell() -> Result<Scene, String> {
    scenes::builtin("cornell-box")
        .ok_or("no cornell-box")?
        .load()
        .map_err(err)
}

fn params_for(scene: &Scene, o: &ConformanceOptions) -> RenderParams {
    let mut p = RenderParams::for_scene(scene);
    p.width = o.size;
    p.height = o.size;
    p.passes = o.passes;
    p.photons_per_pass = o.photons_per_pass;
    p.seed = 7;
    p
}

/// The first iteration's eye pass, fresh slots, as the driver builds it.
fn eye_params(p: &RenderParams, extent: f32) -> EyePassParams {
    pass_params::eye_pass(p, extent, 0, false)
}

/// The backend's generator and stratified sequences reproduce the fixed vectors bit for bit.
fn check_rng_vectors(make: BackendFactory, _: &ConformanceOptions) -> Result<String, String> {
    let mut b = make().map_err(err)?;
    let keys: Vec<[u32; 5]> = TEST_VECTORS.iter().map(|(k, _)| *k).collect();
    let got = b.random_bits(&keys).map_err(err)?;
    for ((key, expected), got) in TEST_VECTORS.iter().zip(&got) {
        if got != expected {
            return Err(format!(
                "key {key:?}: {got:#010x}, expected {expected:#010x}"
            ));
        }
    }
    let pairs: Vec<[u32; 2]> = qmc::TEST_VECTORS.iter().map(|(k, _)| *k).collect();
    let got = b.stratified_bits(&pairs).map_err(err)?;
    for ((key, expected), got) in qmc::TEST_VECTORS.iter().zip(&got) {
        if got != expected {
            return Err(format!(
                "stratified key {key:?}: {got:#010x?}, expected {expected:#010x?}"
            ));
        }
    }
    Ok(format!(
        "{} generator and {} stratified vectors reproduced",
        keys.len(),
        pairs.len()
    ))
}

/// Slot `i` belongs to pixel `i / spp`; empty slots say so; fresh slots start with the
/// initial radius and every other statistic (direct sum and its iteration count included)
/// at zero.
fn check_hit_point_layout(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let scene = cornell()?;
    let mut p = params_for(&scene, o);
    p.spp = 2;
    let compiled = compile_scene(&scene, p.width, p.height);
    let mut b = make().map_err(err)?;
    b.load_scene(&compiled).map_err(err)?;
    b.eye_pass(&eye_params(&p, compiled.extent)).map_err(err)?;
    let hps = b.read_hit_points().map_err(err)?;
    if hps.len() != p.slots() {
        return Err(format!(
            "{} slots read back, expected {}",
            hps.len(),
            p.slots()
        ));
    }
    let r2 = p.initial_radius * p.initial_radius;
    for (i, hp) in hps.iter().enumerate() {
        let bad = if hp.pixel as usize != i / 2 {
            Some("pixel index")
        } else if !hp.is_valid() && hp.material != NO_MATERIAL {
            Some("empty slot without NO_MATERIAL")
        } else if hp.r2 != r2
            || hp.n != 0.0
            || hp.emitted != 0.0
            || hp.tau != [0.0; 3]
            || hp.direct != [0.0; 3]
            || hp.iterations != 0
        {
            Some("fresh statistics")
        } else if hp.is_valid() && (Vec3::from(hp.normal).length() - 1.0).abs() > 1e-3 {
            Some("unit normal")
        } else {
            None
        };
        if let Some(what) = bad {
            return Err(format!("slot {i}: {what} wrong: {hp:?}"));
        }
    }
    let valid = hps
        .iter()
        .filter(|h| h.flags & hit_flags::VALID != 0)
        .count();
    Ok(format!(
        "{} slots, {valid} hit points, layout as specified",
        hps.len()
    ))
}

/// Eye-pass hit points match the CPU reference's positions.
fn check_eye_pass(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let scene = cornell()?;
    let p = params_for(&scene, o);
    let compiled = compile_scene(&scene, p.width, p.height);
    let eye = |b: &mut dyn Backend| -> Result<Vec<HitPoint>, String> {
        b.load_scene(&compiled).map_err(err)?;
        b.eye_pass(&eye_params(&p, compiled.extent)).map_err(err)?;
        b.read_hit_points().map_err(err)
    };
    let reference = eye(&mut CpuBackend::new())?;
    let got = eye(make().map_err(err)?.as_mut())?;
    let tolerance = 1e-4 * compiled.extent;
    let matching = reference
        .iter()
        .zip(&got)
        .filter(|(a, b)| {
            a.is_valid() == b.is_valid()
                && Vec3::from(a.position).distance(Vec3::from(b.position)) <= tolerance
                && a.material == b.material
        })
        .count();
    let share = matching as f64 / reference.len() as f64;
    if share < 0.999 {
        return Err(format!(
            "{:.3}% of slots match the CPU eye pass (need 99.9%)",
            100.0 * share
        ));
    }
    Ok(format!(
        "{:.3}% of slots within {tolerance:.3e} of the CPU eye pass",
        100.0 * share
    ))
}

/// In the closed grey furnace (albedo 0.5, photons carrying direct light), deposits sum to
/// the emitted power times `1 + rho + rho^2 + ... = 2` per photon.
fn check_photon_power(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let scene = scenes::analytic::furnace(Vec3::splat(0.5), 1.0);
    let compiled = compile_scene(&scene, 8, 8);
    let mut b = make().map_err(err)?;
    b.load_scene(&compiled).map_err(err)?;
    let p = params_for(&scene, o);
    b.eye_pass(&eye_params(&p, compiled.extent)).map_err(err)?;
    let photons = o.photons_per_pass.max(50_000);
    let params = PhotonPassParams {
        seed: 3,
        max_depth: 24,
        first_hit: first_hit::DEPOSIT,
        ..pass_params::photon_pass(&p, compiled.extent, 0, photons, 1.0, gather_kind::ORDINARY)
    };
    b.photon_pass(&params, &PhotonSource::Lights).map_err(err)?;
    let deposits = b.read_photons().map_err(err)?;
    let total: f64 = deposits.iter().map(|d| f64::from(d.power[0])).sum();
    let ratio = total / f64::from(photons) / f64::from(compiled.light_power.x);
    // Deposits per photon are geometric (mean 2, variance 2): 4 standard errors at 50,000
    // photons is 2.5%.
    if (ratio - 2.0).abs() > 0.05 {
        return Err(format!(
            "deposited / emitted power = {ratio:.4}, expected 2"
        ));
    }
    Ok(format!(
        "deposited / emitted power = {ratio:.4} (expected 2)"
    ))
}

/// Two renders with the same seed give identical buffers.
fn check_determinism(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let scene = cornell()?;
    let p = params_for(&scene, o);
    let mut render = || -> Result<Vec<HitPoint>, String> {
        let mut b = make().map_err(err)?;
        let schedule = Schedule::frame(0, Budget::iterations(p.passes));
        run(
            b.as_mut(),
            &scene,
            &p,
            &MoveParams::default(),
            &schedule,
            &mut (),
        )
        .map_err(err)?;
        b.read_hit_points().map_err(err)
    };
    let (a, b) = (render()?, render()?);
    if bytemuck::cast_slice::<_, u8>(&a) != bytemuck::cast_slice::<_, u8>(&b) {
        return Err("two same-seed renders differ".into());
    }
    Ok(format!("{} hit points identical across two runs", a.len()))
}

/// Same seed: slots agree with the CPU reference on every built-in scene, with either
/// estimator.
fn check_same_seed(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let mut details = Vec::new();
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().map_err(err)?;
        for estimator in [Estimator::Sppm, Estimator::Ppm] {
            let mut p = params_for(&scene, o);
            p.estimator = estimator;
            p.direct_samples = estimator.default_direct_samples();
            let reference = record(&mut CpuBackend::new(), &scene, 0, &p).map_err(err)?;
            let other = record(make().map_err(err)?.as_mut(), &scene, 0, &p).map_err(err)?;
            let name = format!("{} ({})", builtin.name, estimator.name());
            details.push(agreement_line(&name, &reference, &other, &p)?);
        }
    }
    Ok(details.join(", "))
}

/// `name: share% agree` when `other` agrees with `reference` slot by slot, else the whole
/// comparison on one line.
fn agreement_line(
    name: &str,
    reference: &Recording,
    other: &Recording,
    p: &RenderParams,
) -> Result<String, String> {
    let r = same_seed::compare(reference, other, p, 3);
    let line = format!("{name}: {:.3}% agree", 100.0 * r.all_fields_share);
    if !r.agree {
        return Err(format!(
            "{line}; {}",
            same_seed::format(&r).replace('\n', "; ")
        ));
    }
    Ok(line)
}

/// The moves the `moves/` checks follow: each built-in scene's declared move in each of
/// `modes`, `passes` iterations before and after it, and where `modes` holds local mode, a
/// random path of three unplanned moves of cornell-box in it.
fn move_cases(
    o: &ConformanceOptions,
    modes: &[MoveMode],
) -> Result<Vec<(String, Scene, Schedule)>, String> {
    let budget = Budget::iterations(o.passes);
    let mut cases = Vec::new();
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().map_err(err)?;
        if scene.moves.is_empty() {
            continue;
        }
        for &mode in modes {
            let name = format!("{} {}", builtin.name, mode.name());
            cases.push((
                name,
                scene.clone(),
                Schedule::after_move(budget, mode, budget),
            ));
        }
    }
    if modes.contains(&MoveMode::Local) {
        let scene = cornell()?;
        let first = After::Iterations(o.passes);
        let path = MovePath::random(&scene, 3, 11, first, After::Iterations(2));
        cases.push((
            "cornell-box, a random path".to_owned(),
            scene,
            Schedule::path(&path, MoveMode::Local, budget),
        ));
    }
    Ok(cases)
}

/// Local moves, same seed: through the declared move of every built-in scene that has one
/// and along a random path of three unplanned moves, in local mode, the slots agree with the
/// CPU reference after every iteration and every move. Every local-move pass runs here: the
/// resets, the probe, the direct-light change and the correction.
fn check_local_moves_same_seed(
    make: BackendFactory,
    o: &ConformanceOptions,
) -> Result<String, String> {
    moves_same_seed(make, o, &[MoveMode::Local])
}

/// Moves, same seed: through the declared move of every built-in scene that has one, in the
/// thesis's modes and difference mode, the slots agree with the CPU reference after every
/// iteration and every move. Region, guided, landing and difference photons and the
/// hit-point update run here.
fn check_moves_same_seed(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let modes = [MoveMode::Difference, MoveMode::Area, MoveMode::Thesis];
    moves_same_seed(make, o, &modes)
}

/// The same-seed comparison of [`move_cases`] in `modes`.
fn moves_same_seed(
    make: BackendFactory,
    o: &ConformanceOptions,
    modes: &[MoveMode],
) -> Result<String, String> {
    let moves = MoveParams::default();
    let mut details = Vec::new();
    for (name, scene, schedule) in move_cases(o, modes)? {
        let p = params_for(&scene, o);
        let render = |backend: &mut dyn Backend| {
            record_schedule(backend, &scene, &p, &moves, &schedule).map_err(err)
        };
        let reference = render(&mut CpuBackend::new())?;
        let other = render(make().map_err(err)?.as_mut())?;
        details.push(agreement_line(&name, &reference, &other, &p)?);
    }
    Ok(details.join(", "))
}

/// Moves, independent seeds: after each built-in scene's declared move in local mode, and
/// after a random path of unplanned moves, no tile differs significantly from the CPU's.
fn check_moves_independent(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let moves = MoveParams::default();
    let mut details = Vec::new();
    for (name, scene, schedule) in move_cases(o, &[MoveMode::Local])? {
        let p = params_for(&scene, o);
        let runs = |backend: &mut dyn Backend, offset| {
            runs_of_schedule(backend, &scene, &p, &moves, &schedule, o.runs, offset).map_err(err)
        };
        let reference = runs(&mut CpuBackend::new(), 0)?;
        let other = runs(make().map_err(err)?.as_mut(), OTHER_SEED_OFFSET)?;
        let r = independent::compare(("cpu", &reference), ("other", &other), &p, 3);
        let line = format!(
            "{name}: {} of {} tests rejected, min p {:.2e}",
            r.rejected, r.tests, r.min_p
        );
        if !r.agree {
            return Err(line);
        }
        details.push(line);
    }
    Ok(details.join(", "))
}

/// Independent seeds: no tile of any built-in scene differs significantly from the CPU.
fn check_independent(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let mut details = Vec::new();
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().map_err(err)?;
        let p = params_for(&scene, o);
        let reference = runs_of(&mut CpuBackend::new(), &scene, &p, o.runs, 0).map_err(err)?;
        let other = runs_of(
            make().map_err(err)?.as_mut(),
            &scene,
            &p,
            o.runs,
            OTHER_SEED_OFFSET,
        )
        .map_err(err)?;
        let r = independent::compare(("cpu", &reference), ("other", &other), &p, 3);
        let line = format!(
            "{}: {} of {} tests rejected, min p {:.2e}",
            builtin.name, r.rejected, r.tests, r.min_p
        );
        if !r.agree {
            return Err(line);
        }
        details.push(line);
    }
    Ok(details.join(", "))
}

/// Every case of the stress family holds its invariants and closed forms.
/// The still cases of the stress family hold.
fn check_still_stress(make: BackendFactory, _: &ConformanceOptions) -> Result<String, String> {
    stress_family(make, false)
}

/// The moving cases of the stress family hold.
fn check_moving_stress(make: BackendFactory, _: &ConformanceOptions) -> Result<String, String> {
    stress_family(make, true)
}

fn stress_family(make: BackendFactory, moving: bool) -> Result<String, String> {
    let mut backend = make().map_err(err)?;
    let results: Vec<_> = scenes::stress::STRESS
        .iter()
        .filter(|case| (case.build)().moves.is_some() == moving)
        .map(|case| crate::stress::run_case(backend.as_mut(), case))
        .collect();
    let failed: Vec<String> = results
        .iter()
        .filter(|r| !r.passed)
        .map(|r| format!("{}: {}", r.case, r.verdict))
        .collect();
    if failed.is_empty() {
        Ok(format!("{} cases hold", results.len()))
    } else {
        Err(failed.join("; "))
    }
}

/// A local move's resets alone, same seed: after a few iterations of every built-in scene that
/// moves (paths straight to their visible points, off mirrors, through glass), the move's
/// first passes (`begin_local_move` in pose A, `local_resets` in pose B) start over the slots
/// the CPU backend's do, slot by slot (a probe ray that rounding sends elsewhere may part a
/// few: at most one in a thousand), and count as many.
fn check_local_resets(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    local_pass_agreement(make, o, false)
}

/// A local move's direct-light change, same seed: after the resets of
/// [`check_local_resets`], `local_direct_change` leaves each kept slot's direct sum and count
/// as the CPU backend's does (relative 1e-3; at most one slot in a thousand apart).
fn check_local_direct_change(
    make: BackendFactory,
    o: &ConformanceOptions,
) -> Result<String, String> {
    local_pass_agreement(make, o, true)
}

/// A camera move that keeps the light (docs/algorithm.md 3d), same seed: after a few
/// iterations of every built-in scene that moves, 7 degrees of orbit and a 10% dolly in local
/// mode leave each slot's statistics (`n`, `r2`, `emitted`, `tau`, the direct sum and its
/// count) as the CPU backend's do (relative 1e-3; at most one slot in a thousand apart), and
/// the move keeps as many slots; a backend that starts over instead fails, saying why.
fn check_camera_move(make: BackendFactory, o: &ConformanceOptions) -> Result<String, String> {
    let mut details = Vec::new();
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().map_err(err)?;
        if scene.moves.is_empty() {
            continue;
        }
        let p = params_for(&scene, o);
        let camera = scene.camera.orbited(7.0, 0.1);
        let run = |backend: &mut dyn Backend| -> Result<_, String> {
            let mut render =
                Renderer::start(backend, scene.clone(), &p, &MoveParams::default()).map_err(err)?;
            for _ in 0..p.passes {
                render.iteration().map_err(err)?;
            }
            let report = render
                .move_camera(camera.clone(), MoveMode::Local)
                .map_err(err)?;
            if let Some(why) = report.restarted {
                return Err(format!(
                    "{}: the camera move started over: {why}",
                    builtin.name
                ));
            }
            Ok((
                render.backend().read_hit_points().map_err(err)?,
                report.kept,
            ))
        };
        let (reference, cpu_kept) = run(&mut CpuBackend::new())?;
        let (slots, kept) = run(make().map_err(err)?.as_mut())?;
        let close = |x: f32, y: f32| (x - y).abs() <= 1e-3 * x.abs().max(y.abs()) + 1e-30;
        let apart = reference
            .iter()
            .zip(&slots)
            .filter(|(a, b)| {
                let fields = [
                    (a.n, b.n),
                    (a.r2, b.r2),
                    (a.emitted, b.emitted),
                    (a.tau[0], b.tau[0]),
                    (a.tau[1], b.tau[1]),
                    (a.tau[2], b.tau[2]),
                    (a.direct[0], b.direct[0]),
                    (a.direct[1], b.direct[1]),
                    (a.direct[2], b.direct[2]),
                ];
                a.iterations != b.iterations || fields.iter().any(|&(x, y)| !close(x, y))
            })
            .count();
        let line = format!(
            "{}: {kept} slots kept their light ({cpu_kept} on the CPU), {apart} of {} slots apart",
            builtin.name,
            slots.len()
        );
        if apart * 1000 > slots.len() || slots.len() != reference.len() {
            return Err(line);
        }
        details.push(line);
    }
    Ok(details.join(", "))
}

/// The slots after a local move's passes on the backend and on the CPU backend, on every
/// built-in scene that moves: the resets (their `UPDATED` flags), and with `direct` the
/// direct sums and counts after the direct-light change.
fn local_pass_agreement(
    make: BackendFactory,
    o: &ConformanceOptions,
    direct: bool,
) -> Result<String, String> {
    let mut details = Vec::new();
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().map_err(err)?;
        let Some(&step) = scene.moves.first() else {
            continue;
        };
        let p = params_for(&scene, o);
        let run = |backend: &mut dyn Backend| {
            local_passes(backend, &scene, step, &p, direct).map_err(err)
        };
        let (reference, cpu) = run(&mut CpuBackend::new())?;
        let (slots, stats) = run(make().map_err(err)?.as_mut())?;
        let apart = reference
            .iter()
            .zip(&slots)
            .filter(|(a, b)| match direct {
                false => (a.flags ^ b.flags) & hit_flags::UPDATED != 0,
                true => {
                    let close = |x: f32, y: f32| (x - y).abs() <= 1e-3 * x.abs().max(y.abs());
                    a.iterations != b.iterations || (0..3).any(|c| !close(a.direct[c], b.direct[c]))
                }
            })
            .count();
        let line = format!(
            "{}: {} reset, {} corrected ({} and {} on the CPU), {apart} of {} slots apart",
            builtin.name,
            stats.reset,
            stats.direct_corrected,
            cpu.reset,
            cpu.direct_corrected,
            slots.len()
        );
        if apart * 1000 > slots.len() || slots.len() != reference.len() {
            return Err(line);
        }
        details.push(line);
    }
    Ok(details.join(", "))
}

/// `backend`'s slots after `o.passes`-like iterations of `scene` and the passes of a local
/// move of `step` (its resets, and with `direct` its direct-light change), and the resets'
/// counters.
fn local_passes(
    backend: &mut dyn Backend,
    scene: &Scene,
    step: Move,
    p: &RenderParams,
    direct: bool,
) -> Result<(Vec<HitPoint>, LocalMoveStats), BackendError> {
    let mut render = Renderer::start(backend, scene.clone(), p, &MoveParams::default())?;
    for _ in 0..p.passes {
        render.iteration()?;
    }
    let mut next = scene.clone();
    next.apply(&step);
    let (mut a, mut b) = (
        compile_scene(scene, p.width, p.height),
        compile_scene(&next, p.width, p.height),
    );
    let movers = mover_boxes(scene, &next, &[step.object], a.extent);
    (a.movers, b.movers) = (movers.clone(), movers);
    let request = local_move_request((&a, &b), &[step.object], p, (1.0, 1.0, 8));
    let backend = render.backend();
    let local = backend.local_moves().ok_or_else(|| {
        BackendError::Unsupported("no local-move passes (Backend::local_moves is None)".into())
    })?;
    local.update_scene(&a)?;
    local.begin_local_move(&request)?;
    local.update_scene(&b)?;
    let stats = local.local_resets()?;
    if direct {
        local.local_direct_change()?;
    }
    Ok((backend.read_hit_points()?, stats))
}

/// The backend gives its local-move passes ([`Backend::local_moves`]); without them every
/// move restarts, and the moves checks cannot pass.
fn check_local_passes(make: BackendFactory, _: &ConformanceOptions) -> Result<String, String> {
    let mut backend = make().map_err(err)?;
    match backend.local_moves() {
        Some(_) => Ok("scene update, local resets and direct-light change".into()),
        None => Err(format!(
            "backend '{}' gives no local-move passes (Backend::local_moves is None): it renders \
             still frames only, the static tier",
            backend.name()
        )),
    }
}

/// The backend gives the passes of the thesis's modes ([`Backend::dynamic`]); without them
/// a move in those modes restarts, and their checks cannot pass.
fn check_dynamic_passes(make: BackendFactory, _: &ConformanceOptions) -> Result<String, String> {
    let mut backend = make().map_err(err)?;
    match backend.dynamic() {
        Some(_) => Ok("hit-point update, region, guided and landing passes".into()),
        None => Err(format!(
            "backend '{}' gives no dynamic passes (Backend::dynamic is None): the thesis's \
             modes restart on it",
            backend.name()
        )),
    }
}
