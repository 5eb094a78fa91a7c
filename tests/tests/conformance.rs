//! Both backends pass the conformance suite; deliberately broken backends are caught: a gather
//! that drops photons by the same-seed and the independent-seed comparison alike, compensation
//! photons of the wrong sign by the moves check alone.

use backend_cpu::CpuBackend;
use harness::conformance::{ConformanceOptions, Tier, run_conformance};
use harness::diff::{OTHER_SEED_OFFSET, runs_of};
use harness::diff::{independent, record, same_seed};
use harness::driver::checkpoint::RenderState;
use harness::driver::{Budget, Resume, Schedule};
use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::compile::CompiledScene;
use ppm_core::emission::PhotonSource;
use ppm_core::image::Image;
use ppm_core::layout::*;
use ppm_core::local_move::LocalMove;
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::*;
use std::process::ExitCode;
use tests::{BackendTrials, Suite, figure};

/// Every in-tree backend passes every tier.
fn every_backend_passes_conformance(name: &str, _: Box<dyn Backend + Send>) {
    let registry = harness::registry::Registry::in_tree();
    let verdict = run_conformance(
        &mut || registry.start(name).map(|b| b as Box<dyn Backend>),
        &ConformanceOptions::quick(),
        Tier::Dynamic,
    );
    figure!("{verdict}");
    assert!(verdict.passed(), "{verdict}");
}

/// The CPU backend with one fault.
#[derive(Clone, Copy)]
enum Fault {
    /// A faulty gather from photon pass `from_pass` on: one photon in ten (every tenth
    /// deposit) is never found, as if the gather skipped it. It moves those photons out of
    /// every disc's reach after the photon pass, so the grid still files them and only the
    /// gather misses them.
    DropsOneInTen { from_pass: u32 },
    /// Compensation photons traced with positive power: still frames are the CPU's exactly,
    /// every move adds what it should remove.
    MisSignsCompensation,
    /// No fault in what it renders, but it gives no dynamic passes: a still-frame backend,
    /// which the static tier passes and every move restarts on.
    StillFramesOnly,
    /// Negative photons that empty a slot leave its `emitted` as it was, where the gather
    /// rule starts it over with the statistics: the photons it gathers next are divided by
    /// everything emitted before the move.
    SkipsEmptiedReset,
    /// A gather of this kind (flags included) leaves every slot's flux 1% too high.
    SkewsKind(u32),
    /// A pass asked to add its photons to the last pass's replaces them
    /// ([`photon_flags::ADD_TO_MAP`] ignored): a local correction keeps pose B's photons only.
    IgnoresAddToMap,
    /// A correction's pose B counts each deposit's own square
    /// ([`photon_flags::PAIR_DEPOSITS`] ignored): kept slots give up history a move did not
    /// change.
    IgnoresPairing,
    /// A local move's resets start no slot over: what a moved object newly covers keeps its
    /// stale light.
    ResetsNothing,
    /// A local move's direct-light change leaves every direct sum as it was.
    SkipsDirectChange,
    /// A camera move's inheritance counts the slots kept but leaves each as the fresh eye
    /// pass left it: the render starts over while it says it kept its light.
    InheritsNothing,
}

struct Broken(CpuBackend, Fault);

impl Broken {
    /// `p` as this backend misreads it.
    fn misread(&self, p: &PhotonPassParams) -> PhotonPassParams {
        match self.1 {
            Fault::MisSignsCompensation => PhotonPassParams {
                power_scale: p.power_scale.abs(),
                ..*p
            },
            Fault::IgnoresAddToMap => PhotonPassParams {
                flags: p.flags & !photon_flags::ADD_TO_MAP,
                ..*p
            },
            Fault::IgnoresPairing => PhotonPassParams {
                flags: p.flags & !photon_flags::PAIR_DEPOSITS,
                ..*p
            },
            Fault::DropsOneInTen { .. }
            | Fault::StillFramesOnly
            | Fault::SkipsEmptiedReset
            | Fault::SkewsKind(_)
            | Fault::ResetsNothing
            | Fault::SkipsDirectChange
            | Fault::InheritsNothing => *p,
        }
    }
}

