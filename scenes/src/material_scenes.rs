//! A test scene per material beyond the canonical ones: the Cornell box with its blocks in
//! that material, which docs/materials.md measures against Mitsuba 3 rendering our export.

use glam::Vec3;
use ppm_core::scene::{Material, MaterialKind, Scene, SceneError};

/// Gold's complex index of refraction at the wavelengths of red, green and blue (650, 550
/// and 450 nm; Johnson and Christy 1972).
pub const GOLD: (Vec3, Vec3) = (
    Vec3::new(0.143, 0.374, 1.442),
    Vec3::new(3.983, 2.385, 1.603),
);

/// Copper's, at the same wavelengths and from the same source.
pub const COPPER: (Vec3, Vec3) = (
    Vec3::new(0.200, 0.924, 1.102),
    Vec3::new(3.912, 2.452, 2.142),
);

/// `cornell-metal`: cornell-box with a tall block of rough gold (GGX alpha 0.3) and a short
/// block of nearly polished copper (alpha 0.05); the rest, the light and the move as
/// cornell-box.
pub fn cornell_metal() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-metal".into();
    for (block, name, (eta, k), alpha) in [
        ("tall-block", "rough-gold", GOLD, 0.3),
        ("short-block", "copper", COPPER, 0.05),
    ] {
        let object = scene
            .object_index(block)
            .expect("cornell-box has both blocks");
        scene.materials.push(Material {
            name: name.into(),
            kind: MaterialKind::Conductor {
                eta,
                k,
                reflectance: Vec3::ONE,
                alpha,
            },
        });
        scene.objects[object].material = scene.materials.len() - 1;
    }
    Ok(scene)
}
