//! Settings of one render, with checks that name the offending option.

use crate::scene::{MAX_COORDINATE, Scene, SceneError, number};
use serde::{Deserialize, Serialize};

/// Which progressive estimator renders (docs/algorithm.md 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Estimator {
    /// Stochastic progressive photon mapping: a fresh jittered eye sample per pixel every
    /// iteration, statistics and direct light accumulated per slot. Consistent: converges to
    /// the pixel's true average, edges and direct light included.
    #[default]
    Sppm,
    /// The thesis's progressive photon mapping: hit points traced once per frame, direct
    /// light drawn once per frame. Converges to the radiance at its fixed sample points.
    Ppm,
}

impl Estimator {
    /// The name on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Estimator::Sppm => "sppm",
            Estimator::Ppm => "ppm",
        }
    }

    /// Shadow-ray samples per hit point by default: one per iteration (`sppm`, where they
    /// average over iterations), or sixteen once per frame (`ppm`).
    pub fn default_direct_samples(self) -> u32 {
        match self {
            Estimator::Sppm => 1,
            Estimator::Ppm => 16,
        }
    }
}

impl std::str::FromStr for Estimator {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "sppm" => Ok(Estimator::Sppm),
            "ppm" => Ok(Estimator::Ppm),
            _ => Err(format!("unknown estimator '{s}' (estimators: sppm, ppm)")),
        }
    }
}

/// Where direct light comes from (docs/algorithm.md 1.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DirectMode {
    /// Shadow rays at each hit point; photons skip their first surface (the thesis).
    Explicit,
    /// Photons carry direct light too (classic PPM).
    Photons,
}

/// The bounces an eye path or a photon takes at most (`RenderParams::max_eye_depth` and
/// `max_photon_depth` by default; the exports name it where other renderers differ).
pub const MAX_DEPTH: u32 = 64;

/// Everything a render needs besides the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderParams {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Eye samples per pixel.
    pub spp: u32,
    /// Iterations, each one photon pass (the render may stop earlier on `time_budget`).
    pub passes: u32,
    /// Photons per pass.
    pub photons_per_pass: u32,
    /// Wall-clock budget in seconds for the photon passes.
    pub time_budget: Option<f64>,
    /// Seed of the random generator.
    pub seed: u32,
    /// Fraction of new photons kept per pass.
    pub alpha: f32,
    /// Initial gather radius (not squared).
    pub initial_radius: f32,
    /// Bounces an eye path may take through mirrors, glass, metals and coats.
    pub max_eye_depth: u32,
    /// Bounces a photon may take.
    pub max_photon_depth: u32,
    /// Source of direct light.
    pub direct: DirectMode,
    /// Shadow-ray samples per hit point in explicit mode: per iteration (`sppm`) or per
    /// frame (`ppm`).
    pub direct_samples: u32,
    /// The progressive estimator.
    pub estimator: Estimator,
}

impl RenderParams {
    /// The scene's suggested settings at its own resolution.
    pub fn for_scene(scene: &Scene) -> Self {
        Self {
            width: scene.camera.width,
            height: scene.camera.height,
            spp: 1,
            passes: scene.render.passes,
            photons_per_pass: scene.render.photons_per_pass,
            time_budget: None,
            seed: 0,
            alpha: scene.render.alpha,
            initial_radius: scene.render.initial_radius,
            max_eye_depth: MAX_DEPTH,
            max_photon_depth: MAX_DEPTH,
            direct: DirectMode::Explicit,
            direct_samples: scene.render.estimator.default_direct_samples(),
            estimator: scene.render.estimator,
        }
    }

    /// Checks every setting; `source` names where they came from in the error (`command line`).
    pub fn validate(&self, source: &str) -> Result<(), SceneError> {
        let bad = |field: &str, value: &dyn std::fmt::Display, problem: &str| {
            Err(SceneError::invalid(source, field, value, problem))
        };
        if self.width == 0 {
            return bad("width", &self.width, "must be at least 1");
        }
        if self.height == 0 {
            return bad("height", &self.height, "must be at least 1");
        }
        if self.spp == 0 {
            return bad("spp", &self.spp, "must be at least 1");
        }
        let slots = u64::from(self.width) * u64::from(self.height) * u64::from(self.spp);
        if slots > u64::from(u32::MAX) {
            return bad(
                "width * height * spp",
                &slots,
                "exceeds 2^32 hit-point slots",
            );
        }
        if self.passes == 0 {
            return bad("passes", &self.passes, "must be at least 1");
        }
        if self.photons_per_pass == 0 {
            return bad(
                "photons_per_pass",
                &self.photons_per_pass,
                "must be at least 1",
            );
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return bad("alpha", &self.alpha, "must lie strictly between 0 and 1");
        }
        if !(self.initial_radius.is_finite() && self.initial_radius > 0.0) {
            return bad("radius", &self.initial_radius, "must be a positive number");
        }
        if self.initial_radius * self.initial_radius == 0.0 {
            return bad("radius", &self.initial_radius, "its square underflows f32");
        }
        if self.initial_radius > MAX_COORDINATE {
            return bad(
                "radius",
                &number(self.initial_radius),
                &format!("above {MAX_COORDINATE:e}: its square overflows f32"),
            );
        }
        if let Some(t) = self.time_budget
            && !(t.is_finite() && t > 0.0)
        {
            return bad("time_budget", &t, "must be a positive number of seconds");
        }
        if self.direct == DirectMode::Explicit && self.direct_samples == 0 {
            return bad(
                "direct_samples",
                &self.direct_samples,
                "must be at least 1 with explicit direct light",
            );
        }
        Ok(())
    }