impl SceneUpload for Broken {
    fn load_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.0.load_scene(scene)
    }
}
impl EyePass for Broken {
    fn eye_pass(&mut self, p: &EyePassParams) -> Result<EyeStats, BackendError> {
        self.0.eye_pass(p)
    }
}
impl DirectLight for Broken {
    fn direct_light(&mut self, p: &DirectLightParams) -> Result<DirectStats, BackendError> {
        self.0.direct_light(p)
    }
}
impl PhotonPass for Broken {
    fn photon_pass(
        &mut self,
        p: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        if let Fault::StillFramesOnly = self.1 {
            source.lights_only("broken")?;
        }
        let stats = self.0.photon_pass(&self.misread(p), source)?;
        if let Fault::DropsOneInTen { from_pass } = self.1
            && p.pass_index >= from_pass
        {
            for photon in self.0.photons_mut().iter_mut().step_by(10) {
                photon.position = [f32::MAX; 3];
            }
        }
        Ok(stats)
    }
}
impl GatherPass for Broken {
    fn gather_pass(&mut self, p: &GatherParams) -> Result<GatherStats, BackendError> {
        if let Fault::SkewsKind(kind) = self.1
            && kind == p.kind
        {
            let stats = self.0.gather_pass(p)?;
            let mut slots = self.0.read_hit_points()?;
            for hp in &mut slots {
                hp.tau = hp.tau.map(|t| t * 1.01);
            }
            self.0.write_hit_points(&slots)?;
            return Ok(stats);
        }
        if !matches!(self.1, Fault::SkipsEmptiedReset) {
            return self.0.gather_pass(p);
        }
        let before = self.0.read_hit_points()?;
        let stats = self.0.gather_pass(p)?;
        let mut after = self.0.read_hit_points()?;
        let mut skipped = false;
        for (a, b) in after.iter_mut().zip(&before) {
            if b.n > 0.0 && a.n == 0.0 && b.emitted > 0.0 && a.emitted == 0.0 {
                a.emitted = b.emitted;
                skipped = true;
            }
        }
        if skipped {
            self.0.write_hit_points(&after)?;
        }
        Ok(stats)
    }
}
impl Resolve for Broken {
    fn resolve(&mut self, p: &ResolveParams) -> Result<Image, BackendError> {
        self.0.resolve(p)
    }
}
impl ReadBack for Broken {
    fn read_hit_points(&mut self) -> Result<Vec<HitPoint>, BackendError> {
        self.0.read_hit_points()
    }
    fn read_photons(&mut self) -> Result<Vec<Photon>, BackendError> {
        self.0.read_photons()
    }
    fn write_hit_points(&mut self, hit_points: &[HitPoint]) -> Result<(), BackendError> {
        self.0.write_hit_points(hit_points)
    }
}
impl RandomSource for Broken {
    fn random_bits(&mut self, keys: &[[u32; 5]]) -> Result<Vec<u32>, BackendError> {
        self.0.random_bits(keys)
    }
    fn stratified_bits(&mut self, keys: &[[u32; 2]]) -> Result<Vec<[u32; 2]>, BackendError> {
        self.0.stratified_bits(keys)
    }
}
impl Backend for Broken {
    fn name(&self) -> &str {
        "broken"
    }
    fn local_moves(&mut self) -> Option<&mut dyn LocalMoves> {
        match self.1 {
            Fault::StillFramesOnly => None,
            _ => Some(self),
        }
    }
    fn dynamic(&mut self) -> Option<&mut dyn DynamicBackend> {
        match self.1 {
            Fault::StillFramesOnly => None,
            _ => Some(self),
        }
    }
}
impl LocalMoves for Broken {
    fn update_scene(&mut self, scene: &CompiledScene) -> Result<(), BackendError> {
        self.0.update_scene(scene)
    }
    fn begin_local_move(&mut self, request: &LocalMove) -> Result<(), BackendError> {
        self.0.begin_local_move(request)
    }
    fn local_resets(&mut self) -> Result<LocalMoveStats, BackendError> {
        let before = self.0.read_hit_points()?;
        let stats = self.0.local_resets()?;
        if let Fault::ResetsNothing = self.1 {
            self.0.write_hit_points(&before)?;
            return Ok(LocalMoveStats {
                reset: 0,
                kept: before.len() as u64,
                ..stats
            });
        }
        Ok(stats)
    }
    fn local_direct_change(&mut self) -> Result<LocalMoveStats, BackendError> {
        let before = self.0.read_hit_points()?;
        let stats = self.0.local_direct_change()?;
        if let Fault::SkipsDirectChange = self.1 {
            self.0.write_hit_points(&before)?;
        }
        Ok(stats)
    }
    fn begin_camera_move(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        self.0.begin_camera_move(request)
    }
    fn inherit_light(&mut self) -> Result<CameraMoveStats, BackendError> {
        let fresh = self.0.read_hit_points()?;
        let stats = self.0.inherit_light()?;
        if let Fault::InheritsNothing = self.1 {
            self.0.write_hit_points(&fresh)?;
        }
        Ok(stats)
    }
}
impl DynamicBackend for Broken {
    fn update_hit_points(
        &mut self,
        p: &EyePassParams,
        epsilon: f32,
    ) -> Result<UpdateStats, BackendError> {
        self.0.update_hit_points(p, epsilon)
    }
    fn landing_paths(&mut self) -> Result<Vec<u32>, BackendError> {
        self.0.landing_paths()
    }
}

