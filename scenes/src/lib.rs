//! The built-in scenes: the canonical scenes of SCENES.md, shipped as scene files, and small
//! analytic scenes whose exact answer tests can check; and every file the project reads or
//! writes ([`file`](mod@file): scenes, paths, meshes, images).

#![warn(missing_docs)]

pub mod analytic;
pub mod canonical;
pub mod file;
pub mod material_scenes;
pub mod meshes;
pub mod stress;

use file::parse_scene;
use ppm_core::scene::{Scene, SceneError};
use std::path::Path;

/// A built-in scene.
pub struct BuiltinScene {
    /// Name on the command line.
    pub name: &'static str,
    /// One line on what it is for.
    pub description: &'static str,
    build: fn() -> Result<Scene, SceneError>,
}

impl BuiltinScene {
    /// Builds the scene (frame 0).
    pub fn load(&self) -> Result<Scene, SceneError> {
        (self.build)()
    }
}

/// The cornell-box scene file, as shipped.
pub const CORNELL_BOX_TOML: &str = include_str!("../data/cornell-box.toml");

/// The cornell-box scene as its shipped file describes it.
pub fn cornell_box_file() -> Result<Scene, SceneError> {
    parse_scene(
        CORNELL_BOX_TOML,
        "scenes/data/cornell-box.toml",
        Path::new("."),
    )
}

/// Every built-in scene, in the order `ppm scenes` lists them.
pub const BUILTIN: &[BuiltinScene] = &[
    BuiltinScene {
        name: "cornell-box",
        description: "SCENES.md 1: the measured Cornell box; frame 1 moves the tall block by (40, 0, -100)",
        build: cornell_box_file,
    },
    BuiltinScene {
        name: "cornell-bunny",
        description: "SCENES.md 2: the box with a 70,300-triangle procedural bunny stand-in, moved by (40, 0, -100)",
        build: canonical::cornell_bunny,
    },
    BuiltinScene {
        name: "wedding-band",
        description: "SCENES.md 3: three gold rings throwing caustics, 41,184 triangles; the middle ring moves by (0, 0, 8)",
        build: canonical::wedding_band,
    },
    BuiltinScene {
        name: "cornell-metal",
        description: "cornell-box with blocks of rough gold (GGX alpha 0.3) and nearly polished copper (alpha 0.05)",
        build: material_scenes::cornell_metal,
    },
    BuiltinScene {
        name: "cornell-glass",
        description: "cornell-box with blocks of rough glass (GGX alpha 0.1 and 0.4)",
        build: material_scenes::cornell_glass,
    },
    BuiltinScene {
        name: "cornell-coated",
        description: "cornell-box with blocks of plastic: red under a rough coat (GGX alpha 0.2), blue under a smooth one",
        build: material_scenes::cornell_coated,
    },
    BuiltinScene {
        name: "cornell-brushed",
        description: "cornell-box with anisotropic blocks: brushed gold (GGX alpha 0.4 along, 0.05 across) and frosted glass (0.05, 0.3)",
        build: material_scenes::cornell_brushed,
    },
    BuiltinScene {
        name: "cornell-textured",
        description: "cornell-box with a checkered floor and a back wall painted with coloured rings (image textures)",
        build: material_scenes::cornell_textured,
    },
    BuiltinScene {
        name: "furnace",
        description: "closed box whose walls all emit Le = 1 and reflect albedo 0.5: radiance is exactly 2 everywhere",
        build: || Ok(analytic::furnace(glam::Vec3::splat(0.5), 1.0)),
    },
    BuiltinScene {
        name: "specular-furnace",
        description: "the furnace with a lossless mirror wall and a glass cube: radiance is still exactly 2",
        build: || Ok(analytic::specular_furnace(glam::Vec3::splat(0.5), 1.0)),
    },
    BuiltinScene {
        name: "water-furnace",
        description: "the furnace half full of water (ior 1.8), seen from the air: radiance is still exactly 2, through the water too; frame 1 moves a block under water",
        build: || Ok(analytic::water_furnace(glam::Vec3::splat(0.5), 1.0, 1.8)),
    },
];

/// The built-in scene called `name`.
pub fn builtin(name: &str) -> Option<&'static BuiltinScene> {
    BUILTIN.iter().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scene_loads_and_has_a_light() {
        for s in BUILTIN {
            let scene = s.load().unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert!(scene.triangle_count() > 0, "{}", s.name);
        }
    }

    /// SCENES.md: 5 walls + 5 + 5 block quads + the light = 16 quads, 32 triangles; frame 1
    /// puts the tall block at x 305..512, z 147..356.
    #[test]
    fn cornell_box_matches_scenes_md() {
        let scene = cornell_box_file().unwrap();
        assert_eq!(scene.triangle_count(), 32);
        let tall = scene.object_index("tall-block").unwrap();
        let moved = scene.at_frame(1);
        let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
        for v in moved.objects[tall].triangles.iter().flatten() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        assert_eq!((lo.x, hi.x, lo.z, hi.z), (305.0, 512.0, 147.0, 356.0));
        assert_eq!(scene.at_frame(0), scene);
    }
}
