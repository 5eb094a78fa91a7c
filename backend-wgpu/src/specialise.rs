//! Which code a scene needs (docs/algorithm.md 6): the eye and photon pipelines are
//! specialised with override constants, so that a scene without mirrors, glass or conductors
//! runs no code that continues paths through them, one without glass no refraction, and ordinary photon passes carry no
//! mover-box tests. Each variant is compiled the first time a pass needs it.

use ppm_core::compile::SceneFeatures;

/// Variants of one pipeline: every combination of the three constants.
pub const VARIANTS: usize = 8;

/// The override constants a pass pipeline is built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Specialisation {
    /// The bounces through mirrors, glass and conductors (`SPECULAR` in eye_pass.wgsl and
    /// photon_pass.wgsl).
    pub specular: bool,
    /// The refraction half of the delta lobes (`GLASS` in bsdf.wgsl); only with
    /// `specular`.
    pub glass: bool,
    /// The photon pass's mover-box tests (`MOVERS`), which only local mode's correction
    /// passes use.
    pub movers: bool,
}

impl Specialisation {
    /// Everything compiled in: runs every scene and pass alike
    /// ([`crate::WgpuBackend::set_general`]).
    pub const GENERAL: Self = Self {
        specular: true,
        glass: true,
        movers: true,
    };

    /// Every variant, in [`Specialisation::index`] order.
    pub fn all() -> impl Iterator<Item = Self> {
        (0..VARIANTS).map(|i| Self {
            glass: i & 4 != 0,
            specular: i & 2 != 0,
            movers: i & 1 != 0,
        })
    }

    /// What a scene with `features` needs for passes that do (`movers`) or do not test the
    /// movers' boxes.
    pub fn for_scene(features: &SceneFeatures, movers: bool) -> Self {
        Self {
            specular: features.specular(),
            glass: features.glass,
            movers,
        }
    }

    /// The pipeline constants, as wgpu takes them.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let flag = |on: bool| f64::from(u8::from(on));
        vec![
            ("SPECULAR", flag(self.specular)),
            ("GLASS", flag(self.glass)),
            ("MOVERS", flag(self.movers)),
        ]
    }

    /// Index of this variant among the eight.
    pub fn index(&self) -> usize {
        usize::from(self.glass) * 4 + usize::from(self.specular) * 2 + usize::from(self.movers)
    }
}