fn cornell_params() -> (ppm_core::scene::Scene, RenderParams) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut p = RenderParams::for_scene(&scene);
    p.width = 64;
    p.height = 64;
    p.passes = 4;
    p.photons_per_pass = 30_000;
    // The thesis's 20 mm rather than the scene's 10: at 64x64 after four passes, enough
    // photons per hit point that dropping one in ten stands out in every tile.
    p.initial_radius = 20.0;
    (scene, p)
}

fn same_seed_mode_catches_a_gather_that_drops_one_photon_in_ten() {
    let (scene, p) = cornell_params();
    let reference = record(&mut CpuBackend::new(), &scene, 0, &p).unwrap();
    let honest = record(&mut CpuBackend::new(), &scene, 0, &p).unwrap();
    let broken = record(
        &mut Broken(CpuBackend::new(), Fault::DropsOneInTen { from_pass: 0 }),
        &scene,
        0,
        &p,
    )
    .unwrap();
    let good = same_seed::compare(&reference, &honest, &p, 5);
    let bad = same_seed::compare(&reference, &broken, &p, 5);
    figure!("{}", harness::diff::same_seed::format(&bad));
    insta::assert_snapshot!(
        "same_seed_table_broken",
        harness::diff::same_seed::format(&bad)
    );
    insta::assert_json_snapshot!("same_seed_json_broken", bad);
    let rows = harness::diff::history::pixel_history(&[&reference, &broken], &p, 31, 44);
    insta::assert_snapshot!(
        "pixel_history_broken",
        harness::diff::history::format(&rows)
    );
    assert!(good.agree && good.all_fields_share == 1.0);
    assert!(!bad.agree, "the broken gather went unnoticed");
    let n = bad.fields.iter().find(|f| f.field == "n").unwrap();
    assert!(
        n.share < 0.5,
        "most hit points should see fewer photons: {n:?}"
    );
    assert!(
        bad.first_divergence.iter().any(|p| p.pass == 1),
        "divergence starts at the first gather"
    );
}

/// A gather that goes wrong at the third iteration: the same-seed recordings part there, the
/// state saved just before it replays that iteration alone on both backends (they part at
/// once), and the honest backend's replay ends exactly where its uninterrupted run did.
fn the_state_before_the_first_divergence_replays_it_alone() {
    let (scene, p) = cornell_params();
    let faulty = || Broken(CpuBackend::new(), Fault::DropsOneInTen { from_pass: 2 });
    let reference = record(&mut CpuBackend::new(), &scene, 0, &p).unwrap();
    let broken = record(&mut faulty(), &scene, 0, &p).unwrap();
    assert_eq!(same_seed::first_disagreement(&reference, &broken), Some(3));
    assert_eq!(same_seed::first_disagreement(&reference, &reference), None);

    let state = harness::diff::state_after(&mut CpuBackend::new(), &scene, &p, 2).unwrap();
    let dir = std::env::temp_dir().join(format!("ppm-replay-{}", std::process::id()));
    state.write(&dir).unwrap();
    let state = RenderState::read(&dir).unwrap();
    let replay = |backend: &mut dyn DynamicBackend| {
        let schedule = Schedule::frame(0, Budget::iterations(p.passes - 2));
        let resume = Some(Resume {
            state: &state,
            dir: &dir,
        });
        let moves = MoveParams::default();
        harness::diff::record_schedule_from(backend, &scene, &p, &moves, &schedule, resume).unwrap()
    };
    let (honest, broken) = (replay(&mut CpuBackend::new()), replay(&mut faulty()));
    assert_eq!(same_seed::first_disagreement(&honest, &broken), Some(1));
    assert_eq!(
        bytemuck::cast_slice::<_, u8>(honest.passes.last().unwrap()),
        bytemuck::cast_slice::<_, u8>(reference.passes.last().unwrap()),
        "the replay continues the uninterrupted run bit for bit"
    );
}