    /// Number of hit-point slots.
    pub fn slots(&self) -> usize {
        self.width as usize * self.height as usize * self.spp as usize
    }
}

/// How a render follows a move (docs/algorithm.md 2, 3 and 3b): one row per mode, for every
/// command, report and test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MoveMode {
    /// Start over from scratch on the new pose.
    Restart,
    /// The thesis: point light at the lights' centre, raw `M`, unweighted guided photons.
    Thesis,
    /// Every light point, `M` in ordinary-photon units, defensively weighted guides.
    Area,
    /// Area mode's guides, but the compensation traces ordinary photons in both poses with
    /// the same random numbers, so every path the move changed is removed and re-added, not
    /// only those whose first segment crosses the emitting rectangle.
    Difference,
    /// Ours (`sppm` only): resets only the slots whose eye paths crossed a mover's box,
    /// keeps the direct light of the rest unless their rays crossed one, and corrects their
    /// indirect light with difference passes (`harness::driver` module `local`).
    Local,
}

impl MoveMode {
    /// Every mode, in report order.
    pub const ALL: [MoveMode; 5] = [
        MoveMode::Restart,
        MoveMode::Thesis,
        MoveMode::Area,
        MoveMode::Difference,
        MoveMode::Local,
    ];

    /// The mode's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            MoveMode::Restart => "restart",
            MoveMode::Thesis => "thesis",
            MoveMode::Area => "area",
            MoveMode::Difference => "difference",
            MoveMode::Local => "local",
        }
    }
}

impl std::str::FromStr for MoveMode {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        MoveMode::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = MoveMode::ALL.iter().map(|m| m.name()).collect();
                format!("unknown mode '{s}' (modes: {})", names.join(", "))
            })
    }
}

/// Settings of the passes that follow a move.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MoveParams {
    /// Compensation passes (and as many positive region passes) per move (thesis and area).
    pub compensation_passes: u32,
    /// Photons per compensation or region pass (the thesis: 256 x 256).
    pub region_photons: u32,
    /// Half-angle of the guided photons' jitter cone, degrees (the thesis: within 10).
    pub cone_deg: f32,
    /// Probability of an ordinary direction in the defensive mixture.
    pub beta: f32,
    /// Recorded paths kept for guiding (a stride subsample beyond this).
    pub max_recorded: usize,
    /// Distance beyond which a hit point counts as moved, relative to the scene's extent.
    pub update_epsilon: f32,
    /// Difference passes per move in difference mode (each one negative and one positive
    /// ordinary pass).
    pub difference_passes: u32,
    /// Local mode's correction photons per pose at most, in ordinary passes' worth; a move
    /// uses fewer after a short history, down to one pass ([`MoveParams::correction_for`]).
    /// They are traced as one pass per pose, gathered once.
    pub correction_passes: u32,
    /// Local mode gathers a one-pass correction within at least this many initial radii (0:
    /// each slot's own radius), a larger one within less ([`MoveParams::correction_for`]).
    pub correction_radii: f32,
    /// Local mode: skip in pose B the difference paths that crossed no mover's box in pose A,
    /// which would store nothing; off only to check that culling changes no statistic.
    pub cull_uncrossed: bool,
    /// Local mode: count each correction path's net deposit in the correction's variance
    /// ([`crate::update::pairing`]); off only to measure what that buys.
    pub pair_deposits: bool,
}

/// Iterations of history one pass of a local move's correction is worth
/// ([`MoveParams::correction_for`]).
pub const ITERATIONS_PER_CORRECTION_PASS: u32 = 64;

/// Iterations since the last move that pay for one pass of a move's correction
/// ([`MoveParams::correction_for`], docs/algorithm.md 3b): a pass's worth, traced in both
/// poses and gathered, costs about an iteration, so a correction costs at most about a
/// quarter of the rendering since the move before. Moves a second apart then get a
/// correction as full as a first move's; half as many passes left them further from the
/// truth after the last one.
pub const ITERATIONS_PAYING_A_CORRECTION_PASS: u32 = 4;

