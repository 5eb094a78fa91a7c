//! Settings of one render, with checks that name the offending option.

use crate::scene::{Scene, SceneError};
use serde::Serialize;

/// Where direct light comes from (ALGORITHM.md 1.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DirectMode {
    /// Shadow rays at each hit point; photons skip their first surface (the thesis).
    Explicit,
    /// Photons carry direct light too (classic PPM).
    Photons,
}

/// Everything a render needs besides the scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderParams {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Eye samples per pixel.
    pub spp: u32,
    /// Photon passes (the render may stop earlier on `time_budget`).
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
    /// Specular bounces an eye path may take.
    pub max_eye_depth: u32,
    /// Bounces a photon may take.
    pub max_photon_depth: u32,
    /// Source of direct light.
    pub direct: DirectMode,
    /// Shadow rays per hit point in explicit mode.
    pub direct_samples: u32,
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
            max_eye_depth: 64,
            max_photon_depth: 64,
            direct: DirectMode::Explicit,
            direct_samples: 16,
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