fn independent_mode_catches_a_gather_that_drops_one_photon_in_ten() {
    let (scene, p) = cornell_params();
    let reference = runs_of(&mut CpuBackend::new(), &scene, &p, 4, 0).unwrap();
    let honest = runs_of(&mut CpuBackend::new(), &scene, &p, 4, OTHER_SEED_OFFSET).unwrap();
    let broken = runs_of(
        &mut Broken(CpuBackend::new(), Fault::DropsOneInTen { from_pass: 0 }),
        &scene,
        &p,
        4,
        OTHER_SEED_OFFSET,
    )
    .unwrap();
    let good = independent::compare(("cpu", &reference), ("cpu", &honest), &p, 5);
    let bad = independent::compare(("cpu", &reference), ("broken", &broken), &p, 5);
    figure!("{}", harness::diff::independent::format(&bad));
    insta::assert_snapshot!(
        "independent_table_broken",
        harness::diff::independent::format(&bad)
    );
    assert!(good.agree, "false alarm on two honest CPU runs: {good:?}");
    assert!(!bad.agree, "the broken gather went unnoticed");
}

fn conformance_fails_the_broken_backend_on_both_agreement_checks() {
    let verdict = run_conformance(
        &mut || {
            Ok(Box::new(Broken(
                CpuBackend::new(),
                Fault::DropsOneInTen { from_pass: 0 },
            )))
        },
        &ConformanceOptions::quick(),
        Tier::Dynamic,
    );
    figure!("{verdict}");
    assert!(!verdict.check("agreement/same-seed").unwrap().passed);
    assert!(!verdict.check("agreement/independent").unwrap().passed);
    // Its gather is consistent with the photons it reads back (the fault hides them), and its
    // generator is the CPU's: only the comparisons with the reference can see the fault.
    assert!(verdict.check("gather-formulas").unwrap().passed);
    assert!(verdict.check("rng-vectors").unwrap().passed);
}

/// A backend whose compensation photons carry positive power renders every still frame as
/// the CPU does, so the still-frame checks pass it; both moves checks fail it, and the gather
/// check at the first negative kind.
fn conformance_fails_a_backend_that_mis_signs_compensation_photons_on_moves() {
    let verdict = run_conformance(
        &mut || {
            Ok(Box::new(Broken(
                CpuBackend::new(),
                Fault::MisSignsCompensation,
            )))
        },
        &ConformanceOptions::quick(),
        Tier::Dynamic,
    );
    figure!("{verdict}");
    for moves in [
        "moves/same-seed",
        "moves/local/same-seed",
        "moves/independent",
    ] {
        assert!(!verdict.check(moves).unwrap().passed, "{moves}: {verdict}");
    }
    let kinds = verdict.check("gather-kinds").unwrap();
    assert!(
        !kinds.passed && kinds.detail.contains("(thesis compensation)"),
        "{verdict}"
    );
    for still in [
        "agreement/same-seed",
        "agreement/independent",
        "gather-formulas",
        "determinism",
    ] {
        assert!(verdict.check(still).unwrap().passed, "{still}: {verdict}");
    }
}

