//! Which code a scene needs (docs/algorithm.md, "what is left out when"): the eye and photon
//! pipelines are specialised with override constants, so that a scene without mirrors or
//! glass runs no specular code, and ordinary photon passes carry no mover-box tests. Each
//! variant is compiled the first time a pass needs it.

use ppm_core::compile::SceneFeatures;

/// The override constants a pass pipeline is built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Specialisation {
    /// The specular bounce, Fresnel and refraction (`SPECULAR` in eye_pass.wgsl and
    /// photon_pass.wgsl).
    pub specular: bool,
    /// The photon pass's mover-box tests (`MOVERS`), which only local mode's correction
    /// passes use.
    pub movers: bool,
}

impl Specialisation {
    /// Everything compiled in: runs every scene and pass alike
    /// ([`crate::WgpuBackend::set_general`]).
    pub const GENERAL: Self = Self {
        specular: true,
        movers: true,
    };

    /// What a scene with `features` needs for passes that do (`movers`) or do not test the
    /// movers' boxes.
    pub fn for_scene(features: &SceneFeatures, movers: bool) -> Self {
        Self {
            specular: features.specular(),
            movers,
        }
    }

    /// The pipeline constants, as wgpu takes them.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("SPECULAR", f64::from(u8::from(self.specular))),
            ("MOVERS", f64::from(u8::from(self.movers))),
        ]
    }

    /// Index of this variant among the four.
    pub fn index(&self) -> usize {
        usize::from(self.specular) * 2 + usize::from(self.movers)
    }
}