impl MoveParams {
    /// Local mode's correction for a move after `history` iterations of rendering (what
    /// the slots it keeps may hold), `since_move` of them since the last move: ordinary
    /// passes' worth of photons per pose (0: none), and the disc, in initial radii, they
    /// are gathered within at least.
    ///
    /// A kept slot weighs its history against the correction's noise
    /// ([`crate::update::history_kept`]), so a long history is worth a large correction:
    /// one pass per [`ITERATIONS_PER_CORRECTION_PASS`] iterations of it. What the moves may
    /// spend is what the time between them pays for: one pass per
    /// [`ITERATIONS_PAYING_A_CORRECTION_PASS`] since the last move, so that a drag, which
    /// moves at every iteration, corrects with one small and quick pass (a quarter or half
    /// of one leaves the image right after the drag further from the truth), and moves a
    /// second apart after a long history with several. At least one, at most
    /// `correction_passes`. The disc narrows as `passes^(-1/6)`, a density estimate's
    /// bandwidth rule in two dimensions, trading the correction's noise for its blur of the
    /// change (docs/algorithm.md 3b).
    pub fn correction_for(&self, history: u32, since_move: u32) -> (f32, f32) {
        if self.correction_passes == 0 {
            return (0.0, self.correction_radii);
        }
        let worth = history as f32 / ITERATIONS_PER_CORRECTION_PASS as f32;
        let affordable = since_move as f32 / ITERATIONS_PAYING_A_CORRECTION_PASS as f32;
        let share = worth
            .min(affordable)
            .clamp(1.0, self.correction_passes as f32);
        (share, self.correction_radii * share.powf(-1.0 / 6.0))
    }

    /// Checks every setting; `source` names where they came from in the error.
    pub fn validate(&self, source: &str) -> Result<(), SceneError> {
        let bad = |field: &str, value: &dyn std::fmt::Display, problem: &str| {
            Err(SceneError::invalid(source, field, value, problem))
        };
        if self.region_photons == 0 {
            return bad("region_photons", &self.region_photons, "must be at least 1");
        }
        // The guided photons' solid angle is `2 pi (1 - cos cone)`: zero at 0 degrees.
        if !(self.cone_deg > 0.0 && self.cone_deg <= 180.0) {
            return bad("cone_deg", &self.cone_deg, "must lie in (0, 180] degrees");
        }
        if !(0.0..=1.0).contains(&self.beta) {
            return bad("beta", &self.beta, "must lie in [0, 1]");
        }
        if !(self.correction_radii.is_finite() && (0.0..=1e3).contains(&self.correction_radii)) {
            return bad(
                "correction_radii",
                &self.correction_radii,
                "must lie in [0, 1000] initial radii",
            );
        }
        if !(self.update_epsilon.is_finite() && self.update_epsilon > 0.0) {
            return bad(
                "update_epsilon",
                &self.update_epsilon,
                "must be a positive number",
            );
        }
        Ok(())
    }
}

impl Default for MoveParams {
    fn default() -> Self {
        Self {
            compensation_passes: 4,
            region_photons: 256 * 256,
            cone_deg: 10.0,
            beta: 0.25,
            max_recorded: 1024,
            update_epsilon: 1e-4,
            difference_passes: 8,
            correction_passes: 8,
            correction_radii: 3.0,
            cull_uncrossed: true,
            pair_deposits: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_local_correction_grows_with_the_history_it_keeps_within_its_bounds() {
        let moves = MoveParams::default();
        let most = moves.correction_passes as f32;
        // A first move: all of the history came since the last move.
        let mut last = (0.0, f32::INFINITY);
        for history in [0, 1, 16, 17, 64, 65, 200, 500, 10_000] {
            let (passes, radii) = moves.correction_for(history, history);
            assert!((1.0..=most).contains(&passes), "{history}");
            assert!(
                passes >= last.0 && radii <= last.1,
                "{history}: {passes}, {radii}"
            );
            last = (passes, radii);
        }
        assert_eq!(moves.correction_for(64, 64).0, 1.0);
        assert_eq!(last.0, most);
        // Later moves spend what the time since the last one pays for.
        for history in [1, 64, 500, 10_000] {
            assert_eq!(
                moves.correction_for(history, 1).0,
                1.0,
                "a drag step corrects with one pass, after {history} iterations"
            );
        }
        assert_eq!(moves.correction_for(1000, 16).0, 4.0, "half a second apart");
        assert_eq!(moves.correction_for(1000, 32).0, most, "a second apart");
        assert_eq!(moves.correction_for(128, 32).0, 2.0, "a short history");
        let none = MoveParams {
            correction_passes: 0,
            ..MoveParams::default()
        };
        assert_eq!(
            none.correction_for(500, 500).0,
            0.0,
            "no correction asked, none traced"
        );
    }
}