/// The dynamic tier on a backend with `fault`, which renders still frames as the CPU does:
/// it fails the moves check `moves` that compares slots, and the gather check `kinds` at the
/// step named `step`, and passes the still checks.
fn fails_on_moves_only(fault: Fault, (moves, kinds, step): (&str, &str, &str)) {
    let verdict = run_conformance(
        &mut || Ok(Box::new(Broken(CpuBackend::new(), fault))),
        &ConformanceOptions::quick(),
        Tier::Dynamic,
    );
    figure!("{verdict}");
    assert!(!verdict.check(moves).unwrap().passed, "{verdict}");
    let kinds = verdict.check(kinds).unwrap();
    assert!(
        !kinds.passed && kinds.detail.contains(&format!("({step})")),
        "{verdict}"
    );
    for still in ["agreement/same-seed", "gather-formulas", "determinism"] {
        assert!(verdict.check(still).unwrap().passed, "{still}: {verdict}");
    }
}

/// A backend that skips the reset of an emptied slot's normaliser (no still pass empties a
/// slot) fails at the first kind that empties slots.
fn conformance_fails_a_backend_that_skips_the_reset_of_an_emptied_slot_on_moves() {
    let checks = ("moves/same-seed", "gather-kinds", "thesis compensation");
    fails_on_moves_only(Fault::SkipsEmptiedReset, checks);
}

/// A backend that ignores [`photon_flags::ADD_TO_MAP`] fails where local mode's deferred
/// correction is applied.
fn conformance_fails_a_backend_that_ignores_add_to_map() {
    let checks = (
        "moves/local/same-seed",
        "correction-kinds",
        "local correction, both poses",
    );
    fails_on_moves_only(Fault::IgnoresAddToMap, checks);
}

/// A backend that ignores [`photon_flags::PAIR_DEPOSITS`] fails where local mode's correction
/// is applied: its variance, and so the history a kept slot keeps, is not the contract's.
fn conformance_fails_a_backend_that_ignores_pairing() {
    let checks = (
        "moves/local/same-seed",
        "correction-kinds",
        "local correction, both poses",
    );
    fails_on_moves_only(Fault::IgnoresPairing, checks);
}

/// A backend whose local move skips one of its passes over the slots fails the check that
/// names that pass, and `moves/local/same-seed` where that pass is an object move's; the
/// other passes' checks pass it.
fn conformance_fails_a_backend_that_skips_a_local_move_pass() {
    for (fault, fails, passes) in [
        (
            Fault::ResetsNothing,
            &["local-resets", "moves/local/same-seed"][..],
            None,
        ),
        (
            Fault::SkipsDirectChange,
            &["local-direct-change", "moves/local/same-seed"],
            Some("local-resets"),
        ),
        (
            Fault::InheritsNothing,
            &["camera-move"],
            Some("moves/local/same-seed"),
        ),
    ] {
        let verdict = run_conformance(
            &mut || Ok(Box::new(Broken(CpuBackend::new(), fault))),
            &ConformanceOptions::quick(),
            Tier::Local,
        );
        figure!("{verdict}");
        for &fails in fails {
            assert!(!verdict.check(fails).unwrap().passed, "{fails}: {verdict}");
        }
        if let Some(passes) = passes {
            assert!(verdict.check(passes).unwrap().passed, "{passes}: {verdict}");
        }
    }
}

/// A backend without local-move or dynamic passes passes the static tier, fails the others on
/// `local-passes` and `dynamic-passes`, and renders a moving scene: each of its moves
/// restarts, saying why.
fn a_still_frame_backend_passes_the_static_tier_and_restarts_at_moves() {
    let make = &mut || -> Result<Box<dyn Backend>, BackendError> {
        Ok(Box::new(Broken(CpuBackend::new(), Fault::StillFramesOnly)))
    };
    let options = ConformanceOptions::quick();
    let still = run_conformance(make, &options, Tier::Static);
    figure!("{still}");
    assert!(still.passed(), "{still}");
    assert!(
        still.check("moves/same-seed").is_none(),
        "static runs no moves check"
    );
    let moving = run_conformance(make, &options, Tier::Dynamic);
    let local = moving.check("local-passes").unwrap();
    assert!(!local.passed && local.detail.contains("still frames only"));
    assert!(!moving.check("dynamic-passes").unwrap().passed);
    let kinds = moving.check("gather-kinds").unwrap();
    assert!(
        !kinds.passed && kinds.detail.contains("ordinary photons only"),
        "{moving}"
    );
    assert!(!moving.check("moves/same-seed").unwrap().passed);

    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height, params.photons_per_pass) = (32, 32, 2_000);
    let mut backend = Broken(CpuBackend::new(), Fault::StillFramesOnly);
    let mut render = harness::driver::Renderer::start(
        &mut backend,
        scene.at_time(0.0),
        &params,
        &MoveParams::default(),
    )
    .unwrap();
    render.iteration().unwrap();
    let report = render.move_to(scene.at_time(1.0), MoveMode::Local).unwrap();
    let why = report
        .restarted
        .expect("a move on a still-frame backend restarts");
    assert!(why.contains("still frames only"), "{why}");
    render.iteration().unwrap();
    assert!(
        render
            .resolve()
            .unwrap()
            .pixels
            .iter()
            .any(|p| p.iter().any(|c| *c > 0.0))
    );
}

/// A gather that goes wrong for one kind alone fails the gather checks naming that kind: every
/// kind, in turn (the ordinary one fails the static `gather-formulas`, local mode's the local
/// `correction-kinds`, the others the dynamic `gather-kinds`).
fn the_gather_checks_name_the_one_kind_a_backend_gets_wrong() {
    use gather_kind::*;
    let check = |name: &str| {
        harness::conformance::CHECKS
            .iter()
            .find(|c| c.0 == name)
            .expect("a named check")
            .2
    };
    let kinds = [
        ORDINARY,
        GUIDED,
        REGION_NEGATIVE | RAW_COUNT,
        REGION_POSITIVE | RAW_COUNT,
        REGION_NEGATIVE | DEFERRED,
        REGION_POSITIVE | DEFERRED,
        REGION_APPLY,
        REGION_POSITIVE | DEFERRED | ADD_FLUX,
        REGION_APPLY | ADD_FLUX,
    ];
    for kind in kinds {
        let make = &mut || -> Result<Box<dyn Backend>, BackendError> {
            Ok(Box::new(Broken(CpuBackend::new(), Fault::SkewsKind(kind))))
        };
        let name = match kind {
            ORDINARY => "gather-formulas",
            k if k & ADD_FLUX != 0 => "correction-kinds",
            _ => "gather-kinds",
        };
        let failed = check(name)(make, &ConformanceOptions::quick()).unwrap_err();
        figure!("{kind:#x}: {failed}");
        assert!(
            failed.contains(&format!("kind {kind:#x} (")),
            "{kind:#x}: {failed}"
        );
    }
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "every_backend_passes_conformance",
            every_backend_passes_conformance,
        )
        .test(
            "same_seed_mode_catches_a_gather_that_drops_one_photon_in_ten",
            same_seed_mode_catches_a_gather_that_drops_one_photon_in_ten,
        )
        .test(
            "the_state_before_the_first_divergence_replays_it_alone",
            the_state_before_the_first_divergence_replays_it_alone,
        )
        .test(
            "independent_mode_catches_a_gather_that_drops_one_photon_in_ten",
            independent_mode_catches_a_gather_that_drops_one_photon_in_ten,
        )
        .test(
            "conformance_fails_the_broken_backend_on_both_agreement_checks",
            conformance_fails_the_broken_backend_on_both_agreement_checks,
        )
        .test(
            "conformance_fails_a_backend_that_mis_signs_compensation_photons_on_moves",
            conformance_fails_a_backend_that_mis_signs_compensation_photons_on_moves,
        )
        .test(
            "conformance_fails_a_backend_that_skips_the_reset_of_an_emptied_slot_on_moves",
            conformance_fails_a_backend_that_skips_the_reset_of_an_emptied_slot_on_moves,
        )
        .test(
            "conformance_fails_a_backend_that_ignores_add_to_map",
            conformance_fails_a_backend_that_ignores_add_to_map,
        )
        .test(
            "conformance_fails_a_backend_that_ignores_pairing",
            conformance_fails_a_backend_that_ignores_pairing,
        )
        .test(
            "conformance_fails_a_backend_that_skips_a_local_move_pass",
            conformance_fails_a_backend_that_skips_a_local_move_pass,
        )
        .test(
            "a_still_frame_backend_passes_the_static_tier_and_restarts_at_moves",
            a_still_frame_backend_passes_the_static_tier_and_restarts_at_moves,
        )
        .test(
            "the_gather_checks_name_the_one_kind_a_backend_gets_wrong",
            the_gather_checks_name_the_one_kind_a_backend_gets_wrong,
        )
        .run()
}
